#include "cone/radiance_mips.h"

#include "core/error.h"

#include <nanovdb/util/GridBuilder.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

namespace vl {

namespace {

constexpr int kCoordLimit = 1 << 20;  // packed sort keys hold 21 bits per axis
constexpr size_t kSmallLevelVoxels = 8;

int floorHalf(int c) { return c >= 0 ? c / 2 : -((1 - c) / 2); }

uint64_t packCoord(const ivec3& c) {
    const auto axis = [](int v) { return static_cast<uint64_t>(v + kCoordLimit); };
    return (axis(c.x) << 42) | (axis(c.y) << 21) | axis(c.z);
}

std::string voxelName(const VoxelScene& voxels, size_t i) {
    const ivec3& c = voxels.coords[i];
    return "voxel " + std::to_string(i) + " (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ", " +
           std::to_string(c.z) + ")";
}

void checkInputs(const VoxelScene& voxels, const std::vector<vec3>& radiance, const std::vector<FaceRadiance>* faces) {
    const std::string where = "buildRadianceMips(" + voxels.sourceScene + "): ";
    const size_t n = voxels.size();
    if (radiance.size() != n)
        throw Error(where + "radiance has " + std::to_string(radiance.size()) + " values for " +
                    std::to_string(n) + " voxels (run the lighting stage first)");
    if (voxels.opacity.size() != n || voxels.solid.size() != n)
        throw Error(where + "opacity or solid does not match the " + std::to_string(n) + " voxels");
    if (faces && (faces->size() != n || voxels.axisWeights.size() != n))
        throw Error(where + "face radiance or axis weights do not match the " + std::to_string(n) + " voxels");
    if (n > 0 && !(voxels.voxelSize > 0.0))
        throw Error(where + "voxel size " + std::to_string(voxels.voxelSize) + " is not positive");
    const auto valid = [](const vec3& r) { return isFinite(r) && !glm::any(glm::lessThan(r, vec3(0.0f))); };
    for (size_t i = 0; i < n; ++i) {
        const ivec3& c = voxels.coords[i];
        if (glm::any(glm::greaterThanEqual(glm::abs(c), ivec3(kCoordLimit))))
            throw Error(where + voxelName(voxels, i) + " lies beyond ±2^20 voxels");
        bool ok = valid(radiance[i]);
        if (faces)
            for (const vec3& r : (*faces)[i]) ok = ok && valid(r);
        if (!ok) throw InputError(where + "radiance of " + voxelName(voxels, i) + " is negative, NaN or Inf");
        const float a = voxels.opacity[i];
        if (!voxels.solid[i] && !(a >= 0.0f && a <= 1.0f))
            throw InputError(where + "opacity of " + voxelName(voxels, i) + " is outside [0, 1]");
    }
}

MipTexel makeTexel(const vec3& premultiplied, float alpha, float coverage) {
    MipTexel texel;
    texel.radiance = premultiplied;
    texel.alpha = alpha;
    texel.density = opticalDepth(alpha);
    texel.coverage = coverage;
    return texel;
}

// The face a cone travelling along `travel` sees: the one facing back at it.
constexpr int facingFace(int travel) { return travel ^ 1; }

// Level 0's values and texels from the voxels (level.coords are the voxels'). RadianceOnly:
// the texels' α, σ and coverage are already there (they follow the voxels, not the light),
// only the radiance is new.
template <bool RadianceOnly>
void lightLevelZero(MipLevel& level, const VoxelScene& voxels, const std::vector<vec3>& radiance,
                    const std::vector<FaceRadiance>* faces) {
    level.values.resize(voxels.size());
    level.texels.resize(voxels.size() * kFaceCount);
    tbb::parallel_for(size_t(0), voxels.size(), [&](size_t i) {
        const float alpha = voxels.solid[i] ? 1.0f : voxels.opacity[i];
        level.values[i] = vec4(alpha * radiance[i], alpha);
        MipTexel* texels = &level.texels[i * kFaceCount];
        // The six texels share the voxel's α, and so its density: one logarithm, not six.
        MipTexel shared;
        if (!RadianceOnly) shared = makeTexel(vec3(0.0f), alpha, alpha);
        if (!faces) {
            for (int travel = 0; travel < kFaceCount; ++travel) {
                if (!RadianceOnly) texels[travel] = shared;
                texels[travel].radiance = alpha * radiance[i];
            }
            return;
        }
        const AxisWeights& w = voxels.axisWeights[i];
        float largest = 0.0f;
        for (float weight : w) largest = std::max(largest, std::isfinite(weight) ? weight : 0.0f);
        for (int travel = 0; travel < kFaceCount; ++travel) {
            const int face = facingFace(travel);
            const float weight = w[size_t(face)];
            const float share = largest > 0.0f && weight > 0.0f && std::isfinite(weight) ? weight / largest : 0.0f;
            if (!RadianceOnly) {
                texels[travel] = shared;
                texels[travel].coverage = share * alpha;
            }
            texels[travel].radiance = share * alpha * (*faces)[i][size_t(face)];
        }
    });
}

MipLevel levelZero(const VoxelScene& voxels, const std::vector<vec3>& radiance, const std::vector<FaceRadiance>* faces) {
    MipLevel level;
    level.voxelSize = voxels.voxelSize;
    level.coords = voxels.coords;
    level.facesPerVoxel = kFaceCount;
    lightLevelZero<false>(level, voxels, radiance, faces);
    return level;
}

// Texel composite of front over back (α-premultiplied radiance, α and coverage alike).
MipTexel over(const MipTexel& front, const MipTexel& back) {
    MipTexel t;
    t.radiance = front.radiance + (1.0f - front.alpha) * back.radiance;
    t.alpha = front.alpha + (1.0f - front.alpha) * back.alpha;
    t.coverage = front.coverage + (1.0f - front.alpha) * back.coverage;
    return t;
}

// The texel for travel `face` of one column (du, dv) of a level-k voxel whose children are
// `slots`: its two children along the axis, front over back.
MipTexel columnTexel(const MipLevel& children, const std::array<int32_t, 8>& slots, int face, int du, int dv) {
    const int axis = face / 2;
    const bool towardsNegative = face % 2 == 1;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const auto childTexel = [&](int along) {
        ivec3 offset(0);
        offset[axis] = along;
        offset[u] = du;
        offset[v] = dv;
        const int slot = slots[size_t(offset.x + 2 * offset.y + 4 * offset.z)];
        if (slot < 0) return MipTexel{};
        return children.texels[size_t(slot) * size_t(children.facesPerVoxel) + size_t(face)];
    };
    // Travelling along +axis the lower child is met first.
    return over(childTexel(towardsNegative ? 1 : 0), childTexel(towardsNegative ? 0 : 1));
}

// Parent p of `parents` from its children (slot = child − 2·parent, x + 2y + 4z; −1 where
// absent); RadianceOnly as lightLevelZero.
//
// A travel texel averages the voxel's 4 columns along the axis. A surface that crosses the
// axis at a slant does not fall in one voxel per column: where it steps from this voxel into
// the one behind, some columns hold it here and the rest there, and compositing the two
// partly filled voxels as if independent lets through what no ray could pass (a plane split
// half and half passes 25 %, and a turned closed box gathers well under its radiance:
// docs/decisions.md, "Cone marching"). So a voxel that shows surface to the travel
// (coverage > 0) composites, in each column emptier than its fullest one, the same column of
// the voxel behind it along the travel (`behind`, one step of this level): a slanted wall is
// opaque from the first voxel that holds part of it, and each column shows what it meets. What this leaves alone: an empty voxel; a floor
// seen edge-on (it shows no surface to the travel, and covers the same columns in the next
// voxel anyway); a uniform medium (every column equally full: Beer–Lambert holds); an
// axis-aligned wall (it fills every column of its voxel).
template <bool RadianceOnly>
void makeParent(const MipLevel& children, const MipLevel& parents, size_t p, vec4& value, MipTexel* texels) {
    const std::array<int32_t, 8>& slots = parents.children[p];
    value = vec4(0.0f);
    for (int slot : slots)
        if (slot >= 0) value += children.values[size_t(slot)];
    value *= 0.125f;  // exact in binary floating point

    for (int face = 0; face < kFaceCount; ++face) {
        MipTexel columns[4];
        bool showsSurface = false;
        float fullest = 0.0f;
        for (int c = 0; c < 4; ++c) {
            columns[c] = columnTexel(children, slots, face, c & 1, c >> 1);
            showsSurface = showsSurface || columns[c].coverage > 0.0f;
            fullest = std::max(fullest, columns[c].alpha);
        }
        const int32_t behind = parents.behind[p][size_t(face)];
        if (showsSurface && behind >= 0)
            for (int c = 0; c < 4; ++c)
                if (columns[c].alpha < fullest)
                    columns[c] = over(columns[c], columnTexel(children, parents.children[size_t(behind)], face, c & 1, c >> 1));
        vec3 radiance(0.0f);
        float alpha = 0.0f, coverage = 0.0f;
        for (const MipTexel& column : columns) {
            radiance += column.radiance;
            alpha += column.alpha;
            coverage += column.coverage;
        }
        if (RadianceOnly)
            texels[face].radiance = 0.25f * radiance;
        else
            texels[face] = makeTexel(0.25f * radiance, 0.25f * alpha, 0.25f * coverage);
    }
}

// A parent level's values and texels from its children (parents.children set).
template <bool RadianceOnly>
void lightParents(MipLevel& parents, const MipLevel& children) {
    const size_t parentCount = parents.coords.size();
    parents.values.resize(parentCount);
    parents.texels.resize(parentCount * kFaceCount);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, parentCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t p = range.begin(); p != range.end(); ++p)
            makeParent<RadianceOnly>(children, parents, p, parents.values[p], &parents.texels[p * kFaceCount]);
    });
}

// Children are grouped by a sort of unique keys and each parent reads only its own
// children, so the result is the same bytes at any thread count.
MipLevel parentLevel(const MipLevel& children, double baseVoxelSize, int level) {
    const size_t n = children.coords.size();
    std::vector<std::pair<uint64_t, uint32_t>> keyed(n);
    for (size_t i = 0; i < n; ++i) {
        const ivec3& c = children.coords[i];
        keyed[i] = {packCoord(ivec3(floorHalf(c.x), floorHalf(c.y), floorHalf(c.z))), static_cast<uint32_t>(i)};
    }
    tbb::parallel_sort(keyed.begin(), keyed.end());
    std::vector<size_t> groupBegin;
    for (size_t i = 0; i < n; ++i)
        if (i == 0 || keyed[i].first != keyed[i - 1].first) groupBegin.push_back(i);
    groupBegin.push_back(n);
    const size_t parentCount = groupBegin.size() - 1;

    MipLevel parents;
    parents.voxelSize = children.voxelSize * 2.0;
    parents.centreOffset = vec3(static_cast<float>((std::ldexp(1.0, level) - 1.0) * 0.5 * baseVoxelSize));
    parents.facesPerVoxel = kFaceCount;
    parents.coords.resize(parentCount);
    parents.children.resize(parentCount);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, parentCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t p = range.begin(); p != range.end(); ++p) {
            const ivec3 first = children.coords[keyed[groupBegin[p]].second];
            const ivec3 parent(floorHalf(first.x), floorHalf(first.y), floorHalf(first.z));
            std::array<int32_t, 8> slots = {-1, -1, -1, -1, -1, -1, -1, -1};
            for (size_t j = groupBegin[p]; j < groupBegin[p + 1]; ++j) {
                const ivec3 d = children.coords[keyed[j].second] - 2 * parent;
                slots[size_t(d.x + 2 * d.y + 4 * d.z)] = static_cast<int32_t>(keyed[j].second);
            }
            parents.coords[p] = parent;
            parents.children[p] = slots;
        }
    });
    // coords are in key order (the sort above), so a neighbour is a binary search away.
    std::vector<uint64_t> keys(parentCount);
    for (size_t p = 0; p < parentCount; ++p) keys[p] = packCoord(parents.coords[p]);
    parents.behind.resize(parentCount);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, parentCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t p = range.begin(); p != range.end(); ++p)
            for (int face = 0; face < kFaceCount; ++face) {
                ivec3 next = parents.coords[p];
                next[face / 2] += face % 2 == 1 ? -1 : 1;
                const uint64_t key = packCoord(next);
                const auto found = std::lower_bound(keys.begin(), keys.end(), key);
                parents.behind[p][size_t(face)] =
                    found != keys.end() && *found == key ? static_cast<int32_t>(found - keys.begin()) : -1;
            }
    });
    lightParents<false>(parents, children);
    return parents;
}

bool isSmallEnough(const MipLevel& level) {
    if (level.coords.size() <= kSmallLevelVoxels) return true;
    ivec3 lo = level.coords.front(), hi = level.coords.front();
    for (const ivec3& c : level.coords) {
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    return glm::all(glm::lessThanEqual(hi - lo, ivec3(1)));
}

nanovdb::GridHandle<nanovdb::HostBuffer> toIndexGrid(const MipLevel& level, int k) {
    nanovdb::GridBuilder<int32_t> builder(-1);
    builder.setStats(nanovdb::StatsMode::BBox);  // the index needs no value statistics
    auto accessor = builder.getAccessor();
    for (size_t i = 0; i < level.coords.size(); ++i) {
        const ivec3& c = level.coords[i];
        accessor.setValue(nanovdb::Coord(c.x, c.y, c.z), static_cast<int32_t>(i));
    }
    const vec3 o = level.centreOffset;
    return builder.getHandle<>(level.voxelSize, nanovdb::Vec3d(o.x, o.y, o.z), "mip_index" + std::to_string(k));
}

}  // namespace

const MipIndexGrid* RadianceMips::indexGrid(int k) const {
    return grids_.at(static_cast<size_t>(k)).grid<int32_t>();
}

MipView RadianceMips::view() const {
    MipView view;
    view.levelCount = levelCount();
    view.voxelSize = static_cast<float>(voxelSize_);
    view.boundsMin = boundsMin_;
    view.boundsMax = boundsMax_;
    for (int k = 0; k < view.levelCount; ++k) {
        view.levels[k].index = indexGrid(k);
        view.levels[k].texels = levels_[size_t(k)].texels.data();
        view.levels[k].facesPerVoxel = levels_[size_t(k)].facesPerVoxel;
        view.levels[k].voxelSize = static_cast<float>(levels_[size_t(k)].voxelSize);
        view.levels[k].inverseVoxelSize = static_cast<float>(1.0 / levels_[size_t(k)].voxelSize);
        view.levels[k].centreOffset = static_cast<float>(0.5 - std::ldexp(0.5, -k));
    }
    return view;
}

void RadianceMips::relight(const VoxelScene& voxels, const std::vector<vec3>& radiance,
                           const std::vector<FaceRadiance>& faceRadiance) {
    checkInputs(voxels, radiance, &faceRadiance);
    if (levels_.empty() || levels_[0].coords.size() != voxels.size())
        throw Error("RadianceMips::relight(" + voxels.sourceScene + "): the mips were built for " +
                    std::to_string(levels_.empty() ? 0 : levels_[0].coords.size()) + " voxels, not " +
                    std::to_string(voxels.size()));
    lightLevelZero<true>(levels_[0], voxels, radiance, &faceRadiance);
    for (size_t k = 1; k < levels_.size(); ++k) lightParents<true>(levels_[k], levels_[k - 1]);
}

size_t RadianceMips::memoryBytes() const {
    size_t bytes = 0;
    for (const auto& handle : grids_) bytes += handle.size();
    for (const MipLevel& level : levels_)
        bytes += level.coords.size() * sizeof(ivec3) + level.values.size() * sizeof(vec4) +
                 level.texels.size() * sizeof(MipTexel) + level.children.size() * sizeof(level.children[0]) +
                 level.behind.size() * sizeof(level.behind[0]);
    return bytes;
}

// The one builder behind the overloads (a friend of RadianceMips); faces null: isotropic.
// Level 0 only when `parents` is false.
RadianceMips buildMips(const VoxelScene& voxels, const std::vector<vec3>& radiance, const std::vector<FaceRadiance>* faces,
                       bool parents);

RadianceMips buildRadianceMips(const VoxelScene& voxels) {
    if (voxels.faceRadiance.empty()) return buildMips(voxels, voxels.radiance, nullptr, true);
    return buildMips(voxels, voxels.radiance, &voxels.faceRadiance, true);
}

RadianceMips buildRadianceMips(const VoxelScene& voxels, const std::vector<vec3>& radiance) {
    return buildMips(voxels, radiance, nullptr, true);
}

RadianceMips buildRadianceMips(const VoxelScene& voxels, const std::vector<vec3>& radiance,
                               const std::vector<FaceRadiance>& faceRadiance) {
    return buildMips(voxels, radiance, &faceRadiance, true);
}

RadianceMips buildLevelZeroMips(const VoxelScene& voxels, const std::vector<vec3>& radiance,
                                const std::vector<FaceRadiance>& faceRadiance) {
    return buildMips(voxels, radiance, &faceRadiance, false);
}

RadianceMips buildRadianceMipsFor(const VoxelScene& voxels, MipReaders readers) {
    if (readers == MipReaders::RaysOnly && !voxels.faceRadiance.empty())
        return buildLevelZeroMips(voxels, voxels.radiance, voxels.faceRadiance);
    return buildRadianceMips(voxels);
}

void RadianceMips::addParentLevels() {
    if (levels_.empty()) return;
    while (!isSmallEnough(levels_.back()) && levelCount() < MipView::kMaxLevels) {
        const int k = levelCount();
        levels_.push_back(parentLevel(levels_.back(), voxelSize_, k));
    }
    addIndexGrids();
}

void RadianceMips::addIndexGrids() {
    // Each level's index grid is built on its own; level 0 holds about three quarters of all
    // voxels, so this hides the rest behind it.
    const int first = static_cast<int>(grids_.size());
    grids_.resize(size_t(levelCount()));
    tbb::parallel_for(first, levelCount(), [&](int k) { grids_[size_t(k)] = toIndexGrid(levels_[size_t(k)], k); });
}

RadianceMips buildMips(const VoxelScene& voxels, const std::vector<vec3>& radiance, const std::vector<FaceRadiance>* faces,
                       bool parents) {
    checkInputs(voxels, radiance, faces);
    RadianceMips mips;
    mips.voxelSize_ = voxels.voxelSize;
    mips.origin_ = voxels.origin;
    mips.frame_ = voxels.frame;
    if (voxels.size() == 0) return mips;

    ivec3 lo = voxels.coords.front(), hi = voxels.coords.front();
    for (const ivec3& c : voxels.coords) {
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    const float h = static_cast<float>(voxels.voxelSize);
    mips.boundsMin_ = (vec3(lo) - vec3(0.5f)) * h;
    mips.boundsMax_ = (vec3(hi) + vec3(0.5f)) * h;

    mips.levels_.push_back(levelZero(voxels, radiance, faces));
    if (parents)
        mips.addParentLevels();
    else
        mips.addIndexGrids();
    return mips;
}

std::vector<ExtraGrid> mipGridsForFile(const RadianceMips& mips) {
    std::vector<ExtraGrid> grids;
    for (int k = 0; k < mips.levelCount(); ++k) {
        const MipLevel& level = mips.level(k);
        ExtraGrid radiance, opacity;
        radiance.name = "radiance_mip" + std::to_string(k);
        opacity.name = "opacity_mip" + std::to_string(k);
        radiance.voxelSize = opacity.voxelSize = level.voxelSize;
        radiance.translation = opacity.translation = mips.origin() + mips.frame() * glm::dvec3(level.centreOffset);
        radiance.frame = opacity.frame = mips.frame();
        radiance.coords = opacity.coords = level.coords;
        radiance.vectors.reserve(level.values.size());
        opacity.scalars.reserve(level.values.size());
        for (const vec4& v : level.values) {
            radiance.vectors.emplace_back(v.x, v.y, v.z);
            opacity.scalars.push_back(v.w);
        }
        grids.push_back(std::move(radiance));
        grids.push_back(std::move(opacity));
    }
    return grids;
}

}  // namespace vl
