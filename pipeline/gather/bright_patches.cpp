#include "gather/bright_patches.h"

#include "core/error.h"
#include "core/rng.h"
#include "trace/bvh_traverse.h"
#include "trace/path_kernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace vl {

namespace {

double meanOf(const vec3& v) { return (double(v.x) + double(v.y) + double(v.z)) / 3.0; }

// Patches whose proposal table a gather point keeps on the stack (more take the heap).
constexpr int kMaxDrawnPatches = 1024;

}  // namespace

BrightPatchSplit splitBrightPatches(const VoxelScene& voxels, const VoxelSurfacePoints& points,
                                    const BrightPatchSettings& settings) {
    BrightPatchSplit split;
    split.restFaces = voxels.faceRadiance;
    split.restRadiance = voxels.radiance;
    const size_t n = voxels.size();
    if (!(settings.factor > 0.0f) || voxels.faceRadiance.size() != n || voxels.axisWeights.size() != n || n == 0 ||
        points.slotCount() != n * 6)
        return split;

    double sum = 0.0, area = 0.0;
    for (size_t i = 0; i < n; ++i)
        for (size_t f = 0; f < 6; ++f) {
            const float w = voxels.axisWeights[i][f];
            if (!(w > 0.0f)) continue;
            sum += w * meanOf(voxels.faceRadiance[i][f]);
            area += w;
        }
    if (!(sum > 0.0)) return split;
    const double threshold = settings.factor * sum / area;

    // Cells in (x, y, z, face class) order: std::map keeps the patches' order independent of
    // threads. A bright side joins the patch of its cell and of the signed axis its normal is
    // closest to, with all its faces and points.
    struct Gathered {
        std::vector<std::pair<uint32_t, uint8_t>> faces;  // (voxel, face)
        std::vector<std::pair<uint64_t, BrightPoint>> points;  // by SurfacePoint::id
        double power = 0.0;
    };
    const int cell = std::max(1, settings.cellVoxels);
    const auto cellOf = [cell](int a) { return a >= 0 ? a / cell : -((-a + cell - 1) / cell); };
    std::map<std::tuple<int, int, int, int>, Gathered> cells;
    for (size_t i = 0; i < n; ++i) {
        const VoxelSides sides = voxelSides(voxels.normal[i], voxels.axisWeights[i].data());
        for (int side = 0; side < sides.count; ++side) {
            int face = -1;
            bool bright = false;
            for (int f = 0; f < 6; ++f)
                if (sides.sideOfFace[f] == side && voxels.axisWeights[i][size_t(f)] > 0.0f) {
                    face = face < 0 ? f : face;
                    bright = bright || meanOf(voxels.faceRadiance[i][size_t(f)]) > threshold;
                }
            const uint32_t first = points.begin[i * 6 + size_t(side)], last = points.begin[i * 6 + size_t(side) + 1];
            if (!bright || first == last) continue;
            const ivec3 c = voxels.coords[i];
            Gathered& g = cells[std::make_tuple(cellOf(c.x), cellOf(c.y), cellOf(c.z), dominantAxisFace(sides.normal[side]))];
            for (int f = 0; f < 6; ++f)
                if (sides.sideOfFace[f] == side && voxels.axisWeights[i][size_t(f)] > 0.0f) g.faces.emplace_back(uint32_t(i), uint8_t(f));
            const vec3 L = voxels.faceRadiance[i][size_t(face)];
            for (uint32_t k = first; k < last; ++k) {
                const SurfacePoint& p = points.points[k];
                g.points.emplace_back(p.id, BrightPoint{p.position, p.geometricNormal, p.normal, L, p.area});
                g.power += meanOf(L) * double(p.area);
            }
        }
    }

    // The most powerful first (ties keep the cell order); the first maxPatches of them, in the
    // order of their points' ids, as their points are: an order the scene's placement does not
    // change (a quarter turn reorders the cells), so neither do the draws.
    std::vector<Gathered*> ranked;
    for (auto& entry : cells) {
        std::sort(entry.second.points.begin(), entry.second.points.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        ranked.push_back(&entry.second);
    }
    std::vector<size_t> order(ranked.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return ranked[a]->power > ranked[b]->power; });
    order.resize(std::min(order.size(), size_t(std::max(0, settings.maxPatches))));
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return ranked[a]->points.front().first < ranked[b]->points.front().first; });

    for (size_t k : order) {
        const Gathered& g = *ranked[k];
        BrightPatch patch;
        patch.firstPoint = uint32_t(split.points.size());
        patch.pointCount = uint32_t(g.points.size());
        glm::dvec3 centre(0.0), normal(0.0);
        double a = 0.0, cumulative = 0.0;
        for (const auto& [id, p] : g.points) {
            centre += double(p.area) * glm::dvec3(p.position);
            normal += double(p.area) * glm::dvec3(p.geometricNormal);
            a += p.area;
        }
        patch.position = vec3(centre / a);
        const double length = glm::length(normal);
        patch.normal = length > 1e-6 * a ? vec3(normal / length) : vec3(0.0f);
        patch.area = float(a);
        patch.radiance = vec3(float(g.power / a));
        for (const auto& [id, p] : g.points) {
            patch.radius = std::max(patch.radius, glm::length(p.position - patch.position));
            cumulative += meanOf(p.radiance) * double(p.area);
            split.points.push_back(p);
            split.pointCdf.push_back(float(cumulative / g.power));
        }
        split.pointCdf.back() = 1.0f;
        split.patches.push_back(patch);
        for (const auto& [voxel, face] : g.faces) split.restFaces[voxel][face] = vec3(0.0f);
        split.faces += g.faces.size();
    }
    for (size_t i = 0; i < n; ++i)
        split.restRadiance[i] = faceWeightedMean(split.restFaces[i].data(), voxels.axisWeights[i].data());
    return split;
}

vec3 brightPatchIrradiance(const BrightPatchSplit& split, const BvhView& bvh, const vec3& origin, const vec3& n,
                           int samples, uint64_t seed, float* variance) {
    if (variance) *variance = 0.0f;
    const size_t count = split.patches.size();
    if (count == 0 || samples <= 0) return vec3(0.0f);
    // The proposal: what each patch could send, as a disk of its area at its centre, its
    // cosines floored so a patch curving round toward the point keeps a chance. A patch wholly
    // behind the point's plane (its centre farther behind than its radius) sends nothing.
    float table[kMaxDrawnPatches];
    std::vector<float> larger(count > kMaxDrawnPatches ? count : 0);
    float* cdf = count > kMaxDrawnPatches ? larger.data() : table;
    float total = 0.0f;
    for (size_t p = 0; p < count; ++p) {
        const BrightPatch& patch = split.patches[p];
        const vec3 d = patch.position - origin;
        const float r2 = glm::dot(d, d);
        const float r = std::sqrt(r2);
        float q = 0.0f;
        if (glm::dot(n, d) > -patch.radius) {
            const vec3 w = r > 0.0f ? d / r : n;
            const float cosR = std::max(0.05f, glm::dot(n, w));
            const float cosE = glm::length(patch.normal) > 0.0f ? std::max(0.05f, -glm::dot(patch.normal, w)) : 0.5f;
            const float L = (patch.radiance.x + patch.radiance.y + patch.radiance.z) / 3.0f;
            q = L * patch.area * cosR * cosE / (r2 + patch.area / kPi + patch.radius * patch.radius);
        }
        total += q;
        cdf[p] = total;
    }
    if (!(total > 0.0f)) return vec3(0.0f);
    Pcg32 rng = Pcg32::forItem(seed, 0, 0x425249474854ull);  // "BRIGHT"
    const float jitter = rng.next1D();
    vec3 sum(0.0f);
    double squares = 0.0;
    for (int s = 0; s < samples; ++s) {
        // Stratified over the patches' table; the leftover places the draw within the patch.
        const float u = (float(s) + jitter) / float(samples) * total;
        size_t p = size_t(std::upper_bound(cdf, cdf + count, u) - cdf);
        if (p >= count) p = count - 1;
        const float low = p > 0 ? cdf[p - 1] : 0.0f;
        const float patchProbability = (cdf[p] - low) / total;
        if (!(patchProbability > 0.0f)) continue;
        const BrightPatch& patch = split.patches[p];
        const float* pc = split.pointCdf.data() + patch.firstPoint;
        const float v = rng.next1D();
        uint32_t k = uint32_t(std::upper_bound(pc, pc + patch.pointCount, v) - pc);
        if (k >= patch.pointCount) k = patch.pointCount - 1;
        const float pointProbability = pc[k] - (k > 0 ? pc[k - 1] : 0.0f);
        if (!(pointProbability > 0.0f)) continue;
        const BrightPoint& y = split.points[patch.firstPoint + k];
        const vec3 d = y.position - origin;
        const float d2 = glm::dot(d, d);
        if (!(d2 > 0.0f)) continue;
        const vec3 w = d / std::sqrt(d2);
        const float cosR = glm::dot(n, w), cosE = -glm::dot(y.normal, w);
        if (!(cosR > 0.0f) || !(cosE > 0.0f) || !(-glm::dot(y.geometricNormal, w) > 0.0f)) continue;
        if (occluded(bvh, origin, n, y.position, y.geometricNormal)) continue;
        const vec3 c = y.radiance * (cosR * cosE * y.area / (d2 + y.area / kPi) / (patchProbability * pointProbability));
        sum += c;
        const double l = (double(c.x) + double(c.y) + double(c.z)) / 3.0;
        squares += l * l;
    }
    if (variance) {
        const double mean = (double(sum.x) + double(sum.y) + double(sum.z)) / 3.0 / double(samples);
        *variance = float(std::max(0.0, squares / double(samples) - mean * mean) / double(samples));
    }
    return sum / float(samples);
}

void addBrightPatchIrradiance(const std::vector<GatherPoint>& points, const std::vector<vec3>& origins,
                              const BrightPatchSplit& split, const BvhView& bvh, int samples,
                              std::vector<vec3>& irradiance) {
    if (split.patches.empty()) return;
    if (origins.size() != points.size() || irradiance.size() != points.size())
        throw Error("addBrightPatchIrradiance: " + std::to_string(origins.size()) + " origins and " +
                    std::to_string(irradiance.size()) + " irradiance values for " + std::to_string(points.size()) +
                    " gather points");
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k != range.end(); ++k)
            irradiance[k] += brightPatchIrradiance(split, bvh, origins[k], points[k].normal, samples, k);
    });
}

}  // namespace vl
