// The bake against Cycles, light leaking through thin walls, energy, determinism and bad
// input (issue 5).
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "core/settings_table.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/rng.h"
#include "export/lightmap_encoding.h"
#include "metrics/metrics.h"
#include "scene/gltf_loader.h"
#include "scene/gltf_model.h"
#include "support/paths.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <tuple>

using namespace vl;
using namespace vl::test;
namespace fs = std::filesystem;

namespace {

const BakedLightmap& lightmapNamed(const BakeResult& result, const std::string& name) {
    for (const BakedLightmap& l : result.lightmaps)
        if (l.name == name) return l;
    FAIL("no lightmap named " << name);
    return result.lightmaps.front();
}

// The mean over a lightmap's covered texels of (r + g + b) / 3 of `image` (its total by default).
double coveredMean(const BakedLightmap& l, const Image* image = nullptr) {
    const Image& values = image ? *image : l.total;
    double sum = 0.0;
    for (int y = 0; y < l.mask.height; ++y)
        for (int x = 0; x < l.mask.width; ++x)
            if (l.mask.at(x, y) > 0.5f) {
                const vec3 v = values.rgb(x, y);
                sum += (v.x + v.y + v.z) / 3.0;
            }
    // Buried texels (inside closed geometry: the ceiling over a lamp 1 cm under it) hold their
    // neighbours' light for the bilinear reads beside them; what reaches them is nothing.
    return l.coveredTexels ? sum / static_cast<double>(l.coveredTexels) : 0.0;
}

// A quick bake job of a scene file into `out` (emptied first): quiet, 32 voxels, the
// lightmaps alone.
BakeJob quickJob(const std::string& scene, const fs::path& out) {
    fs::remove_all(out);
    BakeJob job;
    job.scenePath = scene;
    job.outputDir = out.string();
    job.settings = quietSettings();
    job.settings.voxel.resolution = 32;
    return job;
}

// Two rooms [0,1]³ and [1+t, 2+t]×[0,1]² sharing a wall t thick, a point light in the first.
Scene twoRooms(float wallThickness) {
    Scene scene;
    scene.sourcePath = "two rooms (test)";
    const int white = addLambert(scene, vec3(0.8f));
    addRoom(scene, "lit/", white, vec3(0.0f), vec3(1.0f));
    addRoom(scene, "dark/", white, vec3(1.0f + wallThickness, 0.0f, 0.0f), vec3(2.0f + wallThickness, 1.0f, 1.0f));
    scene.lights.push_back(pointLightAt(vec3(0.5f, 0.7f, 0.5f), 1.0f));
    return scene;
}

}  // namespace

// Against the Cycles references (4096 spp, 64 bounces) of both Blender Cornell boxes at the
// default settings: lightmap total (covered texels), the indirect part alone (Cycles' total −
// direct: its converged path-traced indirect) and the camera image (the emitter, reference
// > 5, excluded), as relative RMSE. Earlier bounds and measurements: docs/accuracy.md.
TEST_CASE("The default bake of the Cycles Cornell boxes matches Cycles' lightmaps and renders", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string dir = sharedDir() + "/reference/";
    // Issue 13's bounds: lightmap total, indirect and camera image relative RMSE. Measured
    // (63 voxels from the free paths, gather level 2, gathering by rays): quad 2.70% / 5.20% /
    // 4.40% (direct 1.88%), point 2.69% / 5.35% / 3.97% (direct 1.09%).
    struct Bounds {
        const char* name;
        double total, indirect, image;
    };
    for (const Bounds& bound : {Bounds{"quad", 0.030, 0.07, 0.05}, Bounds{"point", 0.045, 0.09, 0.05}}) {
        const std::string name = bound.name;
        INFO("cornell_" << name);
        Scene scene = loadGltf(dir + "cornell_" + name + ".gltf");
        BakeSettings settings = quietSettings();
        settings.outputs.images = true;
        Diagnostics diagnostics;
        const BakeResult result = bake(scene, settings, diagnostics);
        REQUIRE(result.lightmaps.size() == 1);
        REQUIRE(result.images.size() == 1);
        const BakedLightmap& ours = result.lightmaps[0];

        const std::string cycles = dir + "cycles/cornell_" + name;
        const Image reference = readImage(cycles + "_lightmap_4096spp.exr");
        const Image referenceDirect = readImage(cycles + "_lightmap_direct_4096spp.exr");
        Image referenceIndirect = reference;
        for (size_t k = 0; k < referenceIndirect.pixels.size(); ++k)
            referenceIndirect.pixels[k] -= referenceDirect.pixels[k];
        const Image mask = readImage(cycles + "_lightmap_mask.exr");
        // Over the texels both bakes hold their own light in: under the boxes Cycles holds
        // black, and the bake fills those texels from their neighbours (docs/accuracy.md).
        MetricOptions options;
        options.mask = &mask;
        options.testMask = &ours.mask;
        const ErrorMetrics total = compareImages(ours.total, reference, options);
        const ErrorMetrics direct = compareImages(ours.direct, referenceDirect, options);
        const ErrorMetrics indirect = compareImages(ours.indirect, referenceIndirect, options);
        MetricOptions renderOptions;
        renderOptions.excludeReferenceAbove = 5.0f;
        const ErrorMetrics image =
            compareImages(result.images[0].beauty, readImage(cycles + "_render_4096spp.exr"), renderOptions);
        INFO("lightmap total relRMSE " << total.relativeRmse << ", direct " << direct.relativeRmse << ", indirect "
                                       << indirect.relativeRmse << ", image " << image.relativeRmse);
        // Direct light is exact up to the emitter's stratified penumbrae and Cycles' own noise
        // (Cycles' 1024-spp lightmap shows 2.2% against the same reference).
        CHECK(direct.relativeRmse < 0.03);
        for (int c = 0; c < 3; ++c) CHECK(direct.meanTest[c] == Approx(direct.meanReference[c]).epsilon(0.005));
        CHECK(total.relativeRmse < bound.total);
        CHECK(indirect.relativeRmse < bound.indirect);
        CHECK(image.relativeRmse < bound.image);
        for (int c = 0; c < 3; ++c) {
            CHECK(total.meanTest[c] == Approx(total.meanReference[c]).epsilon(0.05));
            CHECK(image.meanTest[c] == Approx(image.meanReference[c]).epsilon(0.05));
        }
    }
}

TEST_CASE("Light does not leak through a wall between a lit and a dark room", "[bake]") {
    constexpr float h = 1.0f / 32.0f;
    for (float thicknessInVoxels : {0.5f, 1.0f, 2.0f}) {
        const Scene scene = twoRooms(thicknessInVoxels * h);
        BakeSettings settings = quietSettings();
        settings.voxel.voxelSize = h;
        settings.lightmap.atlasPerMesh = true;
        settings.lightmap.width = settings.lightmap.height = 16;
        Diagnostics diagnostics(false, false);
        const BakeResult result = bake(scene, settings, diagnostics);
        // Issue 5's measure: the dark room's lightmap mean against the lit room's (every face
        // is 1 m², so the mean of the face means is the area mean). The brightest dark face
        // is printed too.
        double lit = 0.0, dark = 0.0, brightestDark = 0.0;
        for (const char* face : {"floor", "ceiling", "wall-x", "wall+x", "wall-z", "wall+z"}) {
            lit += coveredMean(lightmapNamed(result, std::string("lit/") + face)) / 6.0;
            const double d = coveredMean(lightmapNamed(result, std::string("dark/") + face));
            dark += d / 6.0;
            brightestDark = std::max(brightestDark, d);
        }
        WARN("wall " << thicknessInVoxels << " voxels: dark room / lit room mean = " << dark / lit
                     << ", brightest dark face / lit room mean = " << brightestDark / lit);
        REQUIRE(lit > 0.0);
        CHECK(dark < 0.01 * lit);
    }
}

TEST_CASE("Receivers that gather their own cones read every mip level when the bounces went by rays", "[bake]") {
    // The bounces by rays need level 0 of the mips alone; with gather level −1 every receiver
    // traces its own cones, which read the coarser levels too. Built without them, a cone
    // reads level 0 at every distance, and the lit room's indirect light came out 19% under the
    // gathered bake's (0.2% over with every level).
    const Scene scene = twoRooms(1.0f / 32.0f);
    BakeSettings settings = quietSettings();
    settings.voxel.voxelSize = 1.0 / 32.0;
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 16;
    settings.gather.visibility = GatherVisibility::Rays;
    Diagnostics diagnostics(false, false);
    const BakeResult gathered = bake(scene, settings, diagnostics);
    settings.gather.gatherLevel = -1;
    const BakeResult own = bake(scene, settings, diagnostics);
    CHECK(gathered.mips.levelCount() == 1);
    CHECK(own.mips.levelCount() > 3);
    double a = 0.0, b = 0.0;
    for (const char* face : {"floor", "ceiling", "wall-x", "wall+x", "wall-z", "wall+z"}) {
        const std::string name = std::string("lit/") + face;
        const auto indirectMean = [&](const BakeResult& r) {
            for (const BakedLightmap& lightmap : r.lightmaps)
                if (lightmap.name == name) {
                    double sum = 0.0;
                    for (float v : lightmap.indirect.pixels) sum += v;
                    return sum / double(lightmap.indirect.pixels.size());
                }
            FAIL("no lightmap " << name);
            return 0.0;
        };
        a += indirectMean(gathered);
        b += indirectMean(own);
    }
    INFO("the lit room's indirect light, gathered at points " << a << ", by each texel's cones " << b);
    REQUIRE(a > 0.0);
    CHECK(b == Approx(a).epsilon(0.1));
}

// scenes/two_rooms.gltf (make_scenes.cpp): two 3 × 2.5 × 3 m rooms of albedo 0.8 sharing a wall
// 10 cm thick, a 40 W point light in room A. Room B's truth is black.
BakeResult bakeTwoRooms(double voxelSize, int resolution, int lightmapSize) {
    const Scene scene = loadGltf(std::string(VOXLIGHT_SOURCE_DIR) + "/scenes/two_rooms.gltf");
    BakeSettings settings = quietSettings();
    settings.voxel.voxelSize = voxelSize;
    settings.voxel.resolution = resolution;
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = lightmapSize;
    Diagnostics diagnostics(false, false);
    return bake(scene, settings, diagnostics);
}

TEST_CASE("Light does not leak between the sealed bright rooms of scenes/two_rooms.gltf", "[bake]") {
    // Issue 13's measure at walls 0.5, 1 and 2 voxels thick: room B's mean lightmap value over
    // room A's (face means over the six faces each), held to the issue's 0.3%. Measured:
    // 0.04%, 0%, 0% gathering by rays (gather/ray_gather.h); by cones 0.10%, 0.18%, 0.41%, the
    // light entering through the coarse mip samples at the cones' far ends.
    for (const double voxelSize : {0.2, 0.1, 0.05}) {
        constexpr double bound = 0.003;
        const BakeResult result = bakeTwoRooms(voxelSize, 0, 32);
        double lit = 0.0, dark = 0.0;
        for (const BakedLightmap& l : result.lightmaps) (l.name[0] == 'A' ? lit : dark) += coveredMean(l) / 6.0;
        WARN("wall " << 0.1 / voxelSize << " voxels: room B / room A = " << dark / lit);
        REQUIRE(lit > 0.0);
        CHECK(dark < bound * lit);
    }
}

TEST_CASE("A texel where a wall meets the floor or ceiling gets the indirect light of the texels beside it",
          "[bake]") {
    // Indirect light varies over the distance to the surfaces that send it, so across a
    // wall's texels in room A it stays within a factor of two of the wall's mean. At 63 voxels
    // the rooms' floor and ceiling lie where a wall's edge texels sat inside their voxel
    // layer and got a tenth of their light or none (shade_element.h lookupCandidates): at
    // 128² per face the darkest texel of each wall was 0.001 of its mean.
    const BakeResult result = bakeTwoRooms(0.0, 64, 128);
    for (const BakedLightmap& l : result.lightmaps) {
        if (l.name[0] != 'A') continue;
        const double mean = coveredMean(l, &l.indirect);
        double darkest = mean;
        for (int y = 0; y < l.mask.height; ++y)
            for (int x = 0; x < l.mask.width; ++x)
                if (l.mask.at(x, y) > 0.5f) darkest = std::min<double>(darkest, l.indirect.at(x, y, 0));
        INFO(l.name << ": darkest texel " << darkest << ", mean " << mean);
        CHECK(darkest > 0.5 * mean);
    }
}

// A closed 1 m white box of albedo ρ (its six faces lightmapped per mesh) with a 0.2 m square
// emitter of radiance 1 facing down 1 cm under the ceiling, which is not baked.
constexpr float kWhiteBoxAlbedo = 0.7f;
constexpr double kWhiteBoxEmitted = kPi * 0.2 * 0.2;  // exitance π·L over 0.04 m²
Scene whiteBox(bool doubleSided = false) {
    Scene scene;
    scene.sourcePath = "white box (test)";
    const int white = addLambert(scene, vec3(kWhiteBoxAlbedo));
    scene.materials[size_t(white)].doubleSided = doubleSided;
    const int lamp = addLambert(scene, vec3(0.0f), vec3(1.0f));
    addRoom(scene, "box/", white, vec3(0.0f), vec3(1.0f));
    addQuad(scene, "lamp", lamp, vec3(0.4f, 0.99f, 0.4f), vec3(0.6f, 0.99f, 0.4f), vec3(0.6f, 0.99f, 0.6f),
            vec3(0.4f, 0.99f, 0.6f));
    scene.meshes.back().uv1.clear();  // emitters are not baked
    return scene;
}

// The indirect power a white box's lightmaps hold over what energy conservation gives it: Φρ
// for the first gather alone (bounces 0), Φρ/(1−ρ) for the whole series (with its tail).
double whiteBoxIndirectPowerRatio(const Scene& scene, int resolution, int lightmapSize, int bounces,
                                  bool ownFrame = true) {
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = resolution;
    settings.voxel.ownFrame = ownFrame;
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = lightmapSize;
    settings.gather.bounces = bounces;
    settings.gather.bounceTail = bounces > 1;
    // The near field traces a record's near hits on past their first bounce: the first gather
    // alone goes without it.
    if (bounces == 0) settings.gather.nearFieldVoxels = 0.0f;
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    double indirectPower = 0.0;  // Σ_faces mean(E/π)·π·area, every face 1 m²
    for (const BakedLightmap& l : result.lightmaps) indirectPower += coveredMean(l, &l.indirect) * kPi;
    const double rho = kWhiteBoxAlbedo;
    return indirectPower / (bounces == 0 ? kWhiteBoxEmitted * rho : kWhiteBoxEmitted * rho / (1.0 - rho));
}

TEST_CASE("A closed white box's indirect power stays near energy conservation at every alignment of its walls in "
          "the cells",
          "[bake]") {
    // Energy conservation: the emitted power Φ bounces with albedo ρ, so Σ over surfaces of
    // E_indirect·A is Φ·ρ/(1−ρ) when every bounce reaches some surface (the emitter's black
    // back takes a little: the exact value lies just under). E/π per texel, area-weighted.
    // The box is centred on a voxel corner, so with N = 41, 43, … 55 voxels across it its walls
    // fall in each of the 4 voxels of their level-2 gather cells twice over, and each surface
    // ends inside a cell in a strip 1 to 4 voxels wide. Measured (level 2): the series
    // 0.970–0.992 of the exact value, the first gather alone 0.985–0.986 of Φρ. The gather
    // points weigh by the surface they stand for (irradiance_cache.h, the points' mass), so
    // the bounces neither create nor lose energy by where the walls sit. The bounds are the
    // measurements with a point or two to spare; they are not a derived limit.
    const Scene scene = whiteBox();
    double lowest[2] = {1e9, 1e9}, highest[2] = {0.0, 0.0}, sum[2] = {0.0, 0.0};
    for (int resolution = 41; resolution <= 55; resolution += 2)
        for (int bounces : {0, 8}) {
            const double ratio = whiteBoxIndirectPowerRatio(scene, resolution, 16, bounces);
            WARN(resolution << " voxels, " << bounces << " bounces: indirect power " << ratio << " of exact");
            const int k = bounces == 0 ? 0 : 1;
            lowest[k] = std::min(lowest[k], ratio);
            highest[k] = std::max(highest[k], ratio);
            sum[k] += ratio / 8.0;
        }
    INFO("first gather " << lowest[0] << " … " << highest[0] << " (mean " << sum[0] << "), series " << lowest[1]
                         << " … " << highest[1] << " (mean " << sum[1] << ")");
    // Over the eight alignments the errors must not all lean one way (measured means 1.003 and
    // 0.992 at level 2): the emitter's black back takes a little, so the exact value lies just
    // under 1. The first gather: the lamp's two faces, 0.08 of the 6.08 m² that light lands on,
    // take about their share of it, so about 0.987 of Φρ reaches the walls. Its mean over the
    // alignments is held within 1.2% of that (docs/accuracy.md, "The filter's stop").
    CHECK(sum[0] == Approx(0.987).epsilon(0.012));
    CHECK(sum[1] < 1.01);
    CHECK(sum[1] > 0.98);
    CHECK(lowest[0] > 0.97);
    CHECK(highest[0] < 1.01);
    CHECK(lowest[1] > 0.95);
    CHECK(highest[1] < 1.04);
    CHECK(highest[1] - lowest[1] < 0.07);
}

TEST_CASE("A closed white box turned to any orientation keeps its indirect power", "[bake]") {
    // The same room as above, turned as a whole. Light does not care how a room is turned, so
    // the first gather must still hold Φρ (all light reflected once lands on some wall) and the
    // whole series Φρ/(1−ρ). By default the bake turns the grid with the room (scene/own_frame.h)
    // and the room bakes as it does unturned: measured 0.997–1.006, held to 0.98–1.02. On the
    // world's axes (grid-frame=world) every surface crosses the voxel axes at a slant; the
    // bounds there, 0.85–1.08, are the ones the axis-aligned room was held to at two of its grid
    // alignments before the gather points weighed by the surface they stand for; measured
    // 97.6–101.0% single-sided and 94.9–99.7% double-sided. How earlier gathers fared on
    // these turns: docs/accuracy.md.
    const glm::quat turns[] = {
        glm::angleAxis(glm::radians(30.0f), vec3(0.0f, 1.0f, 0.0f)),
        glm::angleAxis(glm::radians(45.0f), glm::normalize(vec3(1.0f, 1.0f, 0.0f))),
        glm::angleAxis(glm::radians(60.0f), glm::normalize(vec3(1.0f, 2.0f, 3.0f))),
        glm::angleAxis(glm::radians(20.0f), glm::normalize(vec3(-2.0f, 1.0f, 1.0f))),
    };
    for (const auto& [turn, doubleSided] : {std::pair{turns[0], false}, std::pair{turns[1], false}, std::pair{turns[2], false},
                                            std::pair{turns[3], false}, std::pair{turns[0], true}, std::pair{turns[2], true}}) {
        Scene scene = whiteBox(doubleSided);
        scene.sourcePath = "turned white box (test)";
        for (Mesh& mesh : scene.meshes) {
            for (vec3& p : mesh.positions) p = turn * (p - vec3(0.5f));
            for (vec3& n : mesh.normals) n = turn * n;
        }
        for (const bool ownFrame : {true, false})
            for (int bounces : {0, 8}) {
                const double ratio = whiteBoxIndirectPowerRatio(scene, 64, 32, bounces, ownFrame);
                INFO("turn (" << turn.w << ", " << turn.x << ", " << turn.y << ", " << turn.z << "), "
                              << (doubleSided ? "double-sided, " : "") << (ownFrame ? "own" : "world")
                              << " frame, " << bounces << " bounces: indirect power " << ratio << " of exact");
                CHECK(ratio > (ownFrame ? 0.98 : 0.85));
                CHECK(ratio < (ownFrame ? 1.02 : 1.08));
            }
    }
}

TEST_CASE("The bounce tail follows each room's own decay", "[bake]") {
    // Two closed rooms far apart, each with its own point light: a bright one (albedo 0.9)
    // whose light decays by about 0.9 a bounce and a darker one (albedo 0.7). After 8 bounces
    // plus the geometric tail each room must hold what 64 bounces without a tail hold (0.9^64
    // and 0.7^64 are below 0.2%: the series' limit). With one ratio for the whole scene (the
    // bright room's) the dark room's tail was taken at the bright room's rate: its indirect
    // light came out 7.4% high (2.060 against 1.918); with each face's own ratio it is exact
    // to 0.1%. The bright room's tail is 7.4% low either way (measured: 6.53 against 7.05):
    // its ratio after 8 bounces is still below the rate its light settles to, so its
    // bound is the looser one.
    Scene scene;
    scene.sourcePath = "two rooms, two decays (test)";
    const int bright = addLambert(scene, vec3(0.9f));
    const int dark = addLambert(scene, vec3(0.7f));
    addRoom(scene, "bright/", bright, vec3(0.0f), vec3(1.0f));
    addRoom(scene, "dark/", dark, vec3(3.0f, 0.0f, 0.0f), vec3(4.0f, 1.0f, 1.0f));
    scene.lights.push_back(pointLightAt(vec3(0.5f, 0.7f, 0.5f), 1.0f));
    scene.lights.push_back(pointLightAt(vec3(3.5f, 0.7f, 0.5f), 1.0f));
    auto roomIndirect = [&](int bounces, bool tail) {
        BakeSettings settings = quietSettings();
        settings.voxel.resolution = 64;
        settings.lightmap.atlasPerMesh = true;
        settings.lightmap.width = settings.lightmap.height = 16;
        settings.gather.bounces = bounces;
        settings.gather.bounceTail = tail;
        Diagnostics diagnostics(false, false);
        const BakeResult result = bake(scene, settings, diagnostics);
        std::array<double, 2> mean{0.0, 0.0};
        for (const BakedLightmap& l : result.lightmaps)
            mean[l.name.rfind("dark/", 0) == 0 ? 1 : 0] += coveredMean(l, &l.indirect) / 6.0;
        return mean;
    };
    const std::array<double, 2> tailed = roomIndirect(8, true), converged = roomIndirect(64, false);
    for (int room = 0; room < 2; ++room) {
        INFO((room ? "dark" : "bright") << " room: 8 bounces and the tail " << tailed[size_t(room)]
                                        << ", 64 bounces " << converged[size_t(room)]);
        CHECK(tailed[size_t(room)] == Approx(converged[size_t(room)]).epsilon(room ? 0.02 : 0.10));
    }
}

// The lightmaps and voxel light of a small bake of `scene`, at 1 and 2 threads, are the same.
static void checkSameAtOneAndTwoThreads(const Scene& scene) {
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = 32;
    settings.lightmap.width = settings.lightmap.height = 16;
    settings.lightmap.atlasPerMesh = true;
    const BakeResult one = bakeOnThreads(scene, settings, 1), two = bakeOnThreads(scene, settings, 2);
    REQUIRE(one.lightmaps.size() == two.lightmaps.size());
    for (size_t i = 0; i < one.lightmaps.size(); ++i) CHECK(one.lightmaps[i].total.pixels == two.lightmaps[i].total.pixels);
    CHECK(one.voxels.radiance == two.voxels.radiance);
}

TEST_CASE("A bake is the same at 1 and 2 threads", "[bake]") { checkSameAtOneAndTwoThreads(twoRooms(1.0f / 16.0f)); }

// A closed room 3 × 2.5 × 3 m (albedo 0.7) under 90 point lights scattered below its ceiling
// and a wall of 48 emissive panels (96 triangles), both past kLightTreeFrom: the scene of the
// many-lights tests below.
static Scene manyLightsRoom() {
    Scene scene;
    scene.sourcePath = "a room of many lights (test)";
    const int wall = addLambert(scene, vec3(0.7f));
    const int panel = addLambert(scene, vec3(0.0f), vec3(0.9f, 1.0f, 1.1f));
    addRoom(scene, "room/", wall, vec3(0.0f), vec3(3.0f, 2.5f, 3.0f));
    for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 6; ++b) {
            const float z = 0.3f + 0.3f * float(a), y = 0.6f + 0.3f * float(b);
            // On the wall at x = 0, 5 mm in, facing +X.
            addQuad(scene, "panel", panel, vec3(0.005f, y, z), vec3(0.005f, y + 0.2f, z), vec3(0.005f, y + 0.2f, z + 0.2f),
                    vec3(0.005f, y, z + 0.2f));
        }
    Pcg32 rng(31, 5);
    for (int i = 0; i < 90; ++i) {
        float x, y, z, w;
        rng.next2D(x, y);
        rng.next2D(z, w);
        scene.lights.push_back(pointLightAt(vec3(0.3f + 2.4f * x, 1.6f + 0.7f * y, 0.3f + 2.4f * z), 0.01f + 0.05f * w));
    }
    return scene;
}

TEST_CASE("A bake under many lights, by their trees, is the same at 1 and 2 threads", "[bake]") {
    checkSameAtOneAndTwoThreads(manyLightsRoom());
}

TEST_CASE("Many lights by their trees bake the light of every light visited: each wall's direct and indirect mean",
          "[bake]") {
    // The trees' estimates are unbiased, at the receivers, at the voxels' surface points and at
    // the records' hits (whose lights are taken there and taken out of the voxels they read), so
    // each wall's mean direct and indirect light must match the bake that visits every light
    // (many-lights each) to within the estimates' noise averaged over the wall: 2%. With the
    // emitters' tree left in the voxels' lights-only pass, the emitters' light was taken out of
    // every hit and never put back, and the indirect light came out low (docs/many-lights.md).
    const Scene scene = manyLightsRoom();
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = 32;
    settings.lightmap.width = settings.lightmap.height = 16;
    settings.lightmap.atlasPerMesh = true;
    Diagnostics diagnostics(false, false);
    const BakeResult trees = bake(scene, settings, diagnostics);
    settings.lightTrees = false;
    const BakeResult each = bake(scene, settings, diagnostics);
    REQUIRE(trees.lightmaps.size() == each.lightmaps.size());
    int walls = 0;
    for (size_t i = 0; i < trees.lightmaps.size(); ++i) {
        const BakedLightmap& t = trees.lightmaps[i];
        const BakedLightmap& e = each.lightmaps[i];
        if (t.name.rfind("room/", 0) != 0) continue;
        ++walls;
        const double direct = coveredMean(t, &t.direct), directEach = coveredMean(e, &e.direct);
        const double indirect = coveredMean(t, &t.indirect), indirectEach = coveredMean(e, &e.indirect);
        INFO(t.name << ": direct " << direct << " against " << directEach << ", indirect " << indirect << " against "
                    << indirectEach);
        CHECK(direct == Approx(directEach).epsilon(0.02));
        CHECK(indirect == Approx(indirectEach).epsilon(0.02));
    }
    CHECK(walls == 6);
}

TEST_CASE("A bake's files are the same bytes at 1 and 2 threads, run after run", "[bake]") {
    // nvpro's Cornell box: generated lightmap UVs (their orientations searched side by side),
    // lightmap and image EXRs and PNGs, grids.vdb and scene.glb. Only bake.json's timings and
    // peak memory may differ.
    VL_SKIP_WITHOUT_SHARED();
    const auto run = [&](int threads, const std::string& name) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        BakeJob job = quickJob(sharedDir() + "/scenes/cornellbox-nvpro/cornellBox.gltf", fs::path(tempDir("bytes")) / name);
        job.settings.outputs.images = true;
        job.settings.outputs.grids = true;
        const BakeReport report = runBake(job);
        INFO(report.error);
        REQUIRE(report.ok);
        return fs::path(job.outputDir);
    };
    const fs::path one = run(1, "one"), two = run(2, "two"), again = run(2, "again");
    const auto bytes = [](const fs::path& file) {
        std::ifstream in(file, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    size_t files = 0;
    for (const auto& entry : fs::directory_iterator(one)) {
        const std::string name = entry.path().filename().string();
        if (name == "bake.json") continue;
        INFO(name);
        ++files;
        CHECK(bytes(entry.path()) == bytes(two / name));
        CHECK(bytes(entry.path()) == bytes(again / name));
    }
    CHECK(files >= 12);  // lightmap ×5, image ×5, grids.vdb, scene.glb
}

TEST_CASE("A scene with no lights and no emitters bakes to black with a warning", "[bake]") {
    Scene scene = twoRooms(0.1f);
    scene.lights.clear();
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = 16;
    settings.lightmap.atlasPerMesh = true;
    settings.lightmap.width = settings.lightmap.height = 8;
    Diagnostics diagnostics(false, false);
    const BakeResult result = bake(scene, settings, diagnostics);
    REQUIRE(diagnostics.warnings().size() == 1);
    CHECK_THAT(diagnostics.warnings()[0], Catch::Contains("two rooms (test)") &&
                                              Catch::Contains("no lights, no emissive materials and no sky"));
    for (const BakedLightmap& l : result.lightmaps)
        for (float v : l.total.pixels) REQUIRE(v == 0.0f);
    settings.strict = true;
    Diagnostics strict(true, false);
    CHECK_THROWS_AS(bake(scene, settings, strict), InputError);
}

TEST_CASE("Absurd settings are refused before any work", "[bake]") {
    const Scene scene = twoRooms(0.1f);
    BakeSettings settings = quietSettings();
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "resolution", "0"),
                      Catch::Contains("resolution") && Catch::Contains("out of range"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "aperture", "-5"),
                      Catch::Contains("aperture") && Catch::Contains("out of range"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "cones", "many"), Catch::Contains("not an integer"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "colour", "1"), Catch::Contains("unknown setting"));
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "hit-light", "cones"),
                      Catch::Contains("hit-light") && Catch::Contains("'cones'") && Catch::Contains("voxels, exact"));

    // 10⁹ voxels along an axis: refused by the voxel count check, before voxelizing.
    settings.voxel.voxelSize = 1e-9;
    Diagnostics diagnostics(false, false);
    CHECK_THROWS_AS(bake(scene, settings, diagnostics), SettingsError);
    // Fine enough to pass the per-axis limit but far beyond this machine's memory.
    settings.voxel.voxelSize = 2.0 / 1.5e6;
    CHECK_THROWS_WITH(bake(scene, settings, diagnostics), Catch::Contains("memory") || Catch::Contains("absurd") ||
                                                              Catch::Contains("pieces"));
}

TEST_CASE("A scene too big for the machine is refused before voxelizing, naming the file and its triangles", "[bake]") {
    const Scene scene = twoRooms(0.1f);
    BakeSettings settings = quietSettings();
    settings.outputs.lightmaps = true;
    // Without voxels the estimate is the triangles', the lightmaps' and the images' alone.
    const double estimate = estimateBakeMemory(scene, settings, std::numeric_limits<double>::infinity());
    REQUIRE(estimate > 300.0 * double(scene.triangleCount()));
    CHECK_NOTHROW(checkSceneMemoryBudget(scene, settings, estimate * 1.01));
    CHECK_THROWS_AS(checkSceneMemoryBudget(scene, settings, estimate * 0.99), SettingsError);
    CHECK_THROWS_WITH(checkSceneMemoryBudget(scene, settings, estimate * 0.99),
                      Catch::Contains(scene.sourcePath) &&
                          Catch::Contains(std::to_string(scene.triangleCount()) + " triangles") &&
                          Catch::Contains("lightmap-res"));
    // Each triangle adds its share: twice the meshes, 300 bytes more per added triangle.
    Scene doubled = scene;
    doubled.meshes.insert(doubled.meshes.end(), scene.meshes.begin(), scene.meshes.end());
    CHECK(estimateBakeMemory(doubled, settings, std::numeric_limits<double>::infinity()) - estimate ==
          Approx(300.0 * double(scene.triangleCount())));
}

TEST_CASE("A failed bake leaves no output files and names the problem", "[bake]") {
    const fs::path out = fs::path(tempDir("bake-failure")) / "scene";
    fs::remove_all(out);
    BakeJob job;
    job.scenePath = (fs::path(tempDir("bake-failure")) / "missing.gltf").string();
    job.outputDir = out.string();
    job.settings = quietSettings();
    const BakeReport report = runBake(job);
    CHECK_FALSE(report.ok);
    CHECK_THAT(report.error, Catch::Contains("missing.gltf"));
    CHECK_FALSE(fs::exists(out));
    for (const auto& entry : fs::directory_iterator(out.parent_path()))
        CHECK(entry.path().filename().string().find(".partial") == std::string::npos);
}

TEST_CASE("A bake job writes every output, the report and nothing half-finished", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    const fs::path out = fs::path(tempDir("bake-job")) / "cornell";
    BakeJob job = quickJob(sourceDir() + "/scenes/cornell_box.gltf", out);
    job.settings.lightmap.width = job.settings.lightmap.height = 32;
    job.settings.outputs.grids = true;
    const BakeReport report = runBake(job);
    INFO(report.error);
    REQUIRE(report.ok);
    for (const char* file : {"lightmap.exr", "lightmap_direct.exr", "lightmap_indirect.exr", "lightmap_mask.exr",
                             "lightmap.png", "grids.vdb", "scene.glb", "bake.json"})
        CHECK(fs::exists(out / file));
    const Image total = readImage((out / "lightmap.exr").string());
    CHECK(total.width == 32);
    for (float v : total.pixels) REQUIRE(std::isfinite(v));
    for (const auto& entry : fs::directory_iterator(out.parent_path()))
        CHECK(entry.path().filename().string().find(".partial") == std::string::npos);
}

TEST_CASE("Job files set settings globally and per scene, under the command line's, and add lights", "[bake]") {
    const fs::path dir = tempDir("job-file");
    const fs::path path = dir / "job.json";
    {
        std::ofstream job(path);
        job << R"({"output": "out", "settings": {"resolution": 64, "cones": 6},
                  "scenes": [{"path": "a.gltf"},
                             {"path": "sub/b.gltf", "name": "bee", "settings": {"cones": 32, "images": false},
                              "lights": [{"type": "point", "name": "lamp", "position": [1, 2, 3], "intensity": 5}]}]})";
    }
    const std::vector<BakeJob> jobs = readJobFile(path.string(), BakeSettings{}, "output");
    REQUIRE(jobs.size() == 2);
    CHECK(jobs[0].scenePath == (dir / "a.gltf").string());
    CHECK(jobs[0].outputDir == (dir / "out" / "a").string());
    CHECK(jobs[0].settings.voxel.resolution == 64);
    CHECK(jobs[0].settings.gather.cone.coneCount == 6);
    CHECK(jobs[1].outputDir == (dir / "out" / "bee").string());
    CHECK(jobs[1].settings.gather.cone.coneCount == 32);
    CHECK(jobs[1].settings.voxel.resolution == 64);
    CHECK_FALSE(jobs[1].settings.outputs.images);
    REQUIRE(jobs[1].addedLights.size() == 1);
    CHECK(jobs[1].addedLights[0].position == vec3(1, 2, 3));
    CHECK(jobs[1].addedLights[0].intensity == 5.0f);

    // The command line's settings apply over the file's, global and per scene; the rest stay the file's.
    const std::vector<BakeJob> overridden = readJobFile(path.string(), BakeSettings{}, "output", {{"cones", "12"}});
    REQUIRE(overridden.size() == 2);
    CHECK(overridden[0].settings.gather.cone.coneCount == 12);
    CHECK(overridden[1].settings.gather.cone.coneCount == 12);
    CHECK(overridden[1].settings.voxel.resolution == 64);
    CHECK_FALSE(overridden[1].settings.outputs.images);
    CHECK_THROWS_WITH(readJobFile(path.string(), BakeSettings{}, "output", {{"cones", "many"}}), Catch::Contains("cones"));

    std::ofstream(dir / "bad.json") << R"({"scenes": [{"path": "a.gltf", "settings": {"cones": "x"}}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "bad.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("bad.json") && Catch::Contains("scenes[0]") && Catch::Contains("cones"));
    std::ofstream(dir / "mistyped.json") << R"({"scenes": [{"path": "a.gltf", "lights": [{"position": [0, 1, 0], "intensity": "bright"}]}]})";
    CHECK_THROWS_WITH(readJobFile((dir / "mistyped.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("mistyped.json") && Catch::Contains("scenes[0]") && Catch::Contains("number"));
    std::ofstream(dir / "broken.json") << "{ not json";
    CHECK_THROWS_WITH(readJobFile((dir / "broken.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("broken.json") && Catch::Contains("not valid JSON"));
}

TEST_CASE("Job files add cameras looking from a position at a target", "[bake]") {
    const fs::path dir = tempDir("job-cameras");
    const fs::path path = dir / "job.json";
    std::ofstream(path) << R"({"scenes": [{"path": "level.glb",
        "cameras": [{"name": "hall", "position": [1, 2, 3], "target": [1, 2, -1], "yfov": 0.5},
                    {"position": [0, 0, 0], "target": [3, 0, 4], "up": [0, 0, 1]}]}]})";
    const std::vector<BakeJob> jobs = readJobFile(path.string(), BakeSettings{}, "output");
    REQUIRE(jobs.size() == 1);
    REQUIRE(jobs[0].addedCameras.size() == 2);
    const Camera& hall = jobs[0].addedCameras[0];
    CHECK(hall.name == "hall");
    CHECK(hall.position == vec3(1, 2, 3));
    CHECK(hall.forward == vec3(0, 0, -1));
    CHECK(hall.up == vec3(0, 1, 0));
    CHECK(hall.yfov == 0.5f);
    // The second looks along (3, 0, 4)/5; its up is +Z made orthogonal to that (default yfov).
    const Camera& second = jobs[0].addedCameras[1];
    CHECK(second.forward.x == Approx(0.6f));
    CHECK(second.forward.z == Approx(0.8f));
    CHECK(glm::dot(second.up, second.forward) == Approx(0.0f).margin(1e-6));
    CHECK(glm::length(second.up) == Approx(1.0f));
    CHECK(second.up.z > 0.0f);
    CHECK(second.yfov == Camera{}.yfov);

    Scene scene;
    addJobLightsAndCameras(jobs[0], scene);
    CHECK(scene.cameras.size() == 2);

    const auto error = [&](const std::string& camera) {
        std::ofstream(dir / "bad.json") << R"({"scenes": [{"path": "a.gltf", "cameras": [)" + camera + "]}]}";
        try {
            readJobFile((dir / "bad.json").string(), BakeSettings{}, "output");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string where = (dir / "bad.json").string() + ": scenes[0].cameras[0]";
    CHECK_THAT(error(R"({"position": [0, 0, 0]})"), Catch::StartsWith(where) && Catch::Contains("needs a \"position\" and a \"target\""));
    CHECK_THAT(error(R"({"position": [1, 1, 1], "target": [1, 1, 1]})"), Catch::StartsWith(where) && Catch::Contains("target equals position"));
    CHECK_THAT(error(R"({"position": [0, 0, 0], "target": [0, 1, 0]})"), Catch::StartsWith(where) && Catch::Contains("parallel"));
    CHECK_THAT(error(R"({"position": [0, 0, 0], "target": [0, 0, 1], "yfov": 4})"), Catch::StartsWith(where) && Catch::Contains("yfov"));
    CHECK_THAT(error(R"({"position": [0, 0, 0], "target": [0, 0, 1], "yfov": "wide"})"), Catch::StartsWith(where) && Catch::Contains("yfov must be a number"));
    CHECK_THAT(error(R"({"position": [0, 0, 0], "target": [0, 0, 1], "fov": 1})"), Catch::StartsWith(where) && Catch::Contains("unknown key \"fov\""));
    CHECK_THAT(error(R"({"position": [0, "x", 0], "target": [0, 0, 1]})"), Catch::StartsWith(where) && Catch::Contains("position"));
}

namespace {

// What readJobFile throws (as E) for a job file with this text.
template <typename E>
std::string jobFileError(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
    try {
        readJobFile(path.string(), BakeSettings{}, "output");
    } catch (const E& e) {
        return e.what();
    }
    FAIL(path.filename().string() << " was accepted");
    return "";
}

std::string sceneWithAtlases(const std::string& atlases) {
    return R"({"scenes": [{"path": "a.gltf"}, {"path": "b.gltf", "atlases": )" + atlases + "}]}";
}

}  // namespace

TEST_CASE("Job files group meshes into atlases globally and per scene", "[bake]") {
    const fs::path dir = tempDir("job-atlases");
    const fs::path path = dir / "job.json";
    std::ofstream(path) << R"({"settings": {"lightmap-res": 128},
        "atlases": [{"name": "walls", "meshes": ["Floor", "BackWall"], "resolution": 512},
                    {"name": "blocks", "meshes": ["ShortBlock"]}],
        "scenes": [{"path": "a.gltf"},
                   {"path": "b.gltf", "atlases": [{"name": "props", "meshes": ["Chair", "Table/0"], "resolution": [1024, 256]}]},
                   {"path": "c.gltf", "atlases": []}]})";
    const std::vector<BakeJob> jobs = readJobFile(path.string(), BakeSettings{}, "output");
    REQUIRE(jobs.size() == 3);
    const std::vector<AtlasGroup>& global = jobs[0].settings.lightmap.atlases;
    REQUIRE(global.size() == 2);
    CHECK(global[0].name == "walls");
    CHECK(global[0].meshes == std::vector<std::string>{"Floor", "BackWall"});
    CHECK(global[0].width == 512);
    CHECK(global[0].height == 512);
    CHECK(global[0].origin == path.string() + ": atlases[0]");
    CHECK(global[1].name == "blocks");
    CHECK(global[1].width == 0);  // lightmap-res, 128 here
    CHECK(jobs[0].settings.lightmap.width == 128);
    const std::vector<AtlasGroup>& own = jobs[1].settings.lightmap.atlases;
    REQUIRE(own.size() == 1);  // replaces the global list
    CHECK(own[0].name == "props");
    CHECK(own[0].meshes == std::vector<std::string>{"Chair", "Table/0"});
    CHECK(own[0].width == 1024);
    CHECK(own[0].height == 256);
    CHECK(own[0].origin == path.string() + ": scenes[1].atlases[0]");
    CHECK(jobs[2].settings.lightmap.atlases.empty());

    // Each mistake names the file and the element: "<file>: <element>…".
    const auto at = [&](const std::string& file, const std::string& element) {
        return Catch::Contains((dir / file).string() + ": " + element);
    };
    const std::vector<std::pair<std::string, std::string>> wrongTypes = {
        {R"({"name": "walls"})", "scenes[1].atlases must be an array"},
        {R"(["walls"])", "scenes[1].atlases[0] must be an object"},
        {R"([{"meshes": ["Floor"]}])", "scenes[1].atlases[0] needs a \"name\" string"},
        {R"([{"name": 7, "meshes": ["Floor"]}])", "scenes[1].atlases[0] needs a \"name\" string"},
        {R"([{"name": "walls", "meshes": "Floor"}])", "scenes[1].atlases[0] needs a \"meshes\" array"},
        {R"([{"name": "walls", "meshes": ["Floor", 3]}])", "scenes[1].atlases[0].meshes: 3"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": "512"}])", "scenes[1].atlases[0].resolution"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": 512.5}])", "scenes[1].atlases[0].resolution"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": [512]}])", "scenes[1].atlases[0].resolution"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": [512, "x"]}])", "scenes[1].atlases[0].resolution"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolutoin": 512}])", "scenes[1].atlases[0]: unknown key \"resolutoin\""},
    };
    for (size_t i = 0; i < wrongTypes.size(); ++i) {
        const std::string file = "mistyped" + std::to_string(i) + ".json";
        CHECK_THAT(jobFileError<InputError>(dir / file, sceneWithAtlases(wrongTypes[i].first)), at(file, wrongTypes[i].second));
    }
    CHECK_THAT(jobFileError<InputError>(dir / "global.json", R"({"atlases": [1], "scenes": [{"path": "a.gltf"}]})"),
               at("global.json", "atlases[0] must be an object"));

    const std::vector<std::pair<std::string, std::string>> badValues = {
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": 0}])", "scenes[1].atlases[0].resolution 0 is outside 1..16384"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": 16385}])", "scenes[1].atlases[0].resolution 16385 is outside"},
        {R"([{"name": "walls", "meshes": ["Floor"], "resolution": [512, -2]}])",
         "scenes[1].atlases[0].resolution [512,-2] is outside"},
        {R"([{"name": "walls", "meshes": []}])", "scenes[1].atlases[0]: atlas 'walls': names no meshes"},
        {R"([{"name": "my walls", "meshes": ["Floor"]}])", "scenes[1].atlases[0]: atlas 'my walls': an atlas name must"},
        {R"([{"name": "walls", "meshes": ["Floor"]}, {"name": "walls", "meshes": ["Back"]}])",
         "scenes[1].atlases[1]: atlas 'walls': the name is taken"},
        {R"([{"name": "walls", "meshes": ["Floor"]}, {"name": "floor", "meshes": ["Floor"]}])",
         "scenes[1].atlases[1]: atlas 'floor': mesh 'Floor' is already in atlas 'walls'"},
    };
    for (size_t i = 0; i < badValues.size(); ++i) {
        const std::string file = "refused" + std::to_string(i) + ".json";
        CHECK_THAT(jobFileError<SettingsError>(dir / file, sceneWithAtlases(badValues[i].first)), at(file, badValues[i].second));
    }
}

TEST_CASE("Job files refuse every key they do not know, naming the file, the place and the closest key", "[bake]") {
    const fs::path dir = tempDir("job-unknown-keys");
    const fs::path path = dir / "job.json";
    const std::string file = path.string();
    // The two a new user met, once baked without complaint (and without a sky).
    CHECK(jobFileError<InputError>(path, R"({"lihgts": [], "scenes": [{"path": "a.gltf"}]})") ==
          file + R"(: unknown key "lihgts" at the top level (did you mean "lights"? "lights" is a key of each scene: it goes in a scene of "scenes"))");
    CHECK(jobFileError<InputError>(path, R"({"scenes": [{"path": "a.gltf", "skyy": {"radiance": 1}}]})") ==
          file + R"(: scenes[0]: unknown key "skyy" (did you mean "sky"?))");

    // Every object the reader takes: the top level, a scene, its settings (the bake settings
    // table), sky, atlas groups, lights and cameras, globally and per scene where both are.
    const auto inScene = [](const std::string& fields) {
        return R"({"scenes": [{"path": "a.gltf"}, {"path": "b.gltf", )" + fields + "}]}";
    };
    const std::vector<std::pair<std::string, std::string>> inputErrors = {
        {R"({"scene": [{"path": "a.gltf"}]})", R"(: unknown key "scene" at the top level (did you mean "scenes"?))"},
        {R"({"outptu": "out", "scenes": [{"path": "a.gltf"}]})",
         R"(: unknown key "outptu" at the top level (did you mean "output"?))"},
        {R"({"cones": 6, "scenes": [{"path": "a.gltf"}]})",
         R"(: unknown key "cones" at the top level ("cones" is a bake setting: it goes in "settings"))"},
        {R"({"lights": [], "scenes": [{"path": "a.gltf"}]})",
         R"(: unknown key "lights" at the top level ("lights" is a key of each scene: it goes in a scene of "scenes"))"},
        {R"({"version": 2, "scenes": [{"path": "a.gltf"}]})",
         R"(: unknown key "version" at the top level (known: output, settings, atlases, sky, scenes))"},
        {inScene(R"("lihgts": [])"), R"(: scenes[1]: unknown key "lihgts" (did you mean "lights"?))"},
        {inScene(R"("cones": 6)"), R"(: scenes[1]: unknown key "cones" ("cones" is a bake setting: it goes in "settings"))"},
        {inScene(R"("lightmap_res": 512)"),
         R"(: scenes[1]: unknown key "lightmap_res" (did you mean "lightmap-res"? "lightmap-res" is a bake setting: it goes in "settings"))"},
        {R"({"sky": {"radience": 1}, "scenes": [{"path": "a.gltf"}]})", R"(: sky: unknown key "radience" (did you mean "radiance"?))"},
        {inScene(R"("sky": {"radiance": 1, "colour": "blue"})"),
         R"(: scenes[1].sky: unknown key "colour" (known: radiance, image, rotation, intensity))"},
        {R"({"atlases": [{"name": "walls", "mesh": ["Floor"]}], "scenes": [{"path": "a.gltf"}]})",
         R"(: atlases[0]: unknown key "mesh" (did you mean "meshes"?))"},
        {inScene(R"("atlases": [{"name": "walls", "meshes": ["Floor"], "res": 512}])"),
         R"(: scenes[1].atlases[0]: unknown key "res" (known: name, meshes, resolution))"},
        {inScene(R"("lights": [{"type": "point", "position": [0, 1, 0]}, {"type": "point", "position": [0, 1, 0], "colour": [1, 1, 1]}])"),
         R"(: scenes[1].lights[1]: unknown key "colour" (did you mean "color"?))"},
        {inScene(R"("lights": [{"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "innerConeAngel": 0.1}])"),
         R"(: scenes[1].lights[0]: unknown key "innerConeAngel" (did you mean "innerConeAngle"?))"},
        {inScene(R"("cameras": [{"position": [0, 0, 0], "target": [0, 0, 1], "fov": 1}])"),
         R"(: scenes[1].cameras[0]: unknown key "fov" (did you mean "yfov"?))"},
        // A key of another type's light is read by none: refused, not left out.
        {inScene(R"("lights": [{"position": [0, 1, 0], "direction": [0, -1, 0]}])"),
         R"(: scenes[1].lights[0]: "direction" is for spot and directional lights, not a point light (the default: give a "type"))"},
        {inScene(R"("lights": [{"type": "directional", "direction": [0, -1, 0], "position": [0, 1, 0]}])"),
         R"(: scenes[1].lights[0]: "position" is for point and spot lights, not a directional light)"},
        {inScene(R"("lights": [{"type": "point", "position": [0, 1, 0], "outerConeAngle": 0.5}])"),
         R"(: scenes[1].lights[0]: "outerConeAngle" is for spot lights, not a point light)"},
    };
    for (const auto& [text, message] : inputErrors) {
        INFO(text);
        CHECK(jobFileError<InputError>(path, text) == file + message);
    }
    // In "settings" the keys are the bake settings, looked up in their one table.
    const std::vector<std::pair<std::string, std::string>> settingsErrors = {
        {inScene(R"("settings": {"cone": 6})"), R"(: scenes[1].settings: unknown key "cone" (did you mean "cones"?))"},
        {R"({"settings": {"lightmap_res": 512}, "scenes": [{"path": "a.gltf"}]})",
         R"(: settings: unknown key "lightmap_res" (did you mean "lightmap-res"?))"},
        {R"({"settings": {"lights": []}, "scenes": [{"path": "a.gltf"}]})",
         R"(: settings: unknown key "lights" ("lights" is a key of each scene: it goes in a scene of "scenes"))"},
        {inScene(R"("settings": {"atlases": []})"),
         R"(: scenes[1].settings: unknown key "atlases" ("atlases" is a job-file key, not a bake setting: it goes beside "settings"))"},
    };
    for (const auto& [text, message] : settingsErrors) {
        INFO(text);
        CHECK(jobFileError<SettingsError>(path, text) == file + message);
    }
    // Flags and bench specs share the lookup and its suggestion.
    BakeSettings settings;
    CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "cone", "6"),
                      "unknown setting 'cone' (did you mean 'cones'?)");
    CHECK(closestName("Sky", {"output", "sky"}) == "sky");
    CHECK(closestName("colour", {"name", "color"}) == "color");
    CHECK(closestName("brightness", {"name", "color", "intensity"}).empty());

    // A job using every key still reads, each where it belongs.
    std::ofstream(path) << R"({"output": "out", "settings": {"cones": 6}, "sky": {"radiance": 0.5},
        "atlases": [{"name": "walls", "meshes": ["Floor"], "resolution": 64}],
        "scenes": [{"path": "a.gltf", "name": "first", "settings": {"images": false},
                    "sky": {"image": "noon.exr", "rotation": 30, "intensity": 2},
                    "atlases": [{"name": "props", "meshes": ["Chair"]}],
                    "lights": [{"name": "lamp", "type": "point", "color": [1, 1, 1], "intensity": 5, "range": 4, "position": [0, 1, 0]},
                               {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "innerConeAngle": 0.2, "outerConeAngle": 0.6},
                               {"type": "directional", "direction": [0, -1, 0], "angle": 0.53}],
                    "cameras": [{"name": "hall", "position": [0, 1, 4], "target": [0, 1, 0], "up": [0, 1, 0], "yfov": 0.8}]},
                   {"path": "b.gltf", "output": "levels/b"}]})";
    const std::vector<BakeJob> jobs = readJobFile(file, BakeSettings{}, "output");
    REQUIRE(jobs.size() == 2);
    CHECK(jobs[0].outputDir == (dir / "out" / "first").string());
    CHECK(jobs[0].addedLights.size() == 3);
    CHECK(jobs[0].addedCameras.size() == 1);
    CHECK(jobs[1].outputDir == (dir / "out" / "levels" / "b").string());

    // The command's -o wins over the file's "output", as its settings win over the file's;
    // the scenes keep their folders inside it.
    const std::string elsewhere = (dir / "elsewhere").string();
    const std::vector<BakeJob> moved = readJobFile(file, BakeSettings{}, "output", {}, elsewhere);
    REQUIRE(moved.size() == 2);
    CHECK(moved[0].outputDir == (dir / "elsewhere" / "first").string());
    CHECK(moved[1].outputDir == (dir / "elsewhere" / "levels" / "b").string());
}

TEST_CASE("A job file's scene name is one folder's name, and each scene's bake stays inside the output folder", "[bake]") {
    const fs::path dir = tempDir("job-scene-folders");
    const fs::path path = dir / "job.json";
    const std::string file = path.string();
    const auto job = [](const std::string& fields) {
        return R"({"output": "out", "scenes": [{"path": "a.gltf"}, {"path": "b.gltf", )" + fields + "}]}";
    };
    // The new user's name, whose bake once landed two folders above the output folder.
    CHECK(jobFileError<InputError>(path, job(R"("name": "../../escaped")")) ==
          file + R"(: scenes[1]: "name": "../../escaped" is not a folder name (it holds "/"): a scene bakes into the folder of its name, inside the job's output folder)");
    const std::vector<std::pair<std::string, std::string>> names = {
        {R"("..")", R"(".." leads out of the output folder)"},
        {R"(".")", R"("." is the output folder itself)"},
        {R"("")", "it is empty"},
        {R"("levels/e1m1")", R"(it holds "/")"},
        {R"("/tmp")", R"(it holds "/")"},
        {R"("..\\escaped")", R"(it holds "\")"},
        {R"("C:\\bakes")", R"(it holds "\")"},
        {R"("tab\there")", "it holds a control character"},
        {R"("line\nbreak")", "it holds a control character"},
        {R"("bell\u0007")", "it holds a control character"},
        {R"("nul\u0000")", "it holds a control character"},
        {R"("del\u007f")", "it holds a control character"},
        // What voxlight writes beside a scene's folder, and a cluster bake's work folder.
        {R"("a.lock")", R"(a bake of <folder> is locked with "<folder>.lock")"},
        {R"("a.partial-4242")", R"(a bake of <folder> is staged in "<folder>.partial-…")"},
        {R"(".voxlight-slurm")", R"(a cluster bake keeps its work in ".voxlight-slurm")"},
    };
    for (const auto& [name, fault] : names) {
        INFO(name);
        CHECK(jobFileError<InputError>(path, job(R"("name": )" + name)) ==
              file + ": scenes[1]: \"name\": " + nlohmann::json::parse(name).dump() + " is not a folder name (" + fault +
                  "): a scene bakes into the folder of its name, inside the job's output folder");
    }
    CHECK(jobFileError<InputError>(path, job(R"("name": 7)")) ==
          file + R"(: scenes[1]: "name" must be a string, the name of the folder the scene bakes into)");
    // A name taken from the scene's file is held to the same.
    CHECK(jobFileError<InputError>(path, R"({"scenes": [{"path": "/tmp/.."}]})") ==
          file + R"(: scenes[0]: its path gives the folder name "..", which is not one (".." leads out of the output folder): give the scene a "name")");
    CHECK(jobFileError<InputError>(path, R"({"scenes": [{"path": "levels/"}]})") ==
          file + R"(: scenes[0]: its path gives the folder name "", which is not one (it is empty): give the scene a "name")");

    // A scene's "output" is a relative path inside the output folder.
    const std::vector<std::pair<std::string, std::string>> outputs = {
        {R"("../x")", R"(".." leads out of it)"},
        {R"("levels/../../x")", R"(".." leads out of it)"},
        {R"("/tmp/x")", "it is an absolute path"},
        {R"("levels\\x")", R"(it holds "\")"},
        {R"("levels//x")", R"(it has an empty or "." part)"},
        {R"("")", "it is empty"},
        {R"("a\u0001")", "it holds a control character"},
        {"5", "not a string"},
        {R"(".voxlight-slurm/b")", R"(a cluster bake keeps its work in ".voxlight-slurm")"},
        {R"("levels/b.lock")", R"(a bake of <folder> is locked with "<folder>.lock")"},
    };
    for (const auto& [output, fault] : outputs) {
        INFO(output);
        CHECK(jobFileError<InputError>(path, job(R"("output": )" + output)) ==
              file + ": scenes[1]: \"output\": " + nlohmann::json::parse(output).dump() +
                  " is not a folder inside the job's output folder (" + fault + ")");
    }
    CHECK(jobFileError<InputError>(path, job(R"("name": "b", "output": "levels/b")")) ==
          file + R"(: scenes[1]: "name" and "output" both give the scene's folder: keep one)");

    // Two scenes never share a folder (the second would overwrite the first).
    CHECK(jobFileError<InputError>(path, R"({"scenes": [{"path": "a.gltf"}, {"path": "sub/a.gltf"}]})") ==
          file + R"(: scenes[1]: bakes into output/a, as scenes[0] does: give one of them another "name")");
    CHECK(jobFileError<InputError>(path, job(R"("output": "a/")")) ==
          file + ": scenes[1]: bakes into " + (dir / "out" / "a").string() + ", as scenes[0] does: give one of them another \"name\"");
    // Nor one inside another's: their files would mix.
    CHECK(jobFileError<InputError>(path, job(R"("output": "a/b")")) ==
          file + ": scenes[1]: its folder " + (dir / "out" / "a" / "b").string() + " and the folder of scenes[0], " +
              (dir / "out" / "a").string() + ", lie one inside the other: keep them apart");
    CHECK(jobFileError<InputError>(path, R"({"output": "out", "scenes": [{"path": "a.gltf", "output": "levels/a"},
                                                                         {"path": "levels.gltf"}]})") ==
          file + ": scenes[1]: its folder " + (dir / "out" / "levels").string() + " and the folder of scenes[0], " +
              (dir / "out" / "levels" / "a").string() + ", lie one inside the other: keep them apart");
    // Names that only look alike are apart.
    std::ofstream(path) << R"({"output": "out", "scenes": [{"path": "a.gltf"}, {"path": "b.gltf", "name": "ab"},
                                                            {"path": "c.gltf", "output": "a-levels/c"}, {"path": "a.lock.d.gltf"}]})";
    CHECK(readJobFile(file, BakeSettings{}, "output").size() == 4);

    // Links resolved: a folder that leads out through a link is refused; an output folder
    // that is itself a link holds its scenes.
    fs::remove_all(dir / "out");
    fs::remove_all(dir / "elsewhere");
    fs::create_directories(dir / "out");
    fs::create_directories(dir / "elsewhere");
    fs::create_directory_symlink(dir / "elsewhere", dir / "out" / "link");
    const fs::path root = fs::weakly_canonical(dir / "out");
    CHECK(jobFileError<InputError>(path, job(R"("name": "link")")) ==
          file + ": scenes[1]: its folder " + (dir / "out" / "link").string() + " resolves to " +
              fs::weakly_canonical(dir / "elsewhere").string() + ", outside the job's output folder " + root.string());
    CHECK(jobFileError<InputError>(path, job(R"("output": "link/b")")) ==
          file + ": scenes[1]: its folder " + (dir / "out" / "link" / "b").string() + " resolves to " +
              (fs::weakly_canonical(dir / "elsewhere") / "b").string() + ", outside the job's output folder " + root.string());
    fs::remove(dir / "linked-out");
    fs::create_directory_symlink(dir / "out", dir / "linked-out");
    std::ofstream(path) << R"({"output": "linked-out", "scenes": [{"path": "a.gltf"}, {"path": "b.gltf", "output": "levels/b"}]})";
    const std::vector<BakeJob> jobs = readJobFile(file, BakeSettings{}, "output");
    REQUIRE(jobs.size() == 2);
    CHECK(jobs[0].outputDir == (dir / "linked-out" / "a").string());
    CHECK(jobs[1].outputDir == (dir / "linked-out" / "levels" / "b").string());
    CHECK_FALSE(fs::exists(dir / "out" / "a"));  // read, nothing written
}

TEST_CASE("Every job file in the repository and in ../shared reads", "[bake]") {
    std::vector<fs::path> roots = {sourceDir() + "/scenes", sourceDir() + "/tools/bench", sourceDir() + "/tests"};
    if (haveShared()) roots.push_back(sharedDir() + "/scenes");
    size_t read = 0;
    for (const fs::path& root : roots)
        for (const auto& entry : fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied)) {
            if (!entry.is_regular_file() || entry.path().extension() != ".json") continue;
            // A job file: an object whose "scenes" are objects with a "path".
            std::ifstream in(entry.path());
            const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
            if (!j.is_object() || !j.contains("scenes") || !j["scenes"].is_array() || j["scenes"].empty()) continue;
            const nlohmann::json& scenes = j["scenes"];
            if (!std::all_of(scenes.begin(), scenes.end(), [](const nlohmann::json& s) { return s.is_object() && s.contains("path"); }))
                continue;
            INFO(entry.path().string());
            CHECK_NOTHROW(readJobFile(entry.path().string(), BakeSettings{}, tempDir("job-files-read")));
            ++read;
        }
    CHECK(read >= 4);  // scenes/classroom.json, tools/bench/zdm2.json and library20.json, the classroom reference
}

TEST_CASE("voxlight bake refuses a bad job file before it bakes anything, locally and for a cluster", "[bake]") {
    const std::string voxlight = std::string(VOXLIGHT_BINARY_DIR) + "/voxlight";
    if (!fs::exists(voxlight)) VL_SKIP(voxlight << " is not built");
    const fs::path dir = tempDir("job-refused-bake");
    const fs::path out = dir / "out";
    const fs::path escaped = dir.parent_path() / "escaped";  // where "../../escaped" leads from out/<name>
    const std::string box = sourceDir() + "/scenes/cornell_box.gltf";
    // `voxlight bake <arguments> -o out`: its exit status and what it printed.
    const auto bake = [&](const std::string& arguments) {
        fs::remove_all(out);
        fs::remove_all(escaped);
        const fs::path log = dir / "log.txt";
        const std::string command =
            voxlight + " bake -q " + arguments + " -o " + out.string() + " > " + log.string() + " 2>&1";
        const int status = std::system(command.c_str());
        std::ifstream in(log);
        return std::make_pair(status, std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
    };
    // A good job first, then the bad one: neither bakes.
    std::ofstream(dir / "good.json") << R"({"settings": {"resolution": 8}, "scenes": [{"path": ")" + box + R"("}]})";
    std::ofstream(dir / "bad.json") << R"({"scenes": [{"path": ")" + box + R"(", "name": "../../escaped"}]})";
    const std::string both = (dir / "good.json").string() + " " + (dir / "bad.json").string();
    const std::string refused = (dir / "bad.json").string() + R"(: scenes[0]: "name": "../../escaped" is not a folder name)";
    for (const std::string& arguments : {both, "--slurm-dry-run " + both}) {
        INFO(arguments);
        const auto [status, output] = bake(arguments);
        CHECK(status != 0);
        CHECK_THAT(output, Catch::Contains(refused));
        CHECK_FALSE(fs::exists(out));
        CHECK_FALSE(fs::exists(escaped));
    }
    // The new user's slips: a misspelt key at the top and in a scene, each named with its place.
    std::ofstream(dir / "slips.json") << R"({"lihgts": [], "scenes": [{"path": ")" + box + R"(", "skyy": {"radiance": 1}}]})";
    auto [status, output] = bake((dir / "slips.json").string());
    CHECK(status != 0);
    CHECK_THAT(output, Catch::Contains((dir / "slips.json").string() + R"(: unknown key "lihgts" at the top level (did you mean "lights"?)"));
    CHECK_FALSE(fs::exists(out));
    std::ofstream(dir / "slips.json") << R"({"scenes": [{"path": ")" + box + R"(", "skyy": {"radiance": 1}}]})";
    std::tie(status, output) = bake("--slurm-dry-run " + (dir / "slips.json").string());
    CHECK(status != 0);
    CHECK_THAT(output, Catch::Contains((dir / "slips.json").string() + R"(: scenes[0]: unknown key "skyy" (did you mean "sky"?))"));
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("A bake job writes each atlas group into its own lightmap at its resolution", "[bake]") {
    const fs::path dir = tempDir("bake-atlases");
    const fs::path out = dir / "out";
    fs::remove_all(out);
    const std::string scene = sourceDir() + "/scenes/cornell_box.gltf";
    std::ofstream(dir / "job.json") << R"({"output": "out",
        "settings": {"resolution": 16, "cones": 6, "bounces": 1, "lightmap-res": 32, "images": false, "grids": false},
        "atlases": [{"name": "walls", "meshes": ["Floor", "BackWall", "RedWall", "GreenWall"], "resolution": [64, 32]},
                    {"name": "blocks", "meshes": ["ShortBlock", "TallBlock"], "resolution": 16}],
        "scenes": [{"path": ")" + scene + R"(", "name": "grouped"},
                   {"path": ")" + scene + R"(", "name": "misnamed", "atlases": [{"name": "walls", "meshes": ["Flor"]}]}]})";
    std::vector<BakeJob> jobs = readJobFile((dir / "job.json").string(), BakeSettings{}, "output");
    REQUIRE(jobs.size() == 2);
    for (BakeJob& job : jobs) job.settings.quiet = true;

    const BakeReport report = runBake(jobs[0]);
    INFO(report.error);
    REQUIRE(report.ok);
    const fs::path grouped = out / "grouped";
    for (const auto& [stem, width, height] : std::vector<std::tuple<std::string, int, int>>{
             {"lightmap", 32, 32}, {"walls", 64, 32}, {"blocks", 16, 16}}) {  // the ceiling stays in "lightmap"
        for (const char* suffix : {".exr", "_direct.exr", "_indirect.exr", "_mask.exr", ".png"})
            CHECK(fs::exists(grouped / (stem + suffix)));
        const Image total = readImage((grouped / (stem + ".exr")).string());
        const Image mask = readImage((grouped / (stem + "_mask.exr")).string());
        CHECK(total.width == width);
        CHECK(total.height == height);
        CHECK(std::count(mask.pixels.begin(), mask.pixels.end(), 1.0f) > 0);
    }
    std::ifstream json(grouped / "bake.json");
    const std::string text((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
    CHECK_THAT(text, Catch::Contains("atlases=walls:Floor+BackWall+RedWall+GreenWall@64x32; blocks:ShortBlock+TallBlock@16x16"));

    const BakeReport misnamed = runBake(jobs[1]);
    CHECK_FALSE(misnamed.ok);
    CHECK_THAT(misnamed.error, Catch::Contains((dir / "job.json").string() + ": scenes[1].atlases[0]: atlas 'walls'") &&
                                   Catch::Contains("cornell_box.gltf") && Catch::Contains("'Flor'"));
    CHECK_FALSE(fs::exists(out / "misnamed"));
}

TEST_CASE("Every bake setting's help states its real default", "[bake]") {
    // The help ends with "(default X)": applying X to the defaults must change nothing a
    // bake records (describeBakeSettings), or the help misleads (bounce-rays said 8 after the
    // default became 16).
    const BakeSettings defaults;
    const std::string described = describeBakeSettings(defaults);
    size_t checked = 0;
    for (const SettingSpec<BakeSettings>& spec : bakeSettingsTable()) {
        const size_t at = spec.help.rfind("(default ");
        if (at == std::string::npos) continue;
        const std::string value = spec.help.substr(at + 9, spec.help.size() - at - 10);
        if (value.find(' ') != std::string::npos) continue;  // a default in words
        INFO(spec.name << ": help says default '" << value << "'");
        BakeSettings settings;
        CHECK_NOTHROW(spec.apply(settings, value));
        CHECK(describeBakeSettings(settings) == described);
        ++checked;
    }
    CHECK(checked > 20);
}

TEST_CASE("A bake's scene.glb reads back with the same triangles and TEXCOORD_1, its lightmap attached", "[bake]") {
    // glTF out round trip on both Cycles Cornell boxes: the loader reads scene.glb to the same
    // meshes as the source, every material of a baked primitive carries MOZ_lightmap, and
    // the lightmap it embeds (RGBM PNG, range in `intensity`) decodes to the bake's
    // lightmap.exr within issue 14's 1% relative RMSE over the covered texels.
    VL_SKIP_WITHOUT_SHARED();
    for (const std::string box : {"quad", "point"}) {
        const std::string source = sharedDir() + "/reference/cornell_" + box + ".gltf";
        const fs::path out = fs::path(tempDir("glb-round-trip")) / box;
        const BakeReport report = runBake(quickJob(source, out));
        INFO(box << ": " << report.error);
        REQUIRE(report.ok);
        const std::string glb = (out / "scene.glb").string();
        REQUIRE(fs::exists(glb));

        const Scene original = loadGltf(source), back = loadGltf(glb);
        REQUIRE(back.meshes.size() == original.meshes.size());
        for (size_t m = 0; m < original.meshes.size(); ++m) {
            INFO("mesh " << original.meshes[m].name);
            CHECK(back.meshes[m].name == original.meshes[m].name);
            CHECK(back.meshes[m].indices == original.meshes[m].indices);
            CHECK(back.meshes[m].positions == original.meshes[m].positions);
            CHECK(back.meshes[m].uv1 == original.meshes[m].uv1);
        }

        tinygltf::Model model;
        gltf::EncodedImages encoded;
        readGltfModel(glb, model, encoded);
        int texture = -1;
        double range = 0.0;
        for (const Mesh& mesh : back.meshes) {
            if (mesh.uv1.empty()) continue;
            const tinygltf::Primitive& primitive =
                model.meshes[size_t(mesh.source.mesh)].primitives[size_t(mesh.source.primitive)];
            REQUIRE(primitive.material >= 0);
            const auto found = model.materials[size_t(primitive.material)].extensions.find("MOZ_lightmap");
            INFO("mesh " << mesh.name);
            REQUIRE(found != model.materials[size_t(primitive.material)].extensions.end());
            CHECK(found->second.Get("texCoord").GetNumberAsInt() == 1);
            texture = found->second.Get("index").GetNumberAsInt();
            range = found->second.Get("intensity").GetNumberAsDouble();
        }
        REQUIRE(texture >= 0);
        const tinygltf::Image& image = model.images[size_t(model.textures[size_t(texture)].source)];
        const tinygltf::BufferView& view = model.bufferViews[size_t(image.bufferView)];
        const std::string png = (fs::path(tempDir("glb-round-trip")) / (box + "_lightmap.png")).string();
        std::ofstream(png, std::ios::binary)
            .write(reinterpret_cast<const char*>(model.buffers[0].data.data() + view.byteOffset),
                   static_cast<std::streamsize>(view.byteLength));
        const Image decoded = decodeRgbm(readRgbmPng(png, float(range)));
        const Image exr = readImage((out / "lightmap.exr").string());
        const Image mask = readImage((out / "lightmap_mask.exr").string());
        MetricOptions options;
        options.mask = &mask;
        const double error = relativeRmse(decoded, exr, options);
        INFO("RGBM range " << range << ", relative RMSE " << error);
        CHECK(error < 0.01);
    }
}

TEST_CASE("A scene without TEXCOORD_1 bakes into generated lightmap UVs, and says so", "[bake]") {
    // nvpro's Cornell box has no TEXCOORD_1: the bake generates an atlas (unwrap/lightmap_uvs.h)
    // instead of leaving every mesh out of the lightmap; `lightmap-uvs false` keeps the old
    // behaviour.
    VL_SKIP_WITHOUT_SHARED();
    for (bool generate : {true, false}) {
        const fs::path out = fs::path(tempDir("generated-uvs")) / (generate ? "on" : "off");
        BakeJob job = quickJob(sharedDir() + "/scenes/cornellbox-nvpro/cornellBox.gltf", out);
        job.settings.generateLightmapUvs = generate;
        const BakeReport report = runBake(job);
        INFO("generate " << generate << ": " << report.error);
        REQUIRE(report.ok);
        const auto warned = [&](const std::string& text) {
            return std::any_of(report.warnings.begin(), report.warnings.end(),
                               [&](const std::string& w) { return w.find(text) != std::string::npos; });
        };
        if (generate) {
            REQUIRE(report.lightmapUvs);
            CHECK(report.lightmapUvs->charts > 10);
            CHECK(report.coveredTexels > report.lightmapTexels * 4 / 10);  // charts take 67% (README), less the edges
            CHECK_FALSE(warned("has no TEXCOORD_1"));
            // scene.glb carries the generated TEXCOORD_1: read back, the same triangles
            // (corner by corner: the loader meets the file's winding as before), every mesh
            // with a uv1 and every material with the lightmap.
            const Scene original = loadGltf(job.scenePath), back = loadGltf((out / "scene.glb").string());
            REQUIRE(back.meshes.size() == original.meshes.size());
            for (size_t m = 0; m < back.meshes.size(); ++m) {
                const Mesh &a = original.meshes[m], &b = back.meshes[m];
                INFO("mesh " << a.name);
                CHECK(b.uv1.size() == (original.materialOf(a).emissive() ? 0 : b.positions.size()));
                REQUIRE(b.indices.size() == a.indices.size());
                size_t same = 0;
                for (size_t i = 0; i < a.indices.size(); ++i)
                    same += a.positions[a.indices[i]] == b.positions[b.indices[i]] ? 1 : 0;
                CHECK(same == a.indices.size());
            }
            tinygltf::Model model;
            gltf::EncodedImages encoded;
            readGltfModel((out / "scene.glb").string(), model, encoded);
            for (const tinygltf::Mesh& mesh : model.meshes)
                for (const tinygltf::Primitive& primitive : mesh.primitives) {
                    REQUIRE(primitive.material >= 0);
                    // All but the light: the bake leaves emitters out of the lightmap, and
                    // out of the atlas.
                    const tinygltf::Material& material = model.materials[size_t(primitive.material)];
                    const bool emits = material.emissiveFactor[0] + material.emissiveFactor[1] + material.emissiveFactor[2] > 0.0;
                    INFO("material " << material.name);
                    CHECK(primitive.attributes.count("TEXCOORD_1") == (emits ? 0u : 1u));
                    CHECK(material.extensions.count("MOZ_lightmap") == (emits ? 0u : 1u));
                }
            const Image lightmap = readImage((out / "lightmap.exr").string());
            double sum = 0.0;
            for (float v : lightmap.pixels) sum += v;
            CHECK(sum > 0.0);
            std::ifstream json(out / "bake.json");
            const std::string text((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
            CHECK_THAT(text, Catch::Contains("\"lightmap_uvs\""));
        } else {
            CHECK_FALSE(report.lightmapUvs);
            CHECK(report.coveredTexels == 0);
            CHECK(warned("has no TEXCOORD_1"));
        }
    }
}

TEST_CASE("A scene where some meshes have TEXCOORD_1 bakes the others into generated UVs of their own image", "[bake]") {
    // The Cycles quad box with ShortBlock's TEXCOORD_1 taken out (as a scene assembled from a
    // lightmapped room and a prop without one): the room keeps its own layout in lightmap.exr,
    // the block gets generated charts in lightmap_generated.exr instead of being left out, and
    // the room's lightmap is the one the untouched scene bakes.
    VL_SKIP_WITHOUT_SHARED();
    const fs::path dir = tempDir("mixed-uvs");
    fs::remove_all(dir);
    fs::create_directories(dir);
    fs::copy_file(sharedDir() + "/reference/cbox_quad_spec.bin", dir / "cbox_quad_spec.bin");
    nlohmann::json gltf = nlohmann::json::parse(std::ifstream(sharedDir() + "/reference/cornell_quad.gltf"));
    for (auto& mesh : gltf["meshes"])
        if (mesh["name"] == "ShortBlock") mesh["primitives"][0]["attributes"].erase("TEXCOORD_1");
    std::ofstream(dir / "mixed.gltf") << gltf.dump();

    BakeJob whole = quickJob(sharedDir() + "/reference/cornell_quad.gltf", dir / "whole");
    BakeJob mixed = quickJob((dir / "mixed.gltf").string(), dir / "mixed");
    const BakeReport wholeReport = runBake(whole), mixedReport = runBake(mixed);
    INFO(wholeReport.error << mixedReport.error);
    REQUIRE(wholeReport.ok);
    REQUIRE(mixedReport.ok);
    for (const std::string& warning : mixedReport.warnings) CHECK(warning.find("TEXCOORD_1") == std::string::npos);
    REQUIRE(mixedReport.lightmapUvs);
    CHECK(mixedReport.lightmapUvs->meshes == 1);
    CHECK(mixedReport.lightmapUvs->charts == 5);  // a block on the floor: its bottom is a face too, or not
    REQUIRE(fs::exists(dir / "mixed" / "lightmap_generated.exr"));

    // The block's generated lightmap is lit: every covered texel above zero.
    const Image block = readImage((dir / "mixed" / "lightmap_generated.exr").string());
    const Image blockMask = readImage((dir / "mixed" / "lightmap_generated_mask.exr").string());
    size_t covered = 0, lit = 0;
    for (int y = 0; y < block.height; ++y)
        for (int x = 0; x < block.width; ++x)
            if (blockMask.at(x, y, 0) > 0.5f) {
                ++covered;
                lit += block.at(x, y, 0) + block.at(x, y, 1) + block.at(x, y, 2) > 0.0f ? 1 : 0;
            }
    CHECK(covered > size_t(block.width) * size_t(block.height) / 4);
    CHECK(lit >= covered * 95 / 100);  // the block's bottom, on the floor, is dark

    // The room's lightmap: the same light as the untouched scene's over the texels both cover.
    // Its indirect part is the same; its direct part differs only by the penumbrae's sampling
    // (a receiver sample's index seeds its emitter strata, and the block's texels leaving the
    // atlas renumber the room's samples), which averages out in the mean.
    const Image roomMask = readImage((dir / "mixed" / "lightmap_mask.exr").string());
    MetricOptions options;
    options.mask = &roomMask;
    const auto compare = [&](const std::string& part) {
        return compareImages(readImage((dir / "mixed" / ("lightmap" + part + ".exr")).string()),
                             readImage((dir / "whole" / ("lightmap" + part + ".exr")).string()), options);
    };
    const ErrorMetrics total = compare(""), indirect = compare("_indirect"), direct = compare("_direct");
    INFO("room against the untouched bake: total " << total.relativeRmse << ", direct " << direct.relativeRmse
                                                   << ", indirect " << indirect.relativeRmse);
    CHECK(indirect.relativeRmse < 1e-3);
    CHECK(direct.relativeRmse < 0.05);
    for (int c = 0; c < 3; ++c) CHECK(total.meanTest[c] == Approx(total.meanReference[c]).epsilon(0.002));

    // glTF out: the block's material (White, shared with the walls) is copied for the second
    // lightmap, and the block's primitive carries the generated TEXCOORD_1.
    tinygltf::Model model;
    gltf::EncodedImages encoded;
    readGltfModel((dir / "mixed" / "scene.glb").string(), model, encoded);
    std::set<int> lightmapTextures;
    for (const tinygltf::Mesh& mesh : model.meshes) {
        const tinygltf::Primitive& primitive = mesh.primitives[0];
        const tinygltf::Material& material = model.materials[size_t(primitive.material)];
        const auto moz = material.extensions.find("MOZ_lightmap");
        if (moz == material.extensions.end()) continue;
        lightmapTextures.insert(moz->second.Get("index").GetNumberAsInt());
        INFO(mesh.name);
        CHECK(primitive.attributes.count("TEXCOORD_1") == 1);
    }
    CHECK(lightmapTextures.size() == 2);
}
