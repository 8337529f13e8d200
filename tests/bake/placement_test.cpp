// Where a scene sits and how big it is must not change its bake: the Cornell box of scenes/
// put under one extra root node (scaled, moved up to 10⁶ m, turned by quarter turns) bakes
// like the untouched file. Light is unchanged by uniform scaling, translation and rotation
// (form factors are scale-free), the loader takes the scene to a local frame in double
// precision, and the voxel grid is anchored to the scene's bounds (voxelize.h
// anchorToVoxelGrid), so what remains is float rounding inside the local frame, cone sets
// laid out in a frame of their own (irradiance_cache.h gatherFrame) and, for the turns, the
// order in which the voxelizer meets the triangles. Bound: 0.5% relative RMSE of every
// output against the untransformed bake, issue 18's goal. Measured: at most 0.025% (the
// indirect part, quarter turn about Y). The loader makes a quarter turn's matrix exact
// (gltf_loader.cpp exactQuarterTurns): 2·10⁻¹⁶ where 0 belongs would move walls that lie on
// voxel boundaries into the voxels beside them. The path tracer's means within 4σ of its
// Monte Carlo error.
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "receivers/receivers.h"
#include "metrics/metrics.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "support/skip.h"
#include "voxel/voxelize.h"
#include "quad_scene.h"
#include "scene/own_frame.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <vector>

using namespace vl;
namespace fs = std::filesystem;

namespace {

struct Placement {
    std::string name;
    std::vector<double> translation;  // empty: none
    double scale = 1.0;
    std::vector<double> rotation;  // quaternion x, y, z, w; empty: none
};

const double kHalfRoot = std::sqrt(0.5);

const std::vector<Placement>& placements() {
    static const std::vector<Placement> all = {
        {"scale 1e-3", {}, 1.0e-3, {}},
        {"scale 1e3", {}, 1.0e3, {}},
        {"moved 100 m", {100.0, 50.0, -100.0}, 1.0, {}},
        {"moved 10 km", {1.0e4, 5.0e3, -1.0e4}, 1.0, {}},
        {"moved 1e6 m", {1.0e6, 3.0e5, -1.0e6}, 1.0, {}},
        {"moved 1e6 m and scaled 1e3", {1.0e6, -1.0e6, 1.0e6}, 1.0e3, {}},
        {"quarter turn about Y", {}, 1.0, {0.0, kHalfRoot, 0.0, kHalfRoot}},
        {"quarter turn about X", {}, 1.0, {kHalfRoot, 0.0, 0.0, kHalfRoot}},
        {"half turn about Z", {}, 1.0, {0.0, 0.0, 1.0, 0.0}},
    };
    return all;
}

const std::string kSource = "scenes/cornell_box.gltf";

// The glTF at kSource with every scene root moved under one node that carries the placement,
// written under test-output/<folder>. Each test case names its own folder: ctest runs them as
// parallel processes, and one copying the buffer while another parses it reads an empty file.
std::string placedCopy(const Placement& placement, const std::string& folder,
                       const fs::path& source = fs::path(vl::test::sourceDir()) / kSource) {
    nlohmann::json gltf;
    std::ifstream(source) >> gltf;
    const fs::path dir = vl::test::tempDir(folder);
    for (const auto& buffer : gltf["buffers"]) {
        const std::string uri = buffer["uri"];
        fs::copy_file(source.parent_path() / uri, dir / uri, fs::copy_options::overwrite_existing);
    }
    nlohmann::json root = {{"name", "placement"}, {"children", gltf["scenes"][0]["nodes"]}};
    if (!placement.translation.empty()) root["translation"] = placement.translation;
    if (placement.scale != 1.0) root["scale"] = {placement.scale, placement.scale, placement.scale};
    if (!placement.rotation.empty()) root["rotation"] = placement.rotation;
    gltf["nodes"].push_back(root);
    gltf["scenes"][0]["nodes"] = {static_cast<int>(gltf["nodes"].size()) - 1};
    std::string file = placement.name;
    for (char& c : file)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    const fs::path out = dir / (file + ".gltf");
    std::ofstream(out) << gltf.dump();
    return out.string();
}

Scene load(const std::string& path) {
    LoadOptions options;
    options.echoWarnings = false;
    return loadGltf(path, options);
}

// The placed copy, checked to be placed: its local frame's origin is the base's moved by the
// placement (world = t + s·R·x), and its size is s times the base's (quarter turns only
// exchange the sides). Else a placement the loader ignored would pass as invariant.
Scene loadPlaced(const Placement& placement, const Scene& base, const std::string& folder) {
    Scene scene = load(placedCopy(placement, folder));
    glm::dquat rotation(1.0, 0.0, 0.0, 0.0);
    if (!placement.rotation.empty())
        rotation = glm::dquat(placement.rotation[3], placement.rotation[0], placement.rotation[1], placement.rotation[2]);
    glm::dvec3 expected = placement.scale * (rotation * base.origin);
    if (!placement.translation.empty())
        expected += glm::dvec3(placement.translation[0], placement.translation[1], placement.translation[2]);
    const double size = maxComponent(base.bounds().extent());
    INFO(placement.name << ": origin " << scene.origin.x << ", " << scene.origin.y << ", " << scene.origin.z);
    CHECK(glm::distance(scene.origin, expected) <= 1e-6 * (glm::length(expected) + placement.scale * size));
    CHECK(maxComponent(scene.bounds().extent()) == Approx(placement.scale * size).epsilon(1e-5));
    return scene;
}

BakeSettings placementSettings() {
    BakeSettings settings;
    settings.quiet = true;
    settings.outputs.grids = false;
    settings.lightmap.width = settings.lightmap.height = 128;
    settings.imageWidth = settings.imageHeight = 128;
    return settings;
}

// How far a bake is from another of the same scene placed otherwise: relative RMSE of the
// lightmap (over `base`'s covered texels) and its parts, and of the first camera's image (the
// emitter, seen directly, left out).
struct Difference {
    ErrorMetrics total, direct, indirect, image;
};
Difference difference(const BakeResult& other, const BakeResult& base) {
    REQUIRE(other.lightmaps.size() == 1);
    REQUIRE(other.images.size() == 1);
    REQUIRE(base.lightmaps.size() == 1);
    REQUIRE(base.images.size() == 1);
    MetricOptions lightmapOptions;
    lightmapOptions.mask = &base.lightmaps[0].mask;
    MetricOptions imageOptions;
    imageOptions.excludeReferenceAbove = 5.0f;
    const BakedLightmap& a = other.lightmaps[0];
    const BakedLightmap& b = base.lightmaps[0];
    return {compareImages(a.total, b.total, lightmapOptions), compareImages(a.direct, b.direct, lightmapOptions),
            compareImages(a.indirect, b.indirect, lightmapOptions),
            compareImages(other.images[0].beauty, base.images[0].beauty, imageOptions)};
}

}  // namespace

TEST_CASE("The bake does not change with the scene's scale, position or quarter turns", "[bake]") {
    const BakeSettings settings = placementSettings();
    Diagnostics diagnostics(false, false);
    const Scene baseScene = load(fs::path(vl::test::sourceDir()) / kSource);
    const BakeResult base = bake(baseScene, settings, diagnostics);
    for (const Placement& placement : placements()) {
        const BakeResult placed = bake(loadPlaced(placement, baseScene, "placement-bake"), settings, diagnostics);
        const auto [total, direct, indirect, image] = difference(placed, base);
        INFO(placement.name << ": relative RMSE against the untouched bake: lightmap " << total.relativeRmse
                            << " (direct " << direct.relativeRmse << ", indirect " << indirect.relativeRmse
                            << "), image " << image.relativeRmse);
        CHECK(total.relativeRmse <= 0.005);
        CHECK(direct.relativeRmse <= 0.005);
        CHECK(indirect.relativeRmse <= 0.005);
        CHECK(image.relativeRmse <= 0.005);
    }
}

TEST_CASE("A scene turned at any angle bakes as it does unturned: the voxel grid turns with it", "[bake]") {
    // The bake turns a scene into its own frame (scene/own_frame.h) before it voxelizes, so the
    // grid runs along the Cycles quad box's walls at any turn. Two of accuracy_rotations' turns
    // (by 140° and 102° about oblique axes). Measured: lightmap 0.018% / 0.041% (indirect
    // 0.04% / 0.09%), image 0.085%; held to 0.5% for the lightmap and 1% for the rest.
    VL_SKIP_WITHOUT_SHARED();
    const fs::path source = fs::path(vl::test::sharedDir()) / "reference" / "cornell_quad.gltf";
    BakeSettings settings = placementSettings();
    Diagnostics diagnostics(false, false);
    const BakeResult base = bake(load(source.string()), settings, diagnostics);
    const std::vector<Placement> turns = {{"turn 1", {}, 1.0, {0.464, 0.175, 0.796, -0.346}},
                                          {"turn 4", {}, 1.0, {-0.766, 0.058, 0.117, 0.629}}};
    for (const Placement& placement : turns) {
        const Scene scene = load(placedCopy(placement, "turned-bake", source));
        const BakeResult turned = bake(scene, settings, diagnostics);
        // The loader placed the box turned, and the bake turned the grid with it.
        CHECK(maxComponent(scene.bounds().extent()) > 1.2f * maxComponent(load(source.string()).bounds().extent()));
        CHECK(turned.voxels.frame != glm::dmat3(1.0));
        const auto [total, direct, indirect, image] = difference(turned, base);
        INFO(placement.name << ": relative RMSE against the unturned bake: lightmap " << total.relativeRmse
                            << " (indirect " << indirect.relativeRmse << "), image " << image.relativeRmse);
        CHECK(total.relativeRmse <= 0.005);
        CHECK(indirect.relativeRmse <= 0.01);
        CHECK(image.relativeRmse <= 0.01);
    }
}

TEST_CASE("A scene without a camera is framed in the world's orientation, however the bake turns it", "[bake]") {
    // `voxlight reference` and the bench frame a camera-less scene by its world bounds, looking
    // along −Z; the bake's default camera must be that camera after the scene's turn.
    Scene scene;
    const int white = vl::test::addLambert(scene, vec3(0.6f));
    vl::test::addRoom(scene, "room/", white, vec3(0.0f), vec3(3.0f, 2.0f, 1.0f));
    const glm::mat3 turn = glm::mat3_cast(glm::angleAxis(0.6f, glm::normalize(vec3(1.0f, 2.0f, 0.5f))));
    for (Mesh& mesh : scene.meshes)
        for (vec3& p : mesh.positions) p = turn * p;
    BakeSettings settings = placementSettings();
    const Camera expected = defaultCamera(scene.bounds(), 1.0f);
    Scene turned = scene;
    REQUIRE(turnToOwnFrame(turned));
    anchorToVoxelGrid(turned, 0.01);
    const std::vector<Camera> cameras = bakeCameras(turned, settings);
    REQUIRE(cameras.size() == 1);
    const auto world = [&](const vec3& p) { return vec3(turned.origin + turned.frame * glm::dvec3(p)); };
    const auto worldDirection = [&](const vec3& d) { return vec3(turned.frame * glm::dvec3(d)); };
    CHECK(glm::distance(world(cameras[0].position), expected.position) < 1e-4f);
    CHECK(glm::distance(worldDirection(cameras[0].forward), expected.forward) < 1e-5f);
    CHECK(glm::distance(worldDirection(cameras[0].up), expected.up) < 1e-5f);
}

TEST_CASE("The path tracer's lightmap means do not change with the scene's scale, position or quarter turns",
          "[bake]") {
    struct Means {
        double mean[3];
        double sigma[3];  // of the mean
    };
    auto trace = [](const Scene& scene) {
        const SceneTriangles triangles = gatherTriangles(scene);
        const Bvh bvh = Bvh::build(triangles);
        const TraceScene traceScene = TraceScene::build(scene, triangles);
        LightmapSettings lightmap;
        lightmap.width = lightmap.height = 64;
        Diagnostics diagnostics(false, false);
        const LightmapAtlas atlas = buildLightmapReceivers(scene, lightmap, diagnostics).at(0);
        PathTracerSettings settings;
        settings.samplesPerPixel = 16;
        settings.quiet = true;
        const TraceResult r = traceIrradiance(traceScene, bvh, atlas.receivers, settings);
        REQUIRE(r.nonFiniteSamples == 0);
        Means out{};
        double variance[3] = {0, 0, 0};
        size_t n = 0;
        for (int y = 0; y < atlas.mask.height; ++y)
            for (int x = 0; x < atlas.mask.width; ++x) {
                if (!(atlas.mask.at(x, y) > 0.5f)) continue;
                ++n;
                for (int c = 0; c < 3; ++c) {
                    out.mean[c] += r.beauty.at(x, y, c);
                    variance[c] += r.variance.at(x, y, c);
                }
            }
        REQUIRE(n > 1000);
        for (int c = 0; c < 3; ++c) {
            out.mean[c] /= double(n);
            out.sigma[c] = std::sqrt(variance[c]) / double(n);
        }
        return out;
    };
    const Scene baseScene = load(fs::path(vl::test::sourceDir()) / kSource);
    const Means base = trace(baseScene);
    for (const Placement& placement : placements()) {
        const Means placed = trace(loadPlaced(placement, baseScene, "placement-trace"));
        for (int c = 0; c < 3; ++c) {
            const double sigma = std::hypot(base.sigma[c], placed.sigma[c]);
            INFO(placement.name << ", channel " << c << ": mean " << placed.mean[c] << " against " << base.mean[c]
                                << ", σ of the difference " << sigma);
            CHECK(std::abs(placed.mean[c] - base.mean[c]) <= 4.0 * sigma);
        }
    }
}
