#include "bake/bright_patches.h"

#include "core/error.h"
#include "core/polygon_irradiance.h"
#include "trace/bvh_traverse.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

namespace vl {

namespace {

double meanOf(const vec3& v) { return (double(v.x) + double(v.y) + double(v.z)) / 3.0; }

struct PatchSum {
    glm::dvec3 power{0.0};
    double area = 0.0;
    glm::dvec3 normal{0.0};  // Σ area × unit normal of its voxel sides
    glm::dvec3 weightedPosition{0.0};
    double weight = 0.0;
    std::vector<std::pair<uint32_t, uint8_t>> faces;  // (voxel, face)
};


}  // namespace

BrightPatchSplit splitBrightPatches(const VoxelScene& voxels, const BrightPatchSettings& settings) {
    BrightPatchSplit split;
    split.restFaces = voxels.faceRadiance;
    split.restRadiance = voxels.radiance;
    const size_t n = voxels.size();
    if (!(settings.factor > 0.0f) || voxels.faceRadiance.size() != n || voxels.axisWeights.size() != n || n == 0)
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
    // threads. A voxel side's bright faces join the patch of its cell and of the signed axis its
    // normal is closest to. The side's area is |Σ w_f·d_f| (its faces' weights are the area's
    // projections on the axes), and it sends L·area: summing L·w_f over its faces instead
    // counted a slanted side ‖n‖₁ times over (up to √3), and a patch placed square to an axis
    // lit receivers the side faces away from (a point light's hot spot on a turned ceiling put
    // 4–8% too much indirect light on the Cycles point box's walls).
    const int cell = std::max(1, settings.cellVoxels);
    const auto cellOf = [cell](int a) { return a >= 0 ? a / cell : -((-a + cell - 1) / cell); };
    const double h = voxels.voxelSize;
    std::map<std::tuple<int, int, int, int>, PatchSum> cells;
    for (size_t i = 0; i < n; ++i) {
        const VoxelSides sides = voxelSides(voxels.normal[i], voxels.axisWeights[i].data());
        for (int side = 0; side < sides.count; ++side) {
            glm::dvec3 projected(0.0), radiance(0.0);
            double weight = 0.0;
            PatchSum* s = nullptr;
            for (int f = 0; f < 6; ++f) {
                const float w = voxels.axisWeights[i][size_t(f)];
                const vec3& L = voxels.faceRadiance[i][size_t(f)];
                if (sides.sideOfFace[f] != side || !(w > 0.0f) || !(meanOf(L) > threshold)) continue;
                if (!s) {
                    const ivec3 c = voxels.coords[i];
                    s = &cells[std::make_tuple(cellOf(c.x), cellOf(c.y), cellOf(c.z), dominantAxisFace(sides.normal[side]))];
                }
                projected += double(w) * glm::dvec3(faceDirection(f));
                radiance += double(w) * glm::dvec3(L);
                weight += w;
                s->faces.emplace_back(uint32_t(i), uint8_t(f));
            }
            if (!s) continue;
            const double A = glm::length(projected) * h * h;
            const glm::dvec3 L = radiance / weight;
            const glm::dvec3 surface =
                (glm::dvec3(voxels.coords[i]) + glm::dvec3(voxels.surfaceOffset.size() == n ? voxels.surfaceOffset[i] : vec3(0.0f))) * h;
            s->power += L * A;
            s->area += A;
            s->normal += projected * (h * h);
            s->weightedPosition += meanOf(vec3(L)) * A * surface;
            s->weight += meanOf(vec3(L)) * A;
        }
    }

    // The most powerful first (ties keep the cell order, so the choice does not depend on the
    // sort); the first maxPatches of them, back in cell order.
    struct Ranked {
        size_t order;  // in cell order
        int face;
        const PatchSum* sum;
    };
    std::vector<Ranked> ranked;
    for (const auto& [key, s] : cells) ranked.push_back({ranked.size(), std::get<3>(key), &s});
    std::stable_sort(ranked.begin(), ranked.end(),
                     [](const Ranked& a, const Ranked& b) { return meanOf(vec3(a.sum->power)) > meanOf(vec3(b.sum->power)); });
    ranked.resize(std::min(ranked.size(), size_t(std::max(0, settings.maxPatches))));
    std::sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) { return a.order < b.order; });

    for (const Ranked& r : ranked) {
        const PatchSum& s = *r.sum;
        BrightPatch patch;
        const double length = glm::length(s.normal);
        patch.normal = length > 0.0 ? vec3(s.normal / length) : faceDirection(r.face);
        patch.area = float(s.area);
        patch.radiance = vec3(s.power / s.area);
        patch.position = vec3(s.weightedPosition / s.weight);
        split.patches.push_back(patch);
        for (const auto& [voxel, face] : s.faces) split.restFaces[voxel][face] = vec3(0.0f);
        split.faces += s.faces.size();
    }
    for (size_t i = 0; i < n; ++i)
        split.restRadiance[i] = faceWeightedMean(split.restFaces[i].data(), voxels.axisWeights[i].data());
    return split;
}

void addBrightPatchIrradiance(const std::vector<GatherPoint>& points, const std::vector<vec3>& origins,
                              const std::vector<BrightPatch>& patches, const BvhView& bvh, float voxelSize,
                              std::vector<vec3>& irradiance) {
    if (patches.empty()) return;
    if (origins.size() != points.size() || irradiance.size() != points.size())
        throw Error("addBrightPatchIrradiance: " + std::to_string(origins.size()) + " origins and " +
                    std::to_string(irradiance.size()) + " irradiance values for " + std::to_string(points.size()) +
                    " gather points");
    // Each patch as a square of its area across its normal: Lambert's polygon formula is exact
    // for it at any distance, where L·A·cos·cos/r² overshoots near it. Its half edges u, v
    // follow the two axes after the normal's main one, laid into its plane (exactly those axes
    // for a patch square to an axis).
    std::vector<std::pair<vec3, vec3>> halfEdges(patches.size());
    for (size_t p = 0; p < patches.size(); ++p) {
        const vec3& m = patches[p].normal;
        const int axis = dominantAxisFace(m) >> 1;
        const vec3 e1 = faceDirection(2 * ((axis + 1) % 3)), e2 = faceDirection(2 * ((axis + 2) % 3));
        const vec3 uDir = glm::normalize(e1 - glm::dot(e1, m) * m);
        const vec3 vDir = glm::normalize(e2 - glm::dot(e2, m) * m - glm::dot(e2, uDir) * uDir);
        const float half = 0.5f * std::sqrt(patches[p].area);
        halfEdges[p] = {uDir * half, vDir * half};
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k != range.end(); ++k) {
            const GatherPoint& point = points[k];
            const vec3& origin = origins[k];
            vec3 E(0.0f);
            for (size_t p = 0; p < patches.size(); ++p) {
                const BrightPatch& patch = patches[p];
                const vec3 d = patch.position - origin;
                const float r2 = glm::dot(d, d);
                if (!(r2 > 0.0f)) continue;
                const float r = std::sqrt(r2);
                const vec3 w = d / r;
                const float cosPoint = glm::dot(point.normal, w), cosPatch = -glm::dot(patch.normal, w);
                if (!(cosPoint > 0.0f) || !(cosPatch > 0.0f)) continue;
                Ray ray;
                ray.origin = origin;
                ray.direction = w;
                ray.tMax = r - voxelSize;
                if (ray.tMax > 0.0f && intersectAny(bvh, ray)) continue;
                const auto& [u, v] = halfEdges[p];
                const vec3 first[3] = {d - u - v, d + u - v, d + u + v};
                const vec3 second[3] = {d - u - v, d + u + v, d - u + v};
                E += patch.radiance *
                     (clippedTriangleIrradiance(first, point.normal) + clippedTriangleIrradiance(second, point.normal));
            }
            irradiance[k] += E;
        }
    });
}

}  // namespace vl
