// How far the lightmap-lit image (lightmap/lightmap_image.h) is from the bake's own camera image,
// and what of it the lightmap's 8-bit RGBM accounts for. Bakes the scene (or a job file's
// first scene) in memory as `voxlight bake` does, then lights the first camera by its
// lightmaps twice: as scene.glb carries them (RGBM, what the bake writes) and as the float
// EXRs hold them. Relative RMSE (RMSE / mean, RGB pooled) against image.exr over two pixel
// sets: the bench's (pixels whose image stays at or below 5: emitters seen directly left out)
// and the unclipped ones (every channel of both images below 1: what an 8-bit view shows
// without clipping). An accuracy measurement, not a test.
//
//   build/accuracy/accuracy_lightmap_image SCENE.gltf|JOB.json [-o DIR] [name=value …]
//
// Bake settings as name=value (the bake's flags without --). With -o, writes image.exr and
// the two lightmap-lit images into DIR.
#include "accuracy_job.h"
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "lightmap/lightmap_image.h"
#include "core/error.h"
#include "core/image_io.h"
#include "metrics/metrics.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

using namespace vl;
namespace fs = std::filesystem;

namespace {

Image maskWhere(const Image& image, const Image& other, bool unclipped) {
    Image mask(image.width, image.height, 1, 1.0f);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float a = image.at(x, y, c), b = other.at(x, y, c);
                if (unclipped ? (a >= 1.0f || b >= 1.0f) : a > 5.0f) mask.at(x, y) = 0.0f;
            }
    return mask;
}

double share(const Image& mask) {
    double sum = 0.0;
    for (float v : mask.pixels) sum += v;
    return sum / double(mask.pixels.size());
}

void report(const char* name, const Image& test, const Image& image) {
    for (bool unclipped : {false, true}) {
        const Image mask = maskWhere(image, test, unclipped);
        MetricOptions options;
        options.mask = &mask;
        const ErrorMetrics e = compareImages(test, image, options);
        std::printf("%-34s %-10s %5.1f%% of pixels: relative RMSE %6.2f%%, means %.4f %.4f %.4f against %.4f %.4f %.4f\n",
                    name, unclipped ? "unclipped" : "bench", 100.0 * share(mask), 100.0 * e.relativeRmse, e.meanTest[0],
                    e.meanTest[1], e.meanTest[2], e.meanReference[0], e.meanReference[1], e.meanReference[2]);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SCENE.gltf|JOB.json [-o DIR] [name=value ...]\n", argv[0]);
        return 2;
    }
    try {
        const std::string input = argv[1];
        std::string outDir;
        SettingAssignments assignments;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "-o" && i + 1 < argc) {
                outDir = argv[++i];
                continue;
            }
            addAssignment(assignments, arg);
        }
        BakeJob job = accuracyJob(input, assignments);
        job.settings.quiet = true;
        job.settings.outputs.grids = false;

        // bake() with its scene kept: the lightmaps, the image, and the receivers' scene.
        Diagnostics diagnostics(false, false);
        Scene scene = loadJobScene(job);
        VoxelStages stages = bakeVoxelStages(scene, job.settings, diagnostics);
        const ReceiverGather gather = bakeReceiverGather(*stages.tracing, stages.indirect, job.settings, stages.onGpu);
        std::vector<ShippedLightmap> shipped, floats;
        for (const LightmapAtlas& atlas : buildLightmapReceivers(scene, stages.lightmap, diagnostics)) {
            const ReceiverLighting lit = gather.atlasRows(atlas, 0, atlas.receivers.height);
            const BakedLightmap lightmap =
                finishLightmap(atlas, lit.direct, lit.indirect, lit.open, scene, job.settings, lit.shadowmask);
            shipped.push_back({lightmap.meshes, shippedLightmapTexels(lightmap.total), shippedShadowmask(lightmap.shadowmask)});
            floats.push_back({lightmap.meshes, lightmap.total, lightmap.shadowmask});
            std::printf("lightmap '%s': %d x %d, %zu covered texels, %zu meshes\n", lightmap.name.c_str(),
                        lightmap.total.width, lightmap.total.height, lightmap.coveredTexels, lightmap.meshes.size());
        }
        const Camera camera = bakeCameras(scene, job.settings).front();
        const BakedImage image = bakeCameraImage(gather, *stages.tracing, camera, job.settings);
        const CameraModel model = makeCameraModel(camera, job.settings.imageWidth, job.settings.imageHeight);
        const ReceiverScene& tracing = *stages.tracing;
        const Image rgbm =
            bakeLightmapImage(tracing.traceScene, tracing.bvh, model, scene, tracing.triangles, job.settings, shipped);
        const Image linear =
            bakeLightmapImage(tracing.traceScene, tracing.bvh, model, scene, tracing.triangles, job.settings, floats);
        std::printf("%s, camera '%s', %d x %d, voxel size %.4g m\n", job.scenePath.c_str(), camera.name.c_str(),
                    image.beauty.width, image.beauty.height, stages.result.voxels.voxelSize);
        report("lightmap-lit (RGBM, as shipped)", rgbm, image.beauty);
        report("lightmap-lit (float lightmap)", linear, image.beauty);
        report("RGBM against float lightmap-lit", rgbm, linear);
        if (!outDir.empty()) {
            fs::create_directories(outDir);
            writeExr(image.beauty, (fs::path(outDir) / "image.exr").string());
            writeExr(rgbm, (fs::path(outDir) / "image_lightmapped.exr").string());
            writeExr(linear, (fs::path(outDir) / "image_lightmapped_float.exr").string());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
