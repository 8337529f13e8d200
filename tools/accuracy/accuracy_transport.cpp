// How well the final gather's cones carry light, apart from how well the voxels hold it: at
// every gather point of a bake with no voxel bounces (the voxels hold direct light only),
// the cones' irradiance against a ray-traced gather of the same voxel radiance (rays against
// the scene's triangles from the cone apex, cosine-distributed, each reading the radiance of
// the voxel face it hits). Grouped by the mesh under the gather point, and by cone ring
// (each cone against rays inside its own cap). A ratio away from 1 is the cones' error
// alone: the mips' blur, their opacity model, cone overlap and gaps. An accuracy
// measurement, not a test and not a speed figure.
//
//   build/accuracy/accuracy_transport [SCENE.gltf] [--rays N] [--map MESH] [--hot F] [name=value …]
//   (--map: the ratio over the named mesh in 8 × 8 cells of its two longest axes; --hot: the
//   voxel faces brighter than F times the area-weighted mean face are left out of the cones'
//   mips and gathered by the rays instead, as a split of the light into a few bright patches
//   handled exactly and a diffuse rest would be)
//   (default scene: the Cycles Cornell box with the quad light, ../shared/reference/)
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "gather/bright_patches.h"
#include "lighting/surface_points.h"
#include "cone/cone_trace.h"
#include "gather/irradiance_cache.h"
#include "core/error.h"
#include "core/sampling.h"
#include "scene/gltf_loader.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/trace_scene.h"
#include "voxel/voxelize.h"

#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>

using namespace vl;

namespace {

struct CoordHash {
    size_t operator()(const ivec3& c) const {
        return size_t(uint32_t(c.x)) * 73856093u ^ size_t(uint32_t(c.y)) * 19349663u ^ size_t(uint32_t(c.z)) * 83492791u;
    }
};

// Radiance the voxels show a ray at its hit: the face of the hit surface's main axis that
// faces the ray, in the voxel along that axis (within one) with the most surface there.
class VoxelRadianceLookup {
public:
    VoxelRadianceLookup(const VoxelScene& voxels, const TraceScene& scene) : voxels_(voxels), scene_(scene) {
        for (size_t i = 0; i < voxels.size(); ++i) index_[voxels.coords[i]] = i;
    }

    float at(const Ray& ray, const Hit& hit) const {
        const SurfaceHit surface = surfaceAt(scene_.view(), hit.triangle, hit.b1, hit.b2);
        const vec3 n = glm::abs(surface.geometricNormal);
        const int axis = n.x > n.y ? (n.x > n.z ? 0 : 2) : (n.y > n.z ? 1 : 2);
        const int face = 2 * axis + (ray.direction[axis] < 0.0f ? 0 : 1);
        const ivec3 centre(glm::floor(ray.at(hit.t) / float(voxels_.voxelSize) + vec3(0.5f)));
        float best = 0.0f, radiance = 0.0f;
        for (int k = -1; k <= 1; ++k) {
            ivec3 c = centre;
            c[axis] += k;
            const auto it = index_.find(c);
            if (it == index_.end() || !(voxels_.axisWeights[it->second][size_t(face)] > best)) continue;
            best = voxels_.axisWeights[it->second][size_t(face)];
            const vec3 L = voxels_.faceRadiance.empty() ? voxels_.radiance[it->second] : voxels_.faceRadiance[it->second][size_t(face)];
            radiance = (L.x + L.y + L.z) / 3.0f;
        }
        return radiance;
    }

private:
    const VoxelScene& voxels_;
    const TraceScene& scene_;
    std::unordered_map<ivec3, size_t, CoordHash> index_;
};

int ringOf(float cosToNormal) { return cosToNormal > 0.95f ? 0 : cosToNormal > 0.75f ? 1 : cosToNormal > 0.45f ? 2 : 3; }

}  // namespace

int main(int argc, char** argv) {
    try {
        std::string path = VOXLIGHT_SOURCE_DIR "/../shared/reference/cornell_quad.gltf";
        int raysPerAxis = 12;
        std::string mapMesh;
        float hotFactor = 0.0f;
        BakeSettings settings;
        settings.quiet = true;
        settings.outputs.lightmaps = settings.outputs.images = settings.outputs.grids = false;
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            if (a == "--rays" && i + 1 < argc) raysPerAxis = std::stoi(argv[++i]);
            else if (a == "--map" && i + 1 < argc) mapMesh = argv[++i];
            else if (a == "--hot" && i + 1 < argc) hotFactor = std::stof(argv[++i]);
            else if (a.find('=') != std::string::npos) applySetting(bakeSettingsTable(), settings, a);
            else path = a;
        }
        settings.gather.bounces = 0;
        settings.gather.bounceTail = false;
        const Scene scene = loadGltf(path);
        Diagnostics diagnostics;
        const BakeResult baked = bake(scene, settings, diagnostics);
        // The bake moved its copy of the scene to put a voxel corner at the centre of its
        // bounds: the rays must see the triangles where the voxels do.
        Scene anchored = scene;
        if (anchored.frame != baked.voxels.frame) anchored.turnFrame(baked.voxels.frame);
        anchorToVoxelGrid(anchored, baked.voxels.voxelSize);
        const SceneTriangles triangles = gatherTriangles(anchored);
        const Bvh bvh = Bvh::build(triangles);
        const TraceScene traced = TraceScene::build(anchored, triangles);
        // --hot: the bake's own split (gather/bright_patches.h) with every bright face a patch of
        // its own and none left in the mips; the rays read the bright faces, the cones the rest.
        VoxelScene rest = baked.voxels, hot = baked.voxels;
        size_t hotFaces = 0;
        if (hotFactor > 0.0f) {
            BrightPatchSettings everyFace;
            everyFace.factor = hotFactor;
            everyFace.cellVoxels = 1;
            everyFace.maxPatches = std::numeric_limits<int>::max();
            const BrightPatchSplit split =
                splitBrightPatches(baked.voxels, voxelSurfacePoints(baked.voxels, traced.view(), 4), everyFace);
            hotFaces = split.faces;
            rest.faceRadiance = split.restFaces;
            rest.radiance = split.restRadiance;
            for (size_t i = 0; i < hot.size(); ++i)
                for (size_t f = 0; f < 6; ++f) hot.faceRadiance[i][f] -= rest.faceRadiance[i][f];
        }
        const RadianceMips restMips = hotFactor > 0.0f ? buildRadianceMips(rest) : RadianceMips();
        const VoxelRadianceLookup lookup(baked.voxels, traced);
        const VoxelRadianceLookup hotLookup(hot, traced);
        const IrradianceCache cache(baked.voxels, settings.gather.gatherLevel);
        const MipView mips = hotFactor > 0.0f ? restMips.view() : baked.mips.view();
        const ConeSet& set = coneSet(settings.gather.cone.coneCount);
        const float h = float(baked.voxels.voxelSize);
        const float halfAngle = coneHalfAngle(set, settings.gather.cone);
        const float cosCap = std::cos(halfAngle);

        struct Sums {
            double cone = 0.0, rays = 0.0;
            int points = 0;
        };
        std::map<std::string, Sums> byMesh;
        Sums byRing[4];
        std::vector<std::pair<vec3, std::array<double, 2>>> mapped;
        for (const GatherPoint& point : cache.points()) {
            const vec3 apex = coneApex(point.position, point.normal, settings.gather.cone, h);
            // The mesh under the point: the first surface straight back from the apex.
            Ray down;
            down.origin = apex;
            down.direction = -point.normal;
            Hit under;
            if (!intersectClosest(bvh.view(), down, under)) continue;
            Sums& mesh = byMesh[scene.meshes[triangles.meshIndex[under.triangle]].node];
            ++mesh.points;
            const double before[2] = {mesh.cone, mesh.rays};
            for (int turn = 0; turn < settings.gather.gatherTurns; ++turn) {
                const float angle = 2.0f * kPi * (point.turn + float(turn) / float(settings.gather.gatherTurns));
                const vec3 tangent = std::cos(angle) * point.tangent + std::sin(angle) * glm::cross(point.normal, point.tangent);
                const vec3 bitangent = glm::cross(point.normal, tangent);
                for (int k = 0; k < set.count; ++k) {
                    const vec3& d = set.directions[k];
                    const vec3 dir = glm::normalize(d.x * tangent + d.y * bitangent + d.z * point.normal);
                    ConeOrigin origin;
                    origin.apexHeight = settings.gather.cone.startOffset * h;
                    origin.cosToNormal = d.z;
                    const ConeResult cone = traceCone(mips, apex, dir, std::tan(halfAngle), settings.gather.cone.stepFactor,
                                                      settings.gather.cone.maxDistance, origin);
                    // Rays spread uniformly over the cone's cap (below the receiver's plane: none).
                    vec3 u, v;
                    orthonormalBasis(dir, u, v);
                    double radiance = 0.0, hotRadiance = 0.0;
                    const int n = raysPerAxis;
                    for (int i = 0; i < n; ++i)
                        for (int j = 0; j < n; ++j) {
                            const float cosTheta = 1.0f - (float(i) + 0.5f) / float(n) * (1.0f - cosCap);
                            const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
                            const float phi = 2.0f * kPi * (float(j) + 0.5f) / float(n);
                            Ray ray;
                            ray.origin = apex;
                            ray.direction = sinTheta * std::cos(phi) * u + sinTheta * std::sin(phi) * v + cosTheta * dir;
                            Hit hit;
                            if (glm::dot(ray.direction, point.normal) > 0.0f && intersectClosest(bvh.view(), ray, hit)) {
                                radiance += lookup.at(ray, hit);
                                if (hotFactor > 0.0f) hotRadiance += hotLookup.at(ray, hit);
                            }
                        }
                    radiance /= double(n * n);
                    const double w = set.weights[k] / settings.gather.gatherTurns;
                    const double coneRadiance =
                        (cone.radiance.x + cone.radiance.y + cone.radiance.z) / 3.0 + hotRadiance / double(n * n);
                    mesh.cone += w * coneRadiance;
                    mesh.rays += w * radiance;
                    byRing[ringOf(d.z)].cone += w * coneRadiance;
                    byRing[ringOf(d.z)].rays += w * radiance;
                }
            }
            if (!mapMesh.empty() && scene.meshes[triangles.meshIndex[under.triangle]].node == mapMesh)
                mapped.push_back({point.position, {mesh.cone - before[0], mesh.rays - before[1]}});
        }
        if (!mapped.empty()) {
            vec3 lo(1e30f), hi(-1e30f);
            for (const auto& m : mapped) {
                lo = glm::min(lo, m.first);
                hi = glm::max(hi, m.first);
            }
            const vec3 ext = hi - lo;
            const int a0 = ext.x < ext.y && ext.x < ext.z ? 1 : 0, a1 = ext.z < ext.x && ext.z < ext.y ? 1 : 2;
            double g[8][8][2] = {};
            for (const auto& m : mapped) {
                const vec3 q = (m.first - lo) / glm::max(ext, vec3(1e-6f));
                const int i = std::min(7, int(q[a0] * 8)), j = std::min(7, int(q[a1] * 8));
                g[j][i][0] += m.second[0];
                g[j][i][1] += m.second[1];
            }
            printf("%s, cones / rays by cell (rows: axis %d rising, columns: axis %d rising)\n", mapMesh.c_str(), a1, a0);
            for (int j = 0; j < 8; ++j) {
                for (int i = 0; i < 8; ++i) printf(" %5.2f", g[j][i][0] / g[j][i][1]);
                printf("\n");
            }
        }
        printf("%s: %d cones (%d turns), first bounce gathered by cones / by rays over each cone's cap (%d rays)\n",
               path.c_str(), set.count, settings.gather.gatherTurns, raysPerAxis * raysPerAxis);
        if (hotFactor > 0.0f)
            printf("  the %zu voxel faces brighter than %g times the mean face gathered by the rays in both\n", hotFaces,
                   double(hotFactor));
        Sums all;
        for (const auto& [name, s] : byMesh) {
            printf("  %-16s %5d gather points  %.3f\n", name.c_str(), s.points, s.cone / s.rays);
            all.cone += s.cone;
            all.rays += s.rays;
        }
        printf("  %-16s %5s                %.3f\n", "all", "", all.cone / all.rays);
        const char* rings[4] = {"cos > 0.95", "cos 0.75-0.95", "cos 0.45-0.75", "cos < 0.45"};
        for (int r = 0; r < 4; ++r)
            printf("  cones at %-13s share of the rays' irradiance %4.1f%%  %.3f\n", rings[r], 100.0 * byRing[r].rays / all.rays,
                   byRing[r].cone / byRing[r].rays);
        return 0;
    } catch (const Error& e) {
        fprintf(stderr, "accuracy_transport: %s\n", e.what());
        return 1;
    }
}
