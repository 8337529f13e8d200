// An artist-made room against Cycles, through the lightmap as it ships: the view an engine
// shows (lightmap/lightmap_image.h) against a Cycles render of the same camera
// (tests/reference/grey-white-room, README there: 4 × 1024 spp, every material Lambert; and
// tests/reference/classroom).
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/bake_settings.h"
#include "bake/job_file.h"
#include "core/image_io.h"
#include "metrics/metrics.h"
#include "quad_scene.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

using namespace vl;
using namespace vl::test;

namespace {

// A job's first scene baked with its lightmap-lit view, against a Cycles render of that camera
// over the bench's pixels (the reference at or below 5 in every channel: lamps seen directly
// are left out).
ErrorMetrics lightmapLitAgainst(const std::string& job, const SettingAssignments& assignments, const std::string& render,
                                const std::string& scratch) {
    const std::vector<BakeJob> jobs = readJobFile(job, quietSettings(), tempDir(scratch), assignments);
    REQUIRE(jobs.size() == 1);
    BakeSettings settings = jobs[0].settings;
    settings.outputs.grids = settings.outputs.gltf = false;
    settings.outputs.lightmaps = settings.outputs.images = settings.outputs.lightmapImage = true;
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(loadJobScene(jobs[0]), settings, diagnostics);
    REQUIRE(!result.images.empty());
    const Image& lit = result.images[0].lightmapped;
    const Image reference = readImage(render);
    REQUIRE(lit.width == reference.width);
    REQUIRE(lit.height == reference.height);
    MetricOptions options;
    options.excludeReferenceAbove = 5.0f;
    const ErrorMetrics e = compareImages(lit, reference, options);
    INFO("lightmap-lit view " << e.relativeRmse << "; means " << e.meanTest[0] << " " << e.meanTest[1] << " " << e.meanTest[2]
                              << " against " << e.meanReference[0] << " " << e.meanReference[1] << " " << e.meanReference[2]);
    return e;
}

}  // namespace

TEST_CASE("The grey-white room's lightmap-lit view against Cycles: the transport alone, every material Lambert", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    // Cycles' own noise at 4096 spp is 3.4% per pixel. The view averages 4 × 4 reads a pixel,
    // as Cycles' 1-pixel box does (lightmap/lightmap_image.h). A lightmap whose every texel holds
    // the path tracer's light is itself far from Cycles at this atlas (docs/accuracy.md, the
    // floor); the bound sits just above what docs/accuracy.md measures, so a regression
    // shows. The means are within 1.25% per channel.
    const ErrorMetrics e = lightmapLitAgainst(sharedDir() + "/scenes/grey-white-room/grey_white_room.json", {{"materials", "lambert"}},
                                              sourceDir() + "/tests/reference/grey-white-room/grey_white_room_render_lambert_4096spp.exr",
                                              "gwr-cycles");
    INFO("lightmap-lit view " << e.relativeRmse);
    CHECK(e.relativeRmse < 0.165);
    for (int c = 0; c < 3; ++c) CHECK(e.meanTest[c] == Approx(e.meanReference[c]).epsilon(0.0125));
}

TEST_CASE("The classroom's lightmap-lit view against Cycles' render of its camera", "[bake]") {
    // tests/reference/classroom: Cycles 4 × 1024 spp of the bake's own scene.glb, the job's sky,
    // sun and one-sided lamps; 2.0% noise per pixel. Measured 7.1% (6.8% less that noise) with
    // the view's 4 × 4 reads a pixel; the bound is issue 34's goal of 8%, the means within 2%.
    const std::string dir = sourceDir() + "/tests/reference/classroom/";
    const ErrorMetrics e = lightmapLitAgainst(dir + "classroom_baked.json", {}, dir + "classroom_render_4096spp.exr", "classroom-render");
    INFO("lightmap-lit view " << e.relativeRmse);
    CHECK(e.relativeRmse < 0.08);
    for (int c = 0; c < 3; ++c) CHECK(e.meanTest[c] == Approx(e.meanReference[c]).epsilon(0.02));
}
