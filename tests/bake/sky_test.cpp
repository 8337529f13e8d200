// A uniform sky (scene.h Sky) and a sun with a disk (Light::angularDiameter) in every stage: the path tracer's escaping paths, the
// receivers' direct term, the bounces' voxel light and the camera's background, against the
// closed form of an open floor and against Cycles on the open Cornell box of
// ../shared/reference (cornell_sky.gltf, world radiance (0.6, 0.75, 1.0)).
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "core/settings_table.h"
#include "lighting/direct_light.h"
#include "bake/job_file.h"
#include "receivers/receivers.h"
#include "core/error.h"
#include "core/image_io.h"
#include "metrics/metrics.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "tests/trace/pt_scenes.h"
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

PathTracerSettings quietPaths(int spp) {
    PathTracerSettings path;
    path.samplesPerPixel = spp;
    path.quiet = true;
    return path;
}

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
    const TraceFixture f(scene);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings.lightmap, diagnostics).at(0);
    const TraceResult traced = traceIrradiance(f.trace, f.bvh, atlas.receivers, quietPaths(4));
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

    // The default bake with the sky. Measured: lightmap 4.2%, indirect 6.0%, image 3.2%, every
    // mean within 0.1%.
    BakeSettings settings = quietSettings();
    settings.outputs.images = true;
    applySetting(bakeSettingsTable(), settings, "sky", "0.6,0.75,1.0");
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    REQUIRE(result.lightmaps.size() == 1);
    REQUIRE(result.images.size() == 1);
    // Over the texels the bake holds its own light in: Cycles holds black where the floor lies
    // under the boxes, and the bake fills those texels from their neighbours.
    MetricOptions baked = options;
    baked.testMask = &result.lightmaps[0].mask;
    const ErrorMetrics total = compareImages(result.lightmaps[0].total, reference, baked);
    const ErrorMetrics indirect = compareImages(result.lightmaps[0].indirect, referenceIndirect, baked);
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
    const TraceFixture f(scene);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings.lightmap, diagnostics).at(0);
    PathTracerSettings path = quietPaths(16);
    path.filter = PixelFilter::Box;
    const TraceResult lightmap = traceIrradiance(f.trace, f.bvh, atlas.receivers, path);
    const TraceResult render = renderCamera(f.trace, f.bvh, makeCameraModel(scene.cameras.at(0), 256, 256), path);
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
    std::ofstream(dir / "unknown.json") << R"({"sky": {"radiance": 1, "colour": "blue"}, "scenes": [{"path": "a.gltf"}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "unknown.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("unknown.json") && Catch::Contains("unknown key \"colour\""));
    BakeSettings settings;
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "sky", "1,2"), Catch::Contains("not R,G,B"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "sky", "nan"), Catch::Contains("sky"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "sky", "2e9"), Catch::Contains("at most 1e9"));
}

TEST_CASE("A sun with a disk: exact where wholly seen, its penumbra the disk's visible share", "[bake]") {
    // A sun straight overhead with a 10° disk over a floor, a ledge 0.5 m up over x < 0. A
    // floor point at x sees the part of the disk beyond the ledge's edge: at angular offset
    // x/h from the disk's centre (small angles: the cone is a flat disk of radius α = 5°),
    // the share of a disk on one side of a chord, (α² acos(d/α) − d√(α² − d²)) / (πα²).
    Scene scene;
    const int white = addLambert(scene, vec3(0.5f));
    addQuad(scene, "floor", white, vec3(-2, 0, -2), vec3(-2, 0, 2), vec3(2, 0, 2), vec3(2, 0, -2));
    addQuad(scene, "ledge", white, vec3(-2, 0.5f, -2), vec3(-2, 0.5f, 2), vec3(0, 0.5f, 2), vec3(0, 0.5f, -2));
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = vec3(0, -1, 0);
    sun.intensity = 10.0f;
    sun.angularDiameter = 10.0f * kPi / 180.0f;
    scene.lights.push_back(sun);
    const TraceFixture f(scene);
    const float alpha = 0.5f * sun.angularDiameter, h = 0.5f;
    const float whole = 10.0f * 0.5f * (1.0f + std::cos(alpha));  // E · the cone's mean cosine
    DirectLightSettings settings;
    double squares = 0.0, worstLit = 0.0, worstDark = 0.0;
    int penumbra = 0;
    for (int i = 0; i < 200; ++i) {
        SurfaceSample r;
        r.position = vec3(-0.1f + 0.2f * (i + 0.5f) / 200.0f, 0.0f, 0.3f * std::sin(float(i)));
        r.normal = vec3(0, 1, 0);
        r.triangle = 0;
        const float e = directIrradiance(f.trace.view(), f.bvh.view(), r, settings, uint64_t(i)).x;
        const double d = std::atan(double(r.position.x) / h);  // the edge's offset from the disk's centre
        double share;
        if (d >= alpha) share = 1.0;
        else if (d <= -alpha) share = 0.0;
        else {
            const double c = d;  // hidden: the disk's part beyond −d, a cap at distance d (signed)
            const double hidden = (alpha * alpha * std::acos(c / alpha) - c * std::sqrt(alpha * alpha - c * c)) /
                                  (M_PI * alpha * alpha);
            share = 1.0 - hidden;
        }
        if (share == 1.0) worstLit = std::max(worstLit, std::abs(double(e) - whole) / whole);
        else if (share == 0.0) worstDark = std::max(worstDark, double(e));
        else {
            squares += (e / whole - share) * (e / whole - share);
            ++penumbra;
        }
    }
    const double rms = std::sqrt(squares / penumbra);
    INFO(penumbra << " receivers in the penumbra: RMS error " << rms << " of the whole sun");
    REQUIRE(penumbra > 50);
    CHECK(rms < 0.05);
    CHECK(worstLit < 1e-5);
    CHECK(worstDark == 0.0);

    // The path tracer's mean at a wholly lit point: E · the cone's mean cosine, within its noise.
    const vec3 p(0.5f, 0.0f, 0.0f);
    Pcg32 rng(1, 2);
    double sum = 0.0;
    const int n = 4096;
    for (int k = 0; k < n; ++k) {
        vec2 u;
        rng.next2D(u.x, u.y);
        sum += punctualIrradiance(f.trace.view(), f.bvh.view(), p, vec3(0, 1, 0), vec3(0, 1, 0), u).x;
    }
    CHECK(sum / n == Approx(whole).epsilon(1e-4));
}

TEST_CASE("A job file's sun takes an angle in degrees, for directional lights only", "[bake]") {
    const fs::path dir = tempDir("job-sun");
    std::ofstream(dir / "job.json") << R"({"scenes": [{"path": "a.gltf", "lights": [
        {"type": "directional", "direction": [0, -1, 0], "intensity": 5, "angle": 0.526}]}]})";
    const std::vector<BakeJob> jobs = readJobFile((dir / "job.json").string(), BakeSettings{}, "output");
    REQUIRE(jobs.at(0).addedLights.size() == 1);
    CHECK(jobs[0].addedLights[0].angularDiameter == Approx(0.526 * M_PI / 180.0));
    std::ofstream(dir / "point.json") << R"({"scenes": [{"path": "a.gltf", "lights": [
        {"type": "point", "position": [0, 1, 0], "angle": 1}]}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "point.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("point.json") && Catch::Contains("lights[0]") && Catch::Contains("directional"));
    std::ofstream(dir / "wide.json") << R"({"scenes": [{"path": "a.gltf", "lights": [
        {"type": "directional", "direction": [0, -1, 0], "angle": 120}]}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "wide.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("wide.json") && Catch::Contains("0..90"));
}

TEST_CASE("A bake under a sky and a sun with a disk is the same at 1 and 2 threads", "[bake]") {
    // An open box lit by both: the sky's rays at the receivers, the gather points' openness,
    // the sun's per-voxel directions and its penumbra strata are all seeded per element.
    Scene scene;
    const int white = addLambert(scene, vec3(0.7f));
    addQuad(scene, "floor", white, vec3(0, 0, 0), vec3(0, 0, 1), vec3(1, 0, 1), vec3(1, 0, 0));
    addQuad(scene, "wall", white, vec3(0, 0, 0), vec3(1, 0, 0), vec3(1, 1, 0), vec3(0, 1, 0));
    addQuad(scene, "side", white, vec3(0, 0, 0), vec3(0, 1, 0), vec3(0, 1, 1), vec3(0, 0, 1));
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(vec3(-0.3f, -1.0f, -0.4f));
    sun.intensity = 5.0f;
    sun.angularDiameter = 0.1f;
    scene.lights.push_back(sun);
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = 32;
    settings.lightmap.width = settings.lightmap.height = 32;
    settings.sky = kSky;
    const BakeResult one = bakeOnThreads(scene, settings, 1), two = bakeOnThreads(scene, settings, 2);
    REQUIRE(one.lightmaps.size() == 1);
    REQUIRE(two.lightmaps.size() == 1);
    CHECK(one.lightmaps[0].total.pixels == two.lightmaps[0].total.pixels);
    CHECK(one.voxels.radiance == two.voxels.radiance);
    double indirect = 0.0;
    for (float v : one.lightmaps[0].indirect.pixels) indirect += v;
    CHECK(indirect > 0.0);  // the sky and sun did bounce
}

TEST_CASE("A light's bake mode: a job file's light gives its own, the light-bake setting the rest, bad modes refused",
          "[bake]") {
    const fs::path dir = tempDir("job-light-bake");
    std::ofstream(dir / "job.json") << R"({"settings": {"light-bake": "indirect"}, "scenes": [{"path": "a.gltf", "lights": [
        {"type": "directional", "direction": [0, -1, 0], "bake": "all"},
        {"type": "point", "position": [0, 1, 0]}]}]})";
    const std::vector<BakeJob> jobs = readJobFile((dir / "job.json").string(), BakeSettings{}, "output");
    REQUIRE(jobs.at(0).addedLights.size() == 2);
    CHECK(jobs[0].settings.lightBake == LightBake::Indirect);
    Scene scene;
    scene.lights = jobs[0].addedLights;
    scene.lights.push_back(Light{});  // a glTF light without a mode of its own
    resolveLightBake(scene, jobs[0].settings.lightBake);
    CHECK(scene.lights[0].bake == LightBake::All);  // its own wins
    CHECK(scene.lights[1].bake == LightBake::Indirect);
    CHECK(scene.lights[2].bake == LightBake::Indirect);

    std::ofstream(dir / "masked.json") << R"({"scenes": [{"path": "a.gltf", "lights": [
        {"type": "directional", "direction": [0, -1, 0], "bake": "shadowmask"}]}]})";
    const std::vector<BakeJob> masked = readJobFile((dir / "masked.json").string(), BakeSettings{}, "output");
    CHECK(masked.at(0).addedLights.at(0).bake == LightBake::Shadowmask);
    BakeSettings maskSetting;
    applySetting(bakeSettingsTable(), maskSetting, "light-bake", "shadowmask");
    CHECK(maskSetting.lightBake == LightBake::Shadowmask);

    std::ofstream(dir / "bad.json") << R"({"scenes": [{"path": "a.gltf", "lights": [
        {"type": "point", "position": [0, 1, 0], "bake": "shadow"}]}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "bad.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("bad.json") && Catch::Contains("lights[0].bake") && Catch::Contains("\"shadow\""));
    BakeSettings settings;
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "light-bake", "none"),
                      Catch::Contains("light-bake") && Catch::Contains("'none'") && Catch::Contains("all, indirect, shadowmask"));
}
