// Voxel direct-lighting throughput on zdm2.glb (a Godot demo level) voxelized at 256 and 512
// voxels along its longest axis, lit by four point lights placed inside the level (the file
// has none): voxel–light evaluations per second including visibility, the share of time
// spent stepping, the 1 → 2 thread speed-up, and HDDA empty-space skipping against plain
// one-voxel DDA steps. Every ratio is taken in the same run, beside its peer.
//
// Run: build/microbench/microbench_lighting [scene.glb] [resolution ...]
#include "core/error.h"
#include "lighting/lighting.h"
#include "scene/gltf_loader.h"
#include "voxel/index_grid.h"
#include "voxel/voxelize.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

using namespace vl;

namespace {

std::string defaultScene() { return std::string(VOXLIGHT_SOURCE_DIR) + "/../shared/scenes/interior-zdm2-godot/zdm2.glb"; }

// Four point lights inside the level: where the Godot demo that ships zdm2.glb (test.tscn)
// puts its GrateOmniLight, GarageOmniLight and CornerSpotLight, and its camera's start,
// moved into the file's frame (the demo instances the level at z + 2).
std::vector<Light> lightsInside(const VoxelScene& voxels) {
    const vec3 positions[] = {vec3(11.9461f, -1.33084f, -7.52646f), vec3(21.6053f, -1.96042f, -15.798f),
                              vec3(-14.0594f, -1.81824f, 10.3035f), vec3(11.7976f, 1.49898f, 7.54247f)};
    const auto grid = buildIndexGrid(voxels);
    const auto accessor = grid.grid<int32_t>()->getAccessor();
    const float h = static_cast<float>(voxels.voxelSize);
    std::vector<Light> lights;
    for (const vec3& p : positions) {
        Light light;
        light.name = "bench light " + std::to_string(lights.size());
        light.type = LightType::Point;
        light.intensity = 50.0f;
        light.color = vec3(1.0f, 0.9f, 0.8f);
        light.position = p;
        const vec3 c = glm::floor(p / h + 0.5f);
        if (accessor.getValue(nanovdb::Coord(int(c.x), int(c.y), int(c.z))) >= 0)
            std::printf("  note: %s sits in an active voxel\n", light.name.c_str());
        lights.push_back(light);
    }
    return lights;
}

struct Run {
    LightingStats stats;
    double cpuSeconds = 0.0;  // process CPU time: on a loaded machine wall time is not ours alone
    std::vector<vec3> radiance;
};

Run lightOnce(const Scene& scene, const VoxelScene& voxels, VisibilityTraversal traversal, int threads, bool visibility) {
    VoxelScene copy = voxels;
    LightingSettings settings;
    settings.traversal = traversal;
    settings.threads = threads;
    settings.visibility = visibility;
    Run run;
    const std::clock_t cpu0 = std::clock();
    run.stats = lightVoxels(scene, copy, settings);
    run.cpuSeconds = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
    run.radiance = std::move(copy.radiance);
    return run;
}

double perSecond(const Run& run) { return static_cast<double>(run.stats.voxelLightEvaluations) / run.stats.seconds; }

}  // namespace

int main(int argc, char** argv) {
    try {
        std::string path = defaultScene();
        std::vector<int> resolutions;
        for (int i = 1; i < argc; ++i) {
            const std::string arg = argv[i];
            if (!arg.empty() && std::isdigit(static_cast<unsigned char>(arg[0]))) resolutions.push_back(std::stoi(arg));
            else path = arg;
        }
        if (resolutions.empty()) resolutions = {256, 512};

        Scene scene = loadGltf(path);
        std::printf("scene %s: %zu triangles, %zu lights in the file\n", path.c_str(), scene.triangleCount(),
                    scene.lights.size());
        for (int resolution : resolutions) {
            VoxelSettings voxelSettings;
            voxelSettings.resolution = resolution;
            const auto t0 = std::chrono::steady_clock::now();
            const VoxelScene voxels = voxelize(scene, voxelSettings);
            const double voxelizeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            Scene lit = scene;
            lit.lights = lightsInside(voxels);
            std::printf("\nresolution %d: %zu voxels of %.4g m (voxelized in %.1f s); lights at", resolution,
                        voxels.size(), voxels.voxelSize, voxelizeSeconds);
            for (const Light& light : lit.lights)
                std::printf(" (%.2f, %.2f, %.2f)", light.position.x, light.position.y, light.position.z);
            std::printf("\n");

            const Run hdda1 = lightOnce(lit, voxels, VisibilityTraversal::Hdda, 1, true);
            const Run hdda2 = lightOnce(lit, voxels, VisibilityTraversal::Hdda, 2, true);
            const Run dda1 = lightOnce(lit, voxels, VisibilityTraversal::Dda, 1, true);
            const Run dda2 = lightOnce(lit, voxels, VisibilityTraversal::Dda, 2, true);
            const Run bare1 = lightOnce(lit, voxels, VisibilityTraversal::Hdda, 1, false);
            const Run bare2 = lightOnce(lit, voxels, VisibilityTraversal::Hdda, 2, false);

            std::printf("  %-18s %7s %12s %12s %9s %10s %9s %12s\n", "run", "threads", "evaluations", "steps",
                        "wall s", "eval/s", "cpu s", "eval/cpu-s");
            auto row = [](const char* name, int threads, const Run& run) {
                std::printf("  %-18s %7d %12llu %12llu %9.3f %10.3g %9.3f %12.3g\n", name, threads,
                            static_cast<unsigned long long>(run.stats.voxelLightEvaluations),
                            static_cast<unsigned long long>(run.stats.visibilitySteps), run.stats.seconds, perSecond(run),
                            run.cpuSeconds, static_cast<double>(run.stats.voxelLightEvaluations) / run.cpuSeconds);
            };
            row("HDDA", 1, hdda1);
            row("HDDA", 2, hdda2);
            row("DDA (one voxel)", 1, dda1);
            row("DDA (one voxel)", 2, dda2);
            row("no visibility", 1, bare1);
            row("no visibility", 2, bare2);
            const bool same = std::memcmp(hdda1.radiance.data(), dda2.radiance.data(), hdda1.radiance.size() * sizeof(vec3)) == 0 &&
                              std::memcmp(hdda1.radiance.data(), hdda2.radiance.data(), hdda1.radiance.size() * sizeof(vec3)) == 0;
            std::printf("  share of time stepping (1 thread, HDDA): %.1f %% of wall, %.1f %% of CPU time\n",
                        100.0 * (1.0 - bare1.stats.seconds / hdda1.stats.seconds),
                        100.0 * (1.0 - bare1.cpuSeconds / hdda1.cpuSeconds));
            std::printf("  speed-up 1 -> 2 threads: HDDA %.2fx, DDA %.2fx\n", hdda1.stats.seconds / hdda2.stats.seconds,
                        dda1.stats.seconds / dda2.stats.seconds);
            std::printf("  HDDA vs DDA: %.2fx faster (wall), %.2fx (CPU), %.2fx fewer steps (1 thread); radiance identical across HDDA/DDA and 1/2 threads: %s\n",
                        dda1.stats.seconds / hdda1.stats.seconds, dda1.cpuSeconds / hdda1.cpuSeconds,
                        static_cast<double>(dda1.stats.visibilitySteps) / static_cast<double>(hdda1.stats.visibilitySteps),
                        same ? "yes" : "NO");
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "microbench_lighting: %s\n", e.what());
        return 1;
    }
    return 0;
}
