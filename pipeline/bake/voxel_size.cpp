#include "bake/voxel_size.h"

#include "bake/bake.h"
#include "core/text.h"
#include "gather/gather_visibility.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/math.h"
#include "core/ray.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "scene/own_frame.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/ray_offset.h"
#include "voxel/voxelize.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace vl {
namespace {

// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection §5.1.5:
// the closest point by the Voronoi region of p).
double squaredDistanceToTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    auto squared = [&](const glm::dvec3& q) { return glm::dot(p - q, p - q); };
    if (d1 <= 0.0 && d2 <= 0.0) return squared(a);
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return squared(b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return squared(a + ab * (d1 / (d1 - d3)));
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return squared(c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return squared(a + ac * (d2 / (d2 - d6)));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return squared(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    const double denominator = 1.0 / (va + vb + vc);
    return squared(a + ab * (vb * denominator) + ac * (vc * denominator));
}

struct TriangleRef {
    const Mesh* mesh;
    size_t triangle;
};

double distanceToNearestTriangle(const std::vector<TriangleRef>& triangles, const glm::dvec3& p) {
    const double nearestSquared = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, triangles.size(), 4096), std::numeric_limits<double>::infinity(),
        [&](const tbb::blocked_range<size_t>& range, double nearest) {
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const Mesh& mesh = *triangles[i].mesh;
                const uint32_t* index = &mesh.indices[3 * triangles[i].triangle];
                nearest = std::min(nearest, squaredDistanceToTriangle(p, glm::dvec3(mesh.positions[index[0]]),
                                                                      glm::dvec3(mesh.positions[index[1]]),
                                                                      glm::dvec3(mesh.positions[index[2]])));
            }
            return nearest;
        },
        [](double a, double b) { return std::min(a, b); });
    return std::sqrt(nearestSquared);
}

// The longest side of the scene's box in its own frame (scene/own_frame.h), or the
// axis-aligned box where that is no shorter. The bake turns the scene first, and this is then
// its box; a scene left at an angle (grid-frame=world, or a caller's own) gets the size its
// own frame would, not one from axis-aligned bounds up to √3 times its own size.
double ownFrameLongestSide(const Scene& scene, double axisAlignedLongest) {
    const glm::dmat3 axes = ownFrameAxes(scene);
    glm::dvec3 lower(std::numeric_limits<double>::infinity()), upper(-std::numeric_limits<double>::infinity());
    for (const Mesh& mesh : scene.meshes)
        for (const vec3& v : mesh.positions) {
            const glm::dvec3 q = glm::dvec3(v) * axes;  // (axesᵀ v): v along each own axis
            lower = glm::min(lower, q);
            upper = glm::max(upper, q);
        }
    const glm::dvec3 side = upper - lower;
    return std::min(axisAlignedLongest, std::max(side.x, std::max(side.y, side.z)));
}

}  // namespace

FreePaths surfaceFreePaths(const Scene& scene, int rays) {
    FreePaths out;
    const SceneTriangles triangles = gatherTriangles(scene);
    const size_t count = triangles.meshIndex.size();
    if (count == 0 || rays <= 0) return out;
    // Points uniform by area: each ray picks a triangle from the area CDF, then a point on it.
    std::vector<double> cdf(count);
    double area = 0.0;
    for (size_t t = 0; t < count; ++t) {
        const glm::dvec3 a(triangles.vertices[3 * t]), b(triangles.vertices[3 * t + 1]), c(triangles.vertices[3 * t + 2]);
        area += 0.5 * glm::length(glm::cross(b - a, c - a));
        cdf[t] = area;
    }
    if (!(area > 0.0)) return out;
    const Bvh bvh = Bvh::build(triangles);
    const BvhView view = bvh.view();
    std::vector<float> lengths(static_cast<size_t>(rays), -1.0f);  // −1: left the scene
    std::vector<uint8_t> backs(static_cast<size_t>(rays), 0);        // hit a single-sided back
    tbb::parallel_for(tbb::blocked_range<int>(0, rays, 256), [&](const tbb::blocked_range<int>& range) {
        for (int r = range.begin(); r != range.end(); ++r) {
            Pcg32 rng = Pcg32::forItem(uint64_t(r), 0, 0x66726565u);
            const double pick = (double(r) + double(rng.next1D())) / double(rays) * area;
            const size_t t = std::min(count - 1, size_t(std::lower_bound(cdf.begin(), cdf.end(), pick) - cdf.begin()));
            const vec3 a = triangles.vertices[3 * t], b = triangles.vertices[3 * t + 1], c = triangles.vertices[3 * t + 2];
            vec3 n = glm::cross(b - a, c - a);
            if (!(glm::length(n) > 0.0f)) continue;
            n = glm::normalize(n);
            vec2 u;
            rng.next2D(u.x, u.y);
            const vec2 barycentric = sampleUniformTriangle(u);
            vec2 w;
            rng.next2D(w.x, w.y);
            vec3 tangent, bitangent;
            orthonormalBasis(n, tangent, bitangent);
            const vec3 local = sampleCosineHemisphere(w);
            Ray ray;
            ray.origin = offsetRayOrigin(a + barycentric.x * (b - a) + barycentric.y * (c - a), n, view.extent);
            ray.direction = glm::normalize(local.x * tangent + local.y * bitangent + local.z * n);
            Hit hit;
            if (!intersectClosest(view, ray, hit)) continue;
            lengths[size_t(r)] = hit.t;
            const uint32_t h = hit.triangle;
            const vec3 ha = triangles.vertices[3 * h], hb = triangles.vertices[3 * h + 1], hc = triangles.vertices[3 * h + 2];
            backs[size_t(r)] = glm::dot(ray.direction, glm::cross(hb - ha, hc - ha)) > 0.0f &&
                               !scene.materialOf(scene.meshes[triangles.meshIndex[h]]).doubleSided;
        }
    });
    std::vector<float> hits;
    hits.reserve(lengths.size());
    double sum = 0.0;
    for (const float l : lengths)
        if (l >= 0.0f) {
            hits.push_back(l);
            sum += l;
        }
    out.rays = rays;
    out.hits = static_cast<int>(hits.size());
    for (const uint8_t back : backs) out.singleSidedBacks += back;
    if (hits.empty()) return out;
    out.mean = sum / double(hits.size());
    std::nth_element(hits.begin(), hits.begin() + hits.size() / 2, hits.end());
    out.median = hits[hits.size() / 2];
    return out;
}

namespace {

// The count nearest x of the form 2·cellVoxels·k − 1 (at least one such). Why: the bake
// centres the scene's box on a voxel corner (anchorToVoxelGrid), so with such a count along a
// side the two walls that bound it lie in the outermost voxels of whole gather cells, each
// cell's point standing for a full cell of wall. Other counts cut those cells into strips, and
// the lightmaps' error rises (docs/decisions.md, "A voxel size the scene needs").
int cellAlignedCount(double x, int cellVoxels) {
    const double period = 2.0 * cellVoxels;
    const double k = std::max(1.0, std::round((std::min(x, double(1 << 21)) + 1.0) / period));
    return static_cast<int>(k * period) - 1;
}

// The smallest odd count ≥ x, and the largest odd count ≤ x (at least 1).
int oddAtLeast(double x) {
    const double whole = std::ceil(std::min(x, double(1 << 21)));
    const int n = std::max(1, static_cast<int>(whole));
    return n % 2 == 1 ? n : n + 1;
}
int oddAtMost(double x) {
    const double whole = std::floor(std::min(x, double(1 << 21)));
    const int n = std::max(1, static_cast<int>(whole));
    return n % 2 == 1 ? n : std::max(1, n - 1);
}

}  // namespace

VoxelSizeChoice chooseVoxelSize(const Scene& scene, const BakeSettings& settings) {
    VoxelSizeChoice choice;
    const bool userSize = settings.voxel.voxelSize > 0.0 || settings.voxel.resolution > 0;
    VoxelSettings sizeRule = settings.voxel;
    if (!userSize) sizeRule.resolution = kSceneVoxels;
    // voxelSizeFor also checks the scene (finite positions, triangles) and the voxel count.
    const double sizeRuleVoxel = voxelSizeFor(scene, sizeRule);
    const vec3 extent = scene.bounds().extent();
    const double longest = std::max<double>(extent.x, std::max<double>(extent.y, extent.z));

    std::vector<TriangleRef> triangles;
    for (const Light& light : scene.lights) {
        if (light.type != LightType::Point && light.type != LightType::Spot) continue;
        if (triangles.empty())
            for (const Mesh& mesh : scene.meshes)
                for (size_t t = 0; t < mesh.triangleCount(); ++t) triangles.push_back({&mesh, t});
        choice.clearances.push_back({light.name, distanceToNearestTriangle(triangles, glm::dvec3(light.position))});
    }
    std::stable_sort(choice.clearances.begin(), choice.clearances.end(),
                     [](const LightClearance& a, const LightClearance& b) { return a.metres < b.metres; });

    if (userSize) {
        choice.voxelSize = sizeRuleVoxel;
        choice.setBy = settings.voxel.voxelSize > 0.0 ? "the voxel-size setting" : "the resolution setting";
    } else {
        const FreePaths& paths = choice.freePaths = surfaceFreePaths(scene);
        // Only a user's choice of cones is known here: auto decides on the gather points, which
        // the voxel size places (ray_gather.h chooseGatherVisibility).
        const bool byCones = settings.gather.visibility == GatherVisibility::Cones;
        // Counts along the scene's own longest side: the bake has turned the scene into its
        // own frame before it sizes it (scene/own_frame.h), so that side is along a grid axis;
        // a scene given here unturned is measured in its own frame all the same.
        const double ownLongest = ownFrameLongestSide(scene, longest);
        const bool turned = ownLongest < longest * (1.0 - 1e-4);
        const int cellVoxels = 1 << std::max(0, std::max(settings.gather.gatherLevel, settings.gather.bounceGatherLevel));
        int ownVoxels = 0;
        char text[320];
        if (!byCones && 2 * paths.hits >= paths.rays) {
            const double wanted = ownLongest / (paths.mean / kVoxelsPerFreePath);
            ownVoxels = cellAlignedCount(std::min(wanted, double(kMaxFreePathVoxels)), cellVoxels);
            if (wanted > kMaxFreePathVoxels)
                choice.warnings.push_back(scene.sourcePath + ": the free paths between its surfaces (mean " +
                                          lengthText(paths.mean) + ") ask for " + std::to_string(int(wanted)) +
                                          " voxels along its longest side; the bake takes " +
                                          std::to_string(ownVoxels) + " (give voxel-size for finer)");
            std::snprintf(text, sizeof text,
                          "the mean free path between its surfaces (%g voxels along %s, over the %.0f%% of %d rays that "
                          "hit; %d along its longest side, %s%s)",
                          kVoxelsPerFreePath, lengthText(paths.mean).c_str(), 100.0 * paths.hits / paths.rays,
                          paths.rays, ownVoxels, lengthText(ownLongest).c_str(), turned ? ", in its own frame" : "");
        } else {
            ownVoxels = cellAlignedCount(kSceneVoxels, cellVoxels);
            std::snprintf(text, sizeof text, "the scene's size (%d voxels along its longest side, %s%s; %s)", ownVoxels,
                          lengthText(ownLongest).c_str(), turned ? ", in its own frame" : "",
                          byCones ? "gather-visibility=cones, whose error does not fall with finer voxels"
                                  : "most rays from its surfaces leave it: an open scene");
        }
        choice.setBy = text;
        double voxelSize = ownLongest / ownVoxels;
        const int ruleVoxels = oddAtLeast(longest / voxelSize * (1.0 - 1e-9));  // along the axis-aligned box
        const int maxVoxels = kMaxRefinement * (ruleVoxels + 1) - 1;
        const LightClearance* nearest = choice.clearances.empty() ? nullptr : &choice.clearances.front();
        if (nearest && nearest->metres > 0.0 && nearest->metres < voxelSize) {
            voxelSize = longest / std::min(oddAtLeast(longest / nearest->metres), maxVoxels);
            choice.setBy = "light '" + nearest->light + "', " + lengthText(nearest->metres) +
                           " from the nearest surface (at least one voxel between them)";
        } else if (nearest && nearest->metres <= 0.0) {
            voxelSize = longest / maxVoxels;
            choice.setBy = "light '" + nearest->light + "', which lies on a surface";
        }
        // The finest voxel the memory holds: the estimate is ∝ 1/h² past its fixed part.
        const double fixedBytes = estimateBakeMemory(scene, settings, std::numeric_limits<double>::infinity());
        const double perInverseSquare = estimateBakeMemory(scene, settings, 1.0) - fixedBytes;
        const double spare = availableMemoryBytes() - fixedBytes;
        if (perInverseSquare > 0.0 && spare > 0.0) {
            const int fitting = oddAtMost(longest / std::sqrt(perInverseSquare / spare));
            if (longest / fitting > voxelSize) {
                voxelSize = longest / fitting;
                choice.setBy = "the memory available (" + std::to_string(static_cast<long long>(spare / 1048576.0)) +
                               " MiB past the receivers)";
            }
        }
        choice.voxelSize = voxelSize;
    }
    choice.voxelsAlongLongest = static_cast<int>(std::lround(longest / choice.voxelSize));

    for (const LightClearance& c : choice.clearances)
        if (c.metres < choice.voxelSize)
            choice.warnings.push_back(scene.sourcePath + ": light '" + c.light + "' is " + lengthText(c.metres) +
                                      " from the nearest surface, less than one voxel (" +
                                      lengthText(choice.voxelSize) +
                                      "): the bounce light it gives may be low (by 20-60% at a third of a voxel); "
                                      "move it off the surface or give a smaller voxel-size");
    return choice;
}

std::string describeVoxelSize(const VoxelSizeChoice& choice) {
    return "voxel size " + lengthText(choice.voxelSize) + " (" + std::to_string(choice.voxelsAlongLongest) +
           " along the longest side), set by " + choice.setBy;
}

}  // namespace vl
