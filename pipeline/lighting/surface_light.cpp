#include "lighting/surface_light.h"

#include "core/error.h"
#include "core/progress.h"
#include "core/rng.h"
#include "lighting/direct_light.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>

namespace vl {

SurfaceLightStats lightVoxelsByRays(VoxelScene& voxels, const VoxelSurfacePoints& points, const TraceSceneView& scene,
                                    const BvhView& bvh, int skyStrata, Progress* progress) {
    const auto start = std::chrono::steady_clock::now();
    const size_t n = voxels.size();
    if (points.slotCount() != n * 6)
        throw Error("lightVoxelsByRays: " + std::to_string(points.slotCount()) + " point slots for " +
                    std::to_string(n) + " voxels");
    voxels.faceRadiance.assign(n, FaceRadiance{});
    voxels.radiance.assign(n, vec3(0.0f));
    voxels.occlusion.assign(n, 0.0f);
    const float layer = 0.5f * static_cast<float>(voxels.voxelSize);
    std::vector<uint8_t> empty(n, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t v = range.begin(); v != range.end(); ++v) {
            const VoxelSides sides = voxelSides(voxels.normal[v], voxels.axisWeights[v].data());
            vec3 irradiance[6] = {};
            float area[6] = {};
            uint32_t rays = 0, blocked = 0;
            for (int s = 0; s < sides.count; ++s) {
                const uint32_t first = points.begin[v * 6 + size_t(s)], last = points.begin[v * 6 + size_t(s) + 1];
                // Each side's points take the R2 sequence from an offset of the side's own (seeded
                // by its first point, which the scene's placement does not change), so its few
                // points spread over a sun's disk or an emitter instead of repeating.
                if (first == last) {
                    empty[v] = 1;
                    continue;
                }
                Pcg32 rng = Pcg32::forItem(points.points[first].id, 0, 0x4C49474854ull);  // "LIGHT"
                const double o1 = rng.next1D(), o2 = rng.next1D();
                vec3 sum(0.0f);
                float weight = 0.0f;
                for (uint32_t k = first; k < last; ++k) {
                    const SurfacePoint& p = points.points[k];
                    double u1 = o1 + 0.7548776662466927 * double(k - first), u2 = o2 + 0.5698402909980532 * double(k - first);
                    u1 -= std::floor(u1);
                    u2 -= std::floor(u2);
                    vec3 E = surfacePointIrradiance(scene, bvh, p.position, p.geometricNormal, p.normal,
                                                    vec2(float(u1), float(u2)), layer, p.id, &rays, &blocked);
                    if (skyStrata > 0)
                        E += skyIrradiance(scene, bvh, p.position, p.geometricNormal, p.normal, skyStrata, p.id, &p.tangent);
                    sum += p.area * E;
                    weight += p.area;
                }
                if (weight > 0.0f) {
                    irradiance[s] = sum / weight;
                    area[s] = weight;
                }
            }
            // Sides without points: the irradiance of the voxel's sides that face their way.
            for (int s = 0; s < sides.count; ++s) {
                if (area[s] > 0.0f) continue;
                vec3 sum(0.0f);
                float weight = 0.0f;
                for (int o = 0; o < sides.count; ++o)
                    if (area[o] > 0.0f && glm::dot(sides.normal[o], sides.normal[s]) > 0.0f) {
                        sum += area[o] * irradiance[o];
                        weight += area[o];
                    }
                if (weight > 0.0f) irradiance[s] = sum / weight;
            }
            const vec3 reflectance = voxels.albedo[v] * kInvPi;
            for (int f = 0; f < 6; ++f) {
                const int s = sides.sideOfFace[f];
                voxels.faceRadiance[v][size_t(f)] = s >= 0 ? reflectance * irradiance[s] : vec3(0.0f);
            }
            voxels.radiance[v] = faceWeightedMean(voxels.faceRadiance[v].data(), voxels.axisWeights[v].data());
            voxels.occlusion[v] = rays > 0 ? float(blocked) / float(rays) : 0.0f;
        }
        if (progress) progress->advance(range.size());
    });
    SurfaceLightStats stats;
    stats.points = points.points.size();
    for (uint8_t e : empty) stats.emptySides += e;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return stats;
}

std::vector<FaceRadiance> punctualFaceRadiance(const VoxelScene& voxels, const VoxelSurfacePoints& points,
                                               const TraceSceneView& scene, const BvhView& bvh) {
    if (scene.lightCount == 0) return {};
    TraceSceneView lightsOnly = scene;
    lightsOnly.emitterCount = 0;
    lightsOnly.emitterTree = {};
    VoxelScene lit = voxels;
    lightVoxelsByRays(lit, points, lightsOnly, bvh, 0);
    return std::move(lit.faceRadiance);
}

}  // namespace vl
