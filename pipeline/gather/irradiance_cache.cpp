#include "gather/irradiance_cache.h"

#include "cone/cone_set.h"
#include "core/error.h"
#include "core/progress.h"
#include "gather/gather_scene.h"
#include "gather/shade_element.h"

#include <nanovdb/util/GridBuilder.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace vl {

namespace {

constexpr int kCoordLimit = 1 << 20;  // as radiance_mips.cpp: coordinates within ±2^20

// A voxel side, keyed by its cell and face class, then by its voxel's coordinate along the
// class's axis (`depth`); sorted by key, depth and voxel, so the points and their sums come
// out the same at any thread count.
struct Side {
    ivec3 cell;
    int faceClass;
    int depth;
    uint32_t voxel;
    vec3 normal;
    int side;  // its index among the voxel's sides (voxelSides)

    bool sameKey(const Side& o) const { return cell == o.cell && faceClass == o.faceClass; }
    bool sameCell(const Side& o) const { return cell == o.cell; }
    bool operator<(const Side& o) const {
        if (cell.x != o.cell.x) return cell.x < o.cell.x;
        if (cell.y != o.cell.y) return cell.y < o.cell.y;
        if (cell.z != o.cell.z) return cell.z < o.cell.z;
        if (faceClass != o.faceClass) return faceClass < o.faceClass;
        if (depth != o.depth) return depth < o.depth;
        return voxel < o.voxel;
    }
};

}  // namespace

void IrradianceCache::checkLevel(int level) {
    if (level < 0 || level > kMaxCacheLevel)
        throw SettingsError("gather level " + std::to_string(level) + " is outside 0.." + std::to_string(kMaxCacheLevel));
}

namespace {

// Where a layer's point sits: the mean centre of its voxels, or, with a probe, of those whose
// surface is open (IrradianceCache's constructor says why and how); and the mass it takes
// (irradiance_cache.h): √ of the share of the cell's cross-section those voxels cover, counted
// by their distinct columns across the layer's axis, so that a layer two voxels deep (a plane
// on a voxel boundary) or a slanted one counts each column once.
vec3 layerPosition(const VoxelScene& voxels, const Side* sides, size_t count, int level, const GatherScene* enclosed,
                   float& mass) {
    const int axis = sides[0].faceClass / 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
    const auto massOf = [&](auto&& take) {
        std::vector<uint64_t> columns;
        columns.reserve(count);
        for (size_t k = 0; k < count; ++k)
            if (take(k)) {
                const ivec3& c = voxels.coords[sides[k].voxel];
                columns.push_back(uint64_t(uint32_t(c[u])) << 32 | uint32_t(c[v]));
            }
        std::sort(columns.begin(), columns.end());
        const size_t distinct = size_t(std::unique(columns.begin(), columns.end()) - columns.begin());
        return std::sqrt(std::min(1.0f, float(distinct) / float(uint64_t(1) << (2 * level))));
    };
    const auto meanCentre = [&](auto&& take) {
        glm::dvec3 sum(0.0);
        size_t taken = 0;
        for (size_t k = 0; k < count; ++k)
            if (take(k)) {
                sum += glm::dvec3(voxels.centre(sides[k].voxel));
                ++taken;
            }
        return std::make_pair(vec3(sum / double(std::max<size_t>(taken, 1))), taken);
    };
    const vec3 all = meanCentre([](size_t) { return true; }).first;
    mass = massOf([](size_t) { return true; });
    if (!enclosed || level < 1) return all;
    const float h = static_cast<float>(voxels.voxelSize);
    const bool offsets = voxels.surfaceOffset.size() == voxels.size();
    const auto surfacePoint = [&](size_t k) {
        const uint32_t i = sides[k].voxel;
        return voxels.centre(i) + (offsets ? voxels.surfaceOffset[i] * h : vec3(0.0f));
    };
    // A side half a voxel off its surface is enclosed when most of its probe rays meet the
    // backs of surfaces, as a buried lightmap texel is.
    const auto isEnclosed = [&](const vec3& surface, const vec3& normal) {
        SurfaceSample side;
        side.position = surface + normal * (0.5f * h);
        side.normal = normal;
        return isBuried(enclosed->scene, enclosed->bvh, side);
    };
    // The quarters of the cell in the layer's plane, each probed at the mean of its surface
    // points facing the mean of its normals: nothing in it depends on the voxels' order, so a
    // quarter turn of the scene probes the same places.
    const auto quarter = [&](size_t k) {
        const ivec3& c = voxels.coords[sides[k].voxel];
        return ((c[u] >> (level - 1)) & 1) | (((c[v] >> (level - 1)) & 1) << 1);
    };
    int open = 0, closed = 0;
    for (int q = 0; q < 4; ++q) {
        glm::dvec3 surface(0.0), normal(0.0);
        size_t inQuarter = 0;
        for (size_t k = 0; k < count; ++k)
            if (quarter(k) == q) {
                surface += glm::dvec3(surfacePoint(k));
                normal += glm::dvec3(sides[k].normal);
                ++inQuarter;
            }
        if (inQuarter == 0 || !(glm::length(normal) > 0.0)) continue;
        (isEnclosed(vec3(surface / double(inQuarter)), vec3(glm::normalize(normal))) ? closed : open) += 1;
    }
    if (open == 0 || closed == 0) return all;
    std::vector<char> isOpen(count);
    for (size_t k = 0; k < count; ++k) isOpen[k] = !isEnclosed(surfacePoint(k), sides[k].normal);
    const auto [position, taken] = meanCentre([&](size_t k) { return isOpen[k] != 0; });
    if (taken == 0) return all;
    mass = massOf([&](size_t k) { return isOpen[k] != 0; });
    return position;
}

}  // namespace

IrradianceCache::IrradianceCache(const VoxelScene& voxels, int level, const GatherScene* enclosed)
    : level_(level), voxelSize_(voxels.voxelSize) {
    checkLevel(level);
    const size_t n = voxels.size();
    if (voxels.normal.size() != n || voxels.axisWeights.size() != n)
        throw Error("IrradianceCache(" + voxels.sourceScene + "): normals or axis weights do not match the " +
                    std::to_string(n) + " voxels");

    std::vector<Side> sides;
    sides.reserve(n * 2);
    for (size_t i = 0; i < n; ++i) {
        const ivec3& c = voxels.coords[i];
        if (glm::any(glm::greaterThanEqual(glm::abs(c), ivec3(kCoordLimit))))
            throw Error("IrradianceCache(" + voxels.sourceScene + "): voxel " + std::to_string(i) +
                        " lies beyond ±2^20 voxels");
        const VoxelSides s = voxelSides(voxels.normal[i], voxels.axisWeights[i].data());
        const ivec3 cell(cellOf(c.x, level), cellOf(c.y, level), cellOf(c.z, level));
        for (int k = 0; k < s.count; ++k) {
            const int faceClass = dominantAxisFace(s.normal[k]);
            sides.push_back({cell, faceClass, c[faceClass / 2], static_cast<uint32_t>(i), s.normal[k], k});
        }
    }
    tbb::parallel_sort(sides.begin(), sides.end());
    // Each voxel's surface plane, through the centroid of its pieces (surfaceOffset, in voxels).
    surfacePlanes_.resize(n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const vec3 normal = voxels.normal[i];
        const vec3 offset = voxels.surfaceOffset.size() == n ? voxels.surfaceOffset[i] : vec3(0.0f);
        const vec3 surface = voxels.centre(i) + offset * float(voxels.voxelSize);
        surfacePlanes_[i] = vec4(normal, glm::dot(normal, surface));
    });
    // The voxels' centre, for the points' frames (gatherFrame).
    ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
    for (const ivec3& c : voxels.coords) {
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    const vec3 centre = n > 0 ? (vec3(lo) + vec3(hi)) * (0.5f * float(voxels.voxelSize)) : vec3(0.0f);
    const float cellSize = float(std::ldexp(voxels.voxelSize, level));

    // One point per layer of a class's sides in a cell: sides whose depths leave a gap of a
    // voxel or more are different surfaces (a wall's two faces 0.15 m apart, 3 voxels, in one
    // cell: the −x point of both, averaged into the wall between them, lifted inside it and
    // seen by no receiver, left a window-lit room's walls without indirect light in every
    // cell's middle). A tilted surface steps one voxel at a time and stays one point.
    std::vector<size_t> layerBegin;
    for (size_t begin = 0; begin < sides.size();) {
        size_t end = begin + 1;
        while (end < sides.size() && sides[end].sameKey(sides[begin]) && sides[end].depth - sides[end - 1].depth <= 1)
            ++end;
        layerBegin.push_back(begin);
        begin = end;
    }
    layerBegin.push_back(sides.size());
    // Whether another surface crosses layer p's cell: a layer along another axis, or another
    // of its own class (a parallel surface a voxel or more away). Only such a surface can close
    // off part of the layer; a closed shape whose wall does not cross the cell holds all of it
    // or none, and the point stays at the mean. The layer of the same sheet's other side (the
    // opposite class, on the same axis) does not count.
    const auto crossed = [&](size_t p) {
        const Side& own = sides[layerBegin[p]];
        const auto other = [&](size_t r) {
            const Side& side = sides[layerBegin[r]];
            return side.faceClass / 2 != own.faceClass / 2 || side.faceClass == own.faceClass;
        };
        for (size_t r = p; r > 0 && sides[layerBegin[r - 1]].sameCell(own); --r)
            if (other(r - 1)) return true;
        for (size_t r = p + 1; r + 1 < layerBegin.size() && sides[layerBegin[r]].sameCell(own); ++r)
            if (other(r)) return true;
        return false;
    };
    points_.resize(layerBegin.size() - 1);
    sidePoints_.assign(n * 6, ~0u);
    tbb::parallel_for(size_t(0), points_.size(), [&](size_t p) {
        const size_t begin = layerBegin[p], count = layerBegin[p + 1] - begin;
        for (size_t k = begin; k < begin + count; ++k)
            sidePoints_[size_t(sides[k].voxel) * 6 + size_t(sides[k].side)] = static_cast<uint32_t>(p);
        glm::dvec3 normal(0.0);
        for (size_t k = begin; k < begin + count; ++k) normal += glm::dvec3(sides[k].normal);
        GatherPoint& point = points_[p];
        point.position = layerPosition(voxels, &sides[begin], count, level, crossed(p) ? enclosed : nullptr, point.mass);
        const double length = glm::length(normal);
        // Side normals of one class all lean the same way, so the sum is far from zero.
        point.normal = length > 0.0 ? vec3(normal / length) : sides[begin].normal;
        gatherFrame(point.position, point.normal, centre, cellSize, point.tangent, point.turn);
    });
    nanovdb::GridBuilder<int32_t> builder(-1);
    builder.setStats(nanovdb::StatsMode::BBox);  // the index needs no value statistics
    auto accessor = builder.getAccessor();
    for (size_t p = 0; p < points_.size(); ++p) {
        const size_t begin = layerBegin[p];
        const ivec3 cell = sides[begin].cell;
        if (begin == 0 || cell != sides[begin - 1].cell) {
            accessor.setValue(nanovdb::Coord(cell.x, cell.y, cell.z), static_cast<int32_t>(cellBegin_.size()));
            cellBegin_.push_back(static_cast<uint32_t>(p));
            cellCoords_.push_back(cell);
        }
    }
    cellBegin_.push_back(static_cast<uint32_t>(points_.size()));
    cells_ = builder.getHandle<>(1.0, nanovdb::Vec3d(0.0), "gather_cells");
    irradiance_.assign(points_.size(), vec3(0.0f));
}

void IrradianceCache::gather(const MipView& mips, const ConeSettings& settings, int turns, Progress* progress) {
    validateConeSettings(settings);
    if (turns < 1 || turns > kMaxGatherTurns)
        throw SettingsError("gather turns " + std::to_string(turns) + " is outside 1.." + std::to_string(kMaxGatherTurns));
    const ConeSet& set = coneSet(settings.coneCount);
    irradiance_.assign(points_.size(), vec3(0.0f));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points_.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t q = range.begin(); q != range.end(); ++q) irradiance_[q] = gatherAtPoint(mips, points_[q], set, settings, turns);
        if (progress) progress->advance(range.size());
    });
}

void IrradianceCache::link(const MipView& mips) {
    const float h = static_cast<float>(voxelSize_);
    const MipLevelView occupancy = mips.levelCount > 0 ? mips.levels[0] : MipLevelView{};
    std::vector<std::vector<uint32_t>> perPoint(points_.size());
    const CellIndexGrid* grid = points_.empty() ? nullptr : cellGrid();
    tbb::parallel_for(size_t(0), cellCoords_.size(), [&](size_t slot) {
        IndexLeafCache cells;
        const ivec3 cell = cellCoords_[slot];
        for (uint32_t q = cellBegin_[slot]; q < cellBegin_[slot + 1]; ++q) {
            const GatherPoint& from = points_[q];
            const vec3 lifted = liftOffSurface(from.position, from.normal, h);
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int32_t other = cells.value(*grid, nanovdb::Coord(cell.x + dx, cell.y + dy, cell.z + dz));
                        if (other < 0) continue;
                        for (uint32_t r = cellBegin_[size_t(other)]; r < cellBegin_[size_t(other) + 1]; ++r) {
                            const GatherPoint& to = points_[r];
                            if (!(glm::dot(from.normal, to.normal) > 0.0f)) continue;
                            if (r != q && !clearPath(occupancy, h, lifted, liftOffSurface(to.position, to.normal, h),
                                                     surfacePlanes_.data()))
                                continue;
                            perPoint[q].push_back(r);
                        }
                    }
        }
    });
    neighbourBegin_.assign(points_.size() + 1, 0);
    neighbours_.clear();
    for (size_t q = 0; q < points_.size(); ++q) {
        neighbours_.insert(neighbours_.end(), perPoint[q].begin(), perPoint[q].end());
        neighbourBegin_[q + 1] = static_cast<uint32_t>(neighbours_.size());
    }
}

void IrradianceCache::setIrradiance(std::vector<vec3> irradiance) {
    if (irradiance.size() != points_.size())
        throw Error("IrradianceCache: " + std::to_string(irradiance.size()) + " irradiance values for " +
                    std::to_string(points_.size()) + " gather points");
    irradiance_ = std::move(irradiance);
}

IrradianceCacheView IrradianceCache::view(const MipView& mips) const {
    IrradianceCacheView view;
    if (mips.levelCount > 0) view.occupancy = mips.levels[0];
    view.cells = points_.empty() ? nullptr : cellGrid();
    view.cellBegin = cellBegin_.data();
    view.points = points_.data();
    view.irradiance = irradiance_.data();
    view.neighbourBegin = neighbourBegin_.empty() ? nullptr : neighbourBegin_.data();
    view.neighbours = neighbours_.data();
    view.surfacePlanes = surfacePlanes_.empty() ? nullptr : surfacePlanes_.data();
    view.pointCount = static_cast<uint32_t>(points_.size());
    view.voxelSize = static_cast<float>(voxelSize_);
    view.level = level_;
    view.raysPerAxis = raysPerAxis_;
    return view;
}

size_t IrradianceCache::memoryBytes() const {
    return cells_.size() + cellBegin_.size() * sizeof(uint32_t) + points_.size() * (sizeof(GatherPoint) + sizeof(vec3)) +
           cellCoords_.size() * sizeof(ivec3) +
           (neighbourBegin_.size() + neighbours_.size() + sidePoints_.size()) * sizeof(uint32_t);
}

}  // namespace vl
