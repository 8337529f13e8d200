// A uniform sky (scene.h Sky) in every stage: the path tracer's escaping paths, the
// receivers' direct term, the bounces' voxel light and the camera's background, against the
// closed form of an open floor and against Cycles on the open Cornell box of
// ../shared/reference (cornell_sky.gltf, world radiance (0.6, 0.75, 1.0)).
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "bake/job_file.h"
#include "bake/receivers.h"
#include "core/error.h"
#include "core/image_io.h"
#include "metrics/metrics.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "support/skip.h"
#include "quad_scene.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

using namespace vl;
using namespace vl::test;
namespace fs = std::filesystem;

namespace {

const vec3 kSky(0.6f, 0.75f, 1.0f);

}  // namespace

TEST_CASE("A floor open to a uniform sky receives pi L: the bake's texels and the path tracer's are L", "[bake]") {
    // Nothing but the floor: every direction above it is sky, E = π·L exactly, texel E/π = L,
    // no indirect light (the floor sees nothing to reflect).
    Scene scene;
    const int white = addLambert(scene, vec3(0.8f));
    addQuad(scene, "floor", white, vec3(-1, 0, -1), vec3(-1, 0, 1), vec3(1, 0, 1), vec3(1, 0, -1));
    BakeSettings settings = quietSettings();
    settings.lightmap.width = settings.lightmap.height = 32;
    settings.voxel.resolution = 32;
    applySetting(bakeSettingsTable(), settings, "sky", "0.6,0.75,1.0");
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    REQUIRE(result.lightmaps.size() == 1);
    const BakedLightmap& lightmap = result.lightmaps[0];
    REQUIRE(lightmap.coveredTexels > 0);
    double worstDirect = 0.0, worstIndirect = 0.0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            if (lightmap.mask.at(x, y) < 0.5f) continue;
            for (int c = 0; c < 3; ++c) {
                worstDirect = std::max(worstDirect, double(std::abs(lightmap.direct.at(x, y, c) - kSky[c]) / kSky[c]));
                worstIndirect = std::max(worstIndirect, double(std::abs(lightmap.indirect.at(x, y, c))));
            }
        }
    CHECK(worstDirect < 1e-5);
    CHECK(worstIndirect < 1e-6);

    // The path tracer: every path's first bounce leaves the scene, exactly L.
    scene.sky.radiance = kSky;
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings.lightmap, diagnostics).at(0);
    PathTracerSettings path;
    path.samplesPerPixel = 4;
    path.quiet = true;
    const TraceResult traced = traceIrradiance(trace, bvh, atlas.receivers, path);
    double worstTraced = 0.0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x)
            if (atlas.receivers.covered(size_t(y) * 32 + size_t(x)))
                for (int c = 0; c < 3; ++c)
                    worstTraced = std::max(worstTraced, double(std::abs(traced.beauty.at(x, y, c) - kSky[c]) / kSky[c]));
    CHECK(worstTraced < 1e-5);
}

TEST_CASE("The open Cycles Cornell box under a uniform sky: the bake and the path tracer against Cycles", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string dir = sharedDir() + "/reference/";
    const std::string cycles = dir + "cycles/cornell_sky";
    LoadOptions load;
    load.echoWarnings = false;
    Scene scene = loadGltf(dir + "cornell_sky.gltf", load);
    const Image reference = readImage(cycles + "_lightmap_4096spp.exr");
    const Image referenceDirect = readImage(cycles + "_lightmap_direct_4096spp.exr");
    Image referenceIndirect = reference;
    for (size_t k = 0; k < referenceIndirect.pixels.size(); ++k) referenceIndirect.pixels[k] -= referenceDirect.pixels[k];
    const Image referenceRender = readImage(cycles + "_render_4096spp.exr");
    const Image mask = readImage(cycles + "_lightmap_mask.exr");
    MetricOptions options;
    options.mask = &mask;

    // The default bake with the sky. Measured (2026-11-27): lightmap 4.2%, indirect 6.0%,
    // image 3.2%, every mean within 0.1%.
    BakeSettings settings = quietSettings();
    settings.outputs.images = true;
    applySetting(bakeSettingsTable(), settings, "sky", "0.6,0.75,1.0");
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    REQUIRE(result.lightmaps.size() == 1);
    REQUIRE(result.images.size() == 1);
    const ErrorMetrics total = compareImages(result.lightmaps[0].total, reference, options);
    const ErrorMetrics indirect = compareImages(result.lightmaps[0].indirect, referenceIndirect, options);
    const ErrorMetrics image = compareImages(result.images[0].beauty, referenceRender, MetricOptions{});
    INFO("bake: lightmap " << total.relativeRmse << ", indirect " << indirect.relativeRmse << ", image "
                           << image.relativeRmse);
    CHECK(total.relativeRmse < 0.05);
    CHECK(indirect.relativeRmse < 0.08);
    CHECK(image.relativeRmse < 0.05);
    for (int c = 0; c < 3; ++c) {
        CHECK(total.meanTest[c] == Approx(total.meanReference[c]).epsilon(0.01));
        CHECK(indirect.meanTest[c] == Approx(indirect.meanReference[c]).epsilon(0.02));
        CHECK(image.meanTest[c] == Approx(image.meanReference[c]).epsilon(0.01));
    }
    // Pixels whose rays all leave the box show the sky itself, exactly.
    size_t skyPixels = 0, wrong = 0;
    const Image& beauty = result.images[0].beauty;
    for (int y = 0; y < beauty.height; ++y)
        for (int x = 0; x < beauty.width; ++x)
            if (result.images[0].albedo.rgb(x, y) == vec3(0.0f) &&
                glm::all(glm::lessThan(glm::abs(referenceRender.rgb(x, y) - kSky), vec3(1e-4f)))) {
                ++skyPixels;
                wrong += glm::all(glm::lessThan(glm::abs(beauty.rgb(x, y) - kSky), vec3(1e-6f))) ? 0 : 1;
            }
    CHECK(skyPixels > 100);
    CHECK(wrong == 0);

    // The path tracer's means within 1% of Cycles' (issue 16), lightmap and render.
    scene.sky.radiance = kSky;
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings.lightmap, diagnostics).at(0);
    PathTracerSettings path;
    path.samplesPerPixel = 16;
    path.quiet = true;
    path.filter = PixelFilter::Box;
    const TraceResult lightmap = traceIrradiance(trace, bvh, atlas.receivers, path);
    const TraceResult render = renderCamera(trace, bvh, makeCameraModel(scene.cameras.at(0), 256, 256), path);
    const ErrorMetrics tracedLightmap = compareImages(lightmap.beauty, reference, options);
    const ErrorMetrics tracedRender = compareImages(render.beauty, referenceRender, MetricOptions{});
    for (int c = 0; c < 3; ++c) {
        CHECK(tracedLightmap.meanTest[c] == Approx(tracedLightmap.meanReference[c]).epsilon(0.01));
        CHECK(tracedRender.meanTest[c] == Approx(tracedRender.meanReference[c]).epsilon(0.01));
    }
}

TEST_CASE("A sky is set globally or per scene in a job file and refused when malformed", "[bake]") {
    const fs::path dir = tempDir("job-sky");
    std::ofstream(dir / "job.json") << R"({"sky": {"radiance": [0.6, 0.75, 1.0]},
        "scenes": [{"path": "a.gltf"}, {"path": "b.gltf", "sky": {"radiance": 2}}, {"path": "c.gltf", "sky": {"radiance": 0}}]})";
    const std::vector<BakeJob> jobs = readJobFile((dir / "job.json").string(), BakeSettings{}, "output");
    REQUIRE(jobs.size() == 3);
    CHECK(jobs[0].settings.sky == kSky);
    CHECK(jobs[1].settings.sky == vec3(2.0f));
    CHECK(jobs[2].settings.sky == vec3(0.0f));

    std::ofstream(dir / "negative.json") << R"({"scenes": [{"path": "a.gltf", "sky": {"radiance": [1, -1, 1]}}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "negative.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("negative.json") && Catch::Contains("scenes[0].sky") &&
                          Catch::Contains("non-negative"));
    std::ofstream(dir / "shapeless.json") << R"({"sky": [1, 1, 1], "scenes": [{"path": "a.gltf"}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "shapeless.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("shapeless.json") && Catch::Contains("\"sky\" must be an object"));
    std::ofstream(dir / "unknown.json") << R"({"sky": {"radiance": 1, "image": "sky.hdr"}, "scenes": [{"path": "a.gltf"}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "unknown.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("unknown.json") && Catch::Contains("unknown key \"image\""));
    BakeSettings settings;
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "sky", "1,2"), Catch::Contains("not R,G,B"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "sky", "nan"), Catch::Contains("sky"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "sky", "2e9"), Catch::Contains("at most 1e9"));
}
