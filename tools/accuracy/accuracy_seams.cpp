// Where a lightmap's chart seams jump, and what stitching leaves (bake/lightmap_seams.h).
// Bakes the scene (or a job file's first scene) in memory as `voxlight bake` does, finishes
// each atlas twice, unstitched and stitched, and reports the seams' mean relative jump (what
// bake.json's "lightmap_seams" reports) over all seams and by class: the fold between the two
// triangles, the seam's length in texels, and its light level. Also the time stitching took.
// An accuracy measurement, not a test.
//
//   build/accuracy/accuracy_seams SCENE.gltf|JOB.json [name=value …]
//
// Bake settings as name=value (the bake's flags without --).
#include "accuracy_job.h"
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "bake/lightmap_image.h"
#include "bake/lightmap_seams.h"
#include "core/error.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

using namespace vl;
namespace fs = std::filesystem;

namespace {

// A class of seams: its share of the seams' counted weight and the two jumps' sums.
struct Class {
    const char* name;
    SeamJump before, after;
};

void add(SeamJump& sum, const SeamJump& one) {
    sum.edges += one.edges;
    sum.length += one.length;
    sum.weight += one.weight;
    sum.relativeSum += one.relativeSum;
}

double mean(const SeamJump& j) { return j.weight > 0.0 ? j.relativeSum / j.weight : 0.0; }

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SCENE.gltf|JOB.json [name=value ...]\n", argv[0]);
        return 2;
    }
    try {
        const std::string input = argv[1];
        SettingAssignments assignments;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            const size_t eq = arg.find('=');
            if (eq == std::string::npos) throw SettingsError("not name=value: " + arg);
            assignments.emplace_back(arg.substr(0, eq), arg.substr(eq + 1));
        }
        BakeJob job = accuracyJob(input, assignments);
        job.settings.quiet = true;
        job.settings.outputs.grids = false;

        Diagnostics diagnostics(false, false);
        Scene scene = loadJobScene(job);
        VoxelStages stages = bakeVoxelStages(scene, job.settings, diagnostics);
        const ReceiverShading shading(*stages.tracing, stages.result.mips, stages.cache, stages.bright, job.settings,
                                      stages.onGpu);
        // Folds: < 1°, 1-15°, 15-45°, ≥ 45°; lengths: the longer side < 2, 2-16, ≥ 16 texels;
        // levels: the mean of the two sides unstitched, per channel, < 0.01, 0.01-0.1, ≥ 0.1.
        std::vector<Class> classes = {{"all seams", {}, {}},         {"fold < 1 deg", {}, {}},
                                      {"fold 1-15 deg", {}, {}},     {"fold 15-45 deg", {}, {}},
                                      {"fold >= 45 deg", {}, {}},    {"length < 2 texels", {}, {}},
                                      {"length 2-16 texels", {}, {}}, {"length >= 16 texels", {}, {}},
                                      {"level < 0.01", {}, {}},      {"level 0.01-0.1", {}, {}},
                                      {"level >= 0.1", {}, {}}};
        double stitchSeconds = 0.0, finishSeconds = 0.0;
        for (const LightmapAtlas& atlas : buildLightmapReceivers(scene, stages.lightmap, diagnostics)) {
            const ReceiverLighting lit = shading.shadeAtlasRows(atlas, 0, atlas.receivers.height);
            BakeSettings plain = job.settings, stitched = job.settings;
            plain.lightmapStitch = false;
            stitched.lightmapStitch = true;
            const auto t0 = std::chrono::steady_clock::now();
            const BakedLightmap off = finishLightmap(atlas, lit.direct, lit.indirect, scene, plain);
            const auto t1 = std::chrono::steady_clock::now();
            const BakedLightmap on = finishLightmap(atlas, lit.direct, lit.indirect, scene, stitched);
            const auto t2 = std::chrono::steady_clock::now();
            finishSeconds += std::chrono::duration<double>(t1 - t0).count();
            stitchSeconds += std::chrono::duration<double>((t2 - t1) - (t1 - t0)).count();
            const Image before = shippedLightmapTexels(off.total), after = shippedLightmapTexels(on.total);
            const std::vector<LightmapSeam> seams = findLightmapSeams(scene, atlas.meshes, atlas.mask.width,
                                                                      atlas.mask.height);
            std::printf("atlas '%s': %d x %d, %zu seams, %.2f m; mean relative jump %.2f%% unstitched, %.2f%% "
                        "stitched, %zu texels moved\n",
                        atlas.name.c_str(), atlas.mask.width, atlas.mask.height, seams.size(), on.seams.after.length,
                        100.0 * on.seams.before.meanRelative, 100.0 * on.seams.after.meanRelative,
                        on.seams.texelsMoved);
            for (const LightmapSeam& seam : seams) {
                const SeamJump b = measureSeamJump({seam}, before), a = measureSeamJump({seam}, after);
                const float texels = std::max(glm::length(seam.sides[0].b - seam.sides[0].a),
                                              glm::length(seam.sides[1].b - seam.sides[1].a));
                const double level = b.weight > 0.0 ? b.levelSum / b.weight / 3.0 : 0.0;
                const float fold = seam.foldDegrees;
                for (size_t c : {size_t(0), size_t(fold < 1.0f ? 1 : fold < 15.0f ? 2 : fold < 45.0f ? 3 : 4),
                                 size_t(texels < 2.0f ? 5 : texels < 16.0f ? 6 : 7),
                                 size_t(level < 0.01 ? 8 : level < 0.1 ? 9 : 10)}) {
                    add(classes[c].before, b);
                    add(classes[c].after, a);
                }
            }
        }
        std::printf("%s: finishing the lightmaps took %.2f s unstitched; stitching added %.2f s\n",
                    job.scenePath.c_str(), finishSeconds, stitchSeconds);
        std::printf("%-22s %7s %9s %14s %14s\n", "seams", "count", "share", "jump before", "jump after");
        const double total = classes[0].before.weight;
        for (const Class& c : classes)
            std::printf("%-22s %7zu %8.1f%% %13.2f%% %13.2f%%\n", c.name, c.before.edges,
                        total > 0.0 ? 100.0 * c.before.weight / total : 0.0, 100.0 * mean(c.before),
                        100.0 * mean(c.after));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
