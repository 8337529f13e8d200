#include "lighting/surface_points.h"

#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace vl {

namespace {

// The R2 sequence (Roberts 2018): the most even 2D low-discrepancy sequence from one seed.
constexpr double kR2a = 0.7548776662466927, kR2b = 0.5698402909980532;

// A side keeps at most this many points (a finely tessellated cushion puts one point on each
// of its tiny triangles); the rest give their area to those kept, spread evenly among them.
constexpr uint32_t kMaxPointsPerSide = 12;

bool lexicographicLess(const ivec3& a, const ivec3& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
}

struct Placed {
    uint64_t key;  // slot << 24 | its order within the triangle: sorting keeps each slot's points in one order
    uint32_t triangle;
    SurfacePoint point;
};

}  // namespace

VoxelSurfacePoints voxelSurfacePoints(const VoxelScene& voxels, const TraceSceneView& scene, int perVoxelFace) {
    if (perVoxelFace < 1 || perVoxelFace > 256)
        throw Error("voxelSurfacePoints: " + std::to_string(perVoxelFace) + " points per voxel face is outside 1 … 256");
    VoxelSurfacePoints out;
    const size_t voxelCount = voxels.size();
    out.begin.assign(voxelCount * 6 + 1, 0u);
    if (voxelCount == 0 || scene.triangleCount == 0) return out;
    const double h = voxels.voxelSize;
    const double perArea = double(perVoxelFace) / (h * h);

    std::mutex merge;
    std::vector<Placed> placed;
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, scene.triangleCount, 1024), [&](const tbb::blocked_range<uint32_t>& range) {
        std::vector<Placed> local;
        for (uint32_t t = range.begin(); t != range.end(); ++t) {
            const float area = triangleArea(scene, t);
            if (!(area > 0.0f)) continue;
            const double wanted = std::round(double(area) * perArea);
            const uint32_t n = uint32_t(std::clamp(wanted, 1.0, 1.0e7));
            const bool doubleSided = scene.materials[scene.materialIds[t]].doubleSided;
            Pcg32 rng = Pcg32::forItem(t, 0, 0x5355524Full);  // "SURF"
            const double o1 = rng.next1D(), o2 = rng.next1D();
            for (uint32_t i = 0; i < n; ++i) {
                double u1 = o1 + kR2a * double(i), u2 = o2 + kR2b * double(i);
                u1 -= std::floor(u1);
                u2 -= std::floor(u2);
                const vec2 b = sampleUniformTriangle(vec2(float(u1), float(u2)));
                const SurfaceHit hit = surfaceAt(scene, t, b.x, b.y);
                const ivec3 c(glm::floor(hit.position / float(h) + vec3(0.5f)));
                const auto found = std::lower_bound(voxels.coords.begin(), voxels.coords.end(), c, lexicographicLess);
                if (found == voxels.coords.end() || *found != c) continue;
                const size_t v = size_t(found - voxels.coords.begin());
                const VoxelSides sides = voxelSides(voxels.normal[v], voxels.axisWeights[v].data());
                const vec3 front = glm::dot(hit.shadingNormal, hit.geometricNormal) >= 0.0f ? hit.shadingNormal : -hit.shadingNormal;
                const vec3* corner = scene.vertices + 3 * size_t(t);
                const vec3 edge = corner[1] - corner[0];
                for (int sign = 1; sign >= (doubleSided ? -1 : 1); sign -= 2) {
                    const vec3 ng = float(sign) * hit.geometricNormal;
                    int best = -1;
                    float bestDot = 0.0f;
                    for (int s = 0; s < sides.count; ++s) {
                        const float d = glm::dot(sides.normal[s], ng);
                        if (d > bestDot) best = s, bestDot = d;
                    }
                    if (best < 0) continue;
                    Placed p;
                    const uint64_t slot = uint64_t(v) * 6 + uint64_t(best);
                    p.key = slot << 24 | uint64_t(std::min<uint32_t>(i, 0x7FFFFFu)) << 1 | uint64_t(sign < 0);
                    p.triangle = t;
                    p.point.position = hit.position;
                    p.point.normal = float(sign) * front;
                    p.point.geometricNormal = ng;
                    p.point.triangle = t;
                    p.point.area = float(double(area) / double(n));
                    const vec3 across = edge - glm::dot(edge, p.point.normal) * p.point.normal;
                    const float length = glm::length(across);
                    vec3 bitangent;
                    if (length > 1e-12f) p.point.tangent = across / length;
                    else orthonormalBasis(p.point.normal, p.point.tangent, bitangent);
                    p.point.id = uint64_t(t) << 25 | uint64_t(std::min<uint32_t>(i, 0xFFFFFFu)) << 1 | uint64_t(sign < 0);
                    local.push_back(p);
                }
            }
        }
        std::lock_guard<std::mutex> lock(merge);
        placed.insert(placed.end(), local.begin(), local.end());
    });
    // One order whatever the threads did: by slot, then triangle, then place within it.
    tbb::parallel_sort(placed.begin(), placed.end(), [](const Placed& a, const Placed& b) {
        const uint64_t sa = a.key >> 24, sb = b.key >> 24;
        if (sa != sb) return sa < sb;
        if (a.triangle != b.triangle) return a.triangle < b.triangle;
        return a.key < b.key;
    });

    out.points.reserve(placed.size());
    size_t k = 0;
    for (size_t slot = 0; slot < voxelCount * 6; ++slot) {
        out.begin[slot] = uint32_t(out.points.size());
        size_t end = k;
        while (end < placed.size() && (placed[end].key >> 24) == slot) ++end;
        const size_t count = end - k;
        if (count <= kMaxPointsPerSide) {
            for (size_t j = k; j < end; ++j) out.points.push_back(placed[j].point);
        } else {
            // Evenly spaced over the slot's order, each kept point taking an equal share of the
            // whole side's area.
            double total = 0.0;
            for (size_t j = k; j < end; ++j) total += placed[j].point.area;
            for (uint32_t m = 0; m < kMaxPointsPerSide; ++m) {
                SurfacePoint p = placed[k + (size_t(m) * count) / kMaxPointsPerSide].point;
                p.area = float(total / kMaxPointsPerSide);
                out.points.push_back(p);
            }
        }
        k = end;
    }
    out.begin[voxelCount * 6] = uint32_t(out.points.size());
    return out;
}

}  // namespace vl
