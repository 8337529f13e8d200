// One voxel bounce in a closed box whose walls all hold radiance 1: every wall point sees
// walls only, so its irradiance is exactly π and, with albedo 1, the bounce adds exactly 1 to
// every face. The added light's area-weighted mean and spread, per turn of the box and voxel
// count, isolate what the bounce transfer (gather points, rays, the voxel faces they read,
// the sides' interpolation) loses on slanted walls. An accuracy measurement, not a test.
//
// With --lit the walls are lit instead by a 0.2 m square emitter under the ceiling (the voxel
// light pass, albedo 1): the walls' light is then as uneven as a Cornell box's, and the ratio
// of the light the bounce adds to the direct light is compared between turns (a closed box
// with albedo 1 keeps all of it: the unturned box's ratio is the reference).
//
// With --scene FILE a glTF is lit and turned instead (the same way), its meshes whose name
// holds a --drop text left out: the Cycles Cornell box with and without its blocks, say.
//
//   build/accuracy/accuracy_turned_box [--lit] [--scene FILE [--drop TEXT …]] [RESOLUTION …]
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "gather/ray_gather.h"
#include "gather/bounces.h"
#include "lighting/lighting.h"
#include "scene/gltf_loader.h"
#include "scene/scene.h"
#include "voxel/voxelize.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <vector>

using namespace vl;

namespace {

void addQuad(Scene& scene, const std::string& name, int material, vec3 a, vec3 b, vec3 c, vec3 d) {
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    mesh.positions = {a, b, c, d};
    const vec3 n = glm::normalize(glm::cross(b - a, c - a));
    mesh.normals = {n, n, n, n};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    scene.meshes.push_back(mesh);
}

Scene turnedBox(const glm::quat& turn, bool lit) {
    Scene scene;
    scene.sourcePath = "turned box";
    Material white;
    white.baseColorFactor = vec4(1.0f);
    scene.materials.push_back(white);
    const vec3 p000(0, 0, 0), p100(1, 0, 0), p010(0, 1, 0), p001(0, 0, 1), p110(1, 1, 0), p101(1, 0, 1), p011(0, 1, 1),
        p111(1, 1, 1);
    addQuad(scene, "floor", 0, p000, p001, p101, p100);
    addQuad(scene, "ceiling", 0, p010, p110, p111, p011);
    addQuad(scene, "wall-x", 0, p000, p010, p011, p001);
    addQuad(scene, "wall+x", 0, p100, p101, p111, p110);
    addQuad(scene, "wall-z", 0, p000, p100, p110, p010);
    addQuad(scene, "wall+z", 0, p001, p011, p111, p101);
    if (lit) {
        Material lamp;
        lamp.baseColorFactor = vec4(0.0f, 0.0f, 0.0f, 1.0f);
        lamp.emissiveFactor = vec3(1.0f);
        scene.materials.push_back(lamp);
        addQuad(scene, "lamp", 1, vec3(0.4f, 0.99f, 0.4f), vec3(0.6f, 0.99f, 0.4f), vec3(0.6f, 0.99f, 0.6f),
                vec3(0.4f, 0.99f, 0.6f));
    }
    for (Mesh& mesh : scene.meshes) {
        for (vec3& p : mesh.positions) p = turn * (p - vec3(0.5f));
        for (vec3& n : mesh.normals) n = turn * n;
    }
    return scene;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<int> resolutions;
    bool lit = false;
    std::string sceneFile;
    std::vector<std::string> drops;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--lit")
            lit = true;
        else if (arg == "--scene" && i + 1 < argc)
            sceneFile = argv[++i], lit = true;
        else if (arg == "--drop" && i + 1 < argc)
            drops.push_back(argv[++i]);
        else
            resolutions.push_back(std::atoi(arg.c_str()));
    }
    if (resolutions.empty()) resolutions = {48, 64, 96};
    const glm::quat turns[] = {
        glm::quat(1, 0, 0, 0),
        glm::angleAxis(glm::radians(30.0f), vec3(0.0f, 1.0f, 0.0f)),
        glm::angleAxis(glm::radians(45.0f), glm::normalize(vec3(1.0f, 1.0f, 0.0f))),
        glm::angleAxis(glm::radians(60.0f), glm::normalize(vec3(1.0f, 2.0f, 3.0f))),
        glm::normalize(glm::quat(-0.346f, 0.464f, 0.175f, 0.796f)),  // accuracy_rotations' turn 1
    };
    const char* names[] = {"unturned", "30° about Y", "45° about (1,1,0)", "60° about (1,2,3)", "rotations' turn 1"};
    const int turnCount = sceneFile.empty() ? 4 : 5;
    BakeSettings settings;
    for (int resolution : resolutions)
        for (int t = 0; t < turnCount; ++t) {
            Scene scene = sceneFile.empty() ? turnedBox(turns[t], lit) : loadGltf(sceneFile);
            if (!sceneFile.empty()) {
                std::vector<Mesh> kept;
                for (Mesh& mesh : scene.meshes) {
                    bool drop = false;
                    for (const std::string& d : drops) drop = drop || mesh.name.find(d) != std::string::npos ||
                                                              mesh.node.find(d) != std::string::npos;
                    if (!drop) kept.push_back(std::move(mesh));
                }
                scene.meshes = std::move(kept);
                for (Mesh& mesh : scene.meshes) {
                    for (vec3& p : mesh.positions) p = turns[t] * p;
                    for (vec3& n : mesh.normals) n = turns[t] * n;
                }
                for (Light& light : scene.lights) {
                    light.position = turns[t] * light.position;
                    light.direction = turns[t] * light.direction;
                }
            }
            VoxelSettings voxel = settings.voxel;
            voxel.resolution = resolution;
            const double h = voxelSizeFor(scene, voxel);
            anchorToVoxelGrid(scene, h);
            voxel.voxelSize = h;
            VoxelScene voxels = voxelize(scene, voxel);
            const size_t n = voxels.size();
            if (lit) {
                voxels.albedo.assign(n, vec3(1.0f));
                lightVoxels(scene, voxels, settings.lighting);
            } else {
                voxels.faceRadiance.assign(n, FaceRadiance{});
                voxels.radiance.assign(n, vec3(1.0f));
                for (size_t i = 0; i < n; ++i)
                    for (int f = 0; f < 6; ++f)
                        voxels.faceRadiance[i][f] = voxels.axisWeights[i][f] > 0.0f ? vec3(1.0f) : vec3(0.0f);
            }
            const std::vector<FaceRadiance> direct = voxels.faceRadiance;
            const ReceiverScene tracing(scene);
            const BvhView bvh = tracing.bvh.view();
            const TraceSceneView view = tracing.traceScene.view();
            BounceSettings bounce{1, settings.gather.bounceGatherLevel, BounceTail::None,
                                  bounceConeSettings(settings.gather)};
            bounce.byRays = true;
            bounce.raysPerAxis = settings.gather.bounceRays;
            const GatherScene rays{bvh, view};
            const Bounced bounced =
                propagateBounces(voxels, bounce, &rays, IrradianceCache(voxels, settings.gather.bounceGatherLevel));
            const IrradianceCache& points = bounced.points;
            // The added light per face, weighted by its share of its voxel's surface area;
            // lit: the added light over the direct light, both so weighted.
            double sum = 0.0, squares = 0.0, weight = 0.0, lowest = 1e9, directSum = 0.0;
            for (size_t i = 0; i < n; ++i)
                for (int f = 0; f < 6; ++f) {
                    // A side's axis weights are its area times |n| per axis: over |n|₁ they are
                    // shares of its area, whatever way the wall is turned.
                    const vec3& normal = voxels.normal[i];
                    const float l1 = std::abs(normal.x) + std::abs(normal.y) + std::abs(normal.z);
                    const float w = voxels.axisWeights[i][f] / (l1 > 0.0f ? l1 : 1.0f);
                    if (!(w > 0.0f)) continue;
                    const double added = voxels.faceRadiance[i][f].x - direct[i][f].x;
                    sum += w * added;
                    directSum += w * direct[i][f].x;
                    squares += w * added * added;
                    weight += w;
                    lowest = std::min(lowest, added);
                }
            const double mean = lit ? sum / directSum : sum / weight;
            const double rms = lit ? 0.0 : std::sqrt(std::max(0.0, squares / weight - mean * mean));
            std::printf("%3d voxels, %-18s: added light mean %.4f (exact 1), spread %.4f, lowest %.3f, %zu voxels, %zu points\n",
                        resolution, names[t], mean, rms, lowest, n, points.points().size());
        }
    return 0;
}
