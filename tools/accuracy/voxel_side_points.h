// Points spread over the surface inside each voxel side, area-weighted: what the accuracy
// tools that rate the voxels' light against the exact light at their surfaces average over.
#pragma once

#include "core/math.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/trace_scene.h"
#include "voxel/voxel_scene.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace vl {

struct VoxelSidePoint {
    SurfaceSample sample;  // on the side of its triangle the voxel side faces; weight 1
    uint32_t voxel = 0;
    int side = 0;        // of voxelSides(voxel)
    double area = 0.0;   // of the surface it stands for
    uint64_t draw = 0;   // its own number, for the caller's random draws
};

// Calls visit(const VoxelSidePoint&) for pointsPerVoxel points per h² of each triangle's
// surface (at least one a triangle), drawn uniformly from the triangle by `salt`, on each side
// of it that a double-sided material shows, each given to the side of its voxel whose normal is
// nearest that side's; points outside every voxel are skipped. In triangle order: the same
// points every run.
template <typename Visit>
void forEachVoxelSidePoint(const VoxelScene& voxels, const TraceSceneView& view, int pointsPerVoxel, uint64_t salt,
                           Visit&& visit) {
    struct CoordHash {
        size_t operator()(const ivec3& c) const {
            return size_t(uint32_t(c.x)) * 73856093u ^ size_t(uint32_t(c.y)) * 19349663u ^ size_t(uint32_t(c.z)) * 83492791u;
        }
    };
    std::unordered_map<ivec3, uint32_t, CoordHash> index;
    for (size_t i = 0; i < voxels.size(); ++i) index[voxels.coords[i]] = uint32_t(i);
    const double h = voxels.voxelSize;
    const double perArea = double(pointsPerVoxel) / (h * h);
    for (uint32_t t = 0; t < view.triangleCount; ++t) {
        const float area = triangleArea(view, t);
        if (!(area > 0.0f)) continue;
        const int n = std::max(1, int(std::lround(area * perArea)));
        for (int k = 0; k < n; ++k) {
            Pcg32 rng = Pcg32::forItem(t, uint64_t(k), salt);
            const vec2 b = sampleUniformTriangle(vec2(rng.next1D(), rng.next1D()));
            const SurfaceHit hit = surfaceAt(view, t, b.x, b.y);
            const auto it = index.find(ivec3(glm::floor(hit.position / float(h) + vec3(0.5f))));
            if (it == index.end()) continue;
            const uint32_t v = it->second;
            const VoxelSides sides = voxelSides(voxels.normal[v], voxels.axisWeights[v].data());
            const bool doubleSided = view.materials[view.materialIds[t]].doubleSided;
            const vec3 ng = hit.geometricNormal;
            for (float sign : {1.0f, -1.0f}) {
                if (sign < 0.0f && !doubleSided) continue;
                int best = -1;
                float bestDot = 0.0f;
                for (int s = 0; s < sides.count; ++s) {
                    const float d = glm::dot(sides.normal[s], sign * ng);
                    if (d > bestDot) best = s, bestDot = d;
                }
                if (best < 0) continue;
                VoxelSidePoint p;
                p.sample.position = hit.position;
                p.sample.normal = sign * (glm::dot(hit.shadingNormal, ng) >= 0.0f ? hit.shadingNormal : -hit.shadingNormal);
                p.sample.albedo = baseColorAt(view, hit);
                p.sample.triangle = t;
                p.sample.weight = 1.0f;
                p.voxel = v;
                p.side = best;
                p.area = double(area) / n;
                p.draw = uint64_t(t) * 131u + uint64_t(k);
                visit(p);
            }
        }
    }
}

}  // namespace vl
