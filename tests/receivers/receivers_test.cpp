// Lightmap receivers: texel-space rasterisation of TEXCOORD_1 (glTF v runs down the image),
// sub-texel probes owned by exactly one triangle on a shared edge, the shared atlas and its
// warnings, and the coverage of the Cornell atlas against Cycles' own mask.
#include "receivers/receivers.h"

#include "core/error.h"
#include "core/image_io.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

using namespace vl;

namespace {

// The square [x0, x1] × [z0, z1] at height y facing +Y; u = (x − x0)/(x1 − x0), v = (z − z0)/(z1 − z0).
Mesh floorMesh(const std::string& name, float x0, float x1, float z0, float z1, float y, int material) {
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    mesh.positions = {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}, {x0, y, z1}};
    mesh.normals.assign(4, vec3(0, 1, 0));
    mesh.uv1 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.indices = {0, 2, 1, 0, 3, 2};
    return mesh;
}

Scene floorScene() {
    Scene scene;
    scene.sourcePath = "floor.gltf";
    Material grey;
    grey.name = "grey";
    grey.baseColorFactor = vec4(0.25f, 0.5f, 0.75f, 1.0f);
    scene.materials.push_back(grey);
    scene.meshes.push_back(floorMesh("floor", -1.0f, 1.0f, -2.0f, 2.0f, 0.5f, 0));
    return scene;
}

vec3 floorPoint(float u, float v) { return vec3(-1.0f + 2.0f * u, 0.5f, -2.0f + 4.0f * v); }

}  // namespace

TEST_CASE("Texel centres map to the surface point of their TEXCOORD_1 with v down the image", "[bake]") {
    const Scene scene = floorScene();
    LightmapSettings settings;
    settings.width = 8;
    settings.height = 4;
    settings.subsamplesPerAxis = 1;
    Diagnostics diagnostics(false, false);
    const auto atlases = buildLightmapReceivers(scene, settings, diagnostics);
    REQUIRE(atlases.size() == 1);
    const LightmapAtlas& atlas = atlases[0];
    REQUIRE(atlas.coveredTexels == 32);
    REQUIRE(atlas.receivers.samples.size() == 32);  // every centre lies in exactly one of the two triangles
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            const size_t i = static_cast<size_t>(y) * 8 + x;
            REQUIRE(atlas.receivers.sampleCount(i) == 1);
            const SurfaceSample& s = atlas.receivers.samples[atlas.receivers.begin[i]];
            const vec3 expected = floorPoint((x + 0.5f) / 8.0f, (y + 0.5f) / 4.0f);
            REQUIRE(glm::length(s.position - expected) < 1e-5f);
            REQUIRE(s.normal == vec3(0, 1, 0));
            REQUIRE(s.albedo == vec3(0.25f, 0.5f, 0.75f));
            REQUIRE(s.weight == 1.0f);
            REQUIRE(s.triangle < 2);
            REQUIRE(atlas.mask.at(x, y) == 1.0f);
        }
}

TEST_CASE("Sub-texel probes on a shared edge belong to exactly one triangle", "[bake]") {
    const Scene scene = floorScene();
    LightmapSettings settings;
    settings.width = settings.height = 8;  // the diagonal passes exactly through probes
    settings.subsamplesPerAxis = 4;
    settings.samplePerTriangle = false;
    Diagnostics diagnostics(false, false);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings, diagnostics).at(0);
    REQUIRE(atlas.overlappingProbes == 0);
    REQUIRE(diagnostics.warnings().empty());
    for (size_t i = 0; i < 64; ++i) {
        REQUIRE(atlas.receivers.sampleCount(i) == 16);
        const int x = static_cast<int>(i % 8), y = static_cast<int>(i / 8);
        // The probes are the 4 × 4 stratified grid over the texel's footprint.
        for (uint32_t k = 0; k < 16; ++k) {
            const SurfaceSample& s = atlas.receivers.samples[atlas.receivers.begin[i] + k];
            REQUIRE(s.weight == Approx(1.0f / 16.0f));
            const float u = (s.position.x + 1.0f) / 2.0f * 8.0f - x;  // position within the texel, in texels
            const float v = (s.position.z + 2.0f) / 4.0f * 8.0f - y;
            const float iu = u * 4.0f - 0.5f, iv = v * 4.0f - 0.5f;
            REQUIRE(std::abs(iu - std::round(iu)) < 1e-3f);
            REQUIRE(std::abs(iv - std::round(iv)) < 1e-3f);
            REQUIRE(iu > -0.01f);
            REQUIRE(iu < 3.01f);
        }
    }
    // Merged: the quad's two triangles are one flat surface, so every texel, the diagonal's
    // too, holds one sample of weight 1 at the centroid of its 16 probes, its centre.
    settings.samplePerTriangle = true;
    const LightmapAtlas merged = buildLightmapReceivers(scene, settings, diagnostics).at(0);
    for (size_t i = 0; i < 64; ++i) {
        const int x = static_cast<int>(i % 8), y = static_cast<int>(i / 8);
        REQUIRE(merged.receivers.sampleCount(i) == 1u);
        const SurfaceSample& s = merged.receivers.samples[merged.receivers.begin[i]];
        REQUIRE(s.weight == Approx(1.0f));
        REQUIRE(glm::length(s.position - floorPoint((x + 0.5f) / 8.0f, (y + 0.5f) / 8.0f)) < 1e-5f);
        REQUIRE(s.triangle < 2);
    }
}

TEST_CASE("A texel holds one sample per smooth surface however many triangles it covers", "[bake]") {
    // The floor of floorScene, tessellated into 32 × 32 quads (2,048 triangles) on a 4 × 4
    // atlas: 128 triangles a texel, all one flat surface.
    Scene scene = floorScene();
    Mesh& mesh = scene.meshes[0];
    const int cells = 32;
    mesh.positions.clear();
    mesh.normals.clear();
    mesh.uv1.clear();
    mesh.indices.clear();
    for (int j = 0; j <= cells; ++j)
        for (int i = 0; i <= cells; ++i) {
            const float u = float(i) / cells, v = float(j) / cells;
            mesh.positions.push_back(floorPoint(u, v));
            mesh.normals.push_back(vec3(0, 1, 0));
            mesh.uv1.push_back(vec2(u, v));
        }
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            const uint32_t a = uint32_t(j * (cells + 1) + i), b = a + 1, c = a + cells + 1, d = c + 1;
            mesh.indices.insert(mesh.indices.end(), {a, d, b, a, c, d});
        }
    LightmapSettings settings;
    settings.width = settings.height = 4;
    settings.subsamplesPerAxis = 8;
    Diagnostics diagnostics(false, false);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings, diagnostics).at(0);
    REQUIRE(atlas.coveredTexels == 16);
    REQUIRE(atlas.receivers.samples.size() == 16);
    for (size_t i = 0; i < 16; ++i) {
        const int x = static_cast<int>(i % 4), y = static_cast<int>(i / 4);
        REQUIRE(atlas.receivers.sampleCount(i) == 1u);
        const SurfaceSample& s = atlas.receivers.samples[atlas.receivers.begin[i]];
        REQUIRE(s.weight == Approx(1.0f));
        REQUIRE(glm::length(s.position - floorPoint((x + 0.5f) / 4.0f, (y + 0.5f) / 4.0f)) < 1e-5f);
        REQUIRE(s.normal == vec3(0, 1, 0));
        // The triangle it names lies in the texel (the heaviest of them, all equal here).
        const uint32_t quadIndex = s.triangle / 2;
        const int qi = int(quadIndex % cells), qj = int(quadIndex / cells);
        REQUIRE(qi / (cells / 4) == x);
        REQUIRE(qj / (cells / 4) == y);
    }
}

TEST_CASE("A texel across a crease keeps a sample on each side, weighted by its share", "[bake]") {
    // A strip of 3 × 1 texels: flat for x < 0, rising 20° for x > 0; the crease at x = 0 runs
    // through the middle texel's centre, so each side holds half its probes.
    Scene scene = floorScene();
    Mesh& mesh = scene.meshes[0];
    const float rise = std::tan(glm::radians(20.0f));
    const vec3 up(0, 1, 0), tilted = glm::normalize(vec3(-rise, 1, 0));
    // The crease's vertices twice, one normal a side (a hard edge).
    mesh.positions = {{-1.5f, 0, 0}, {0, 0, 0}, {0, 0, 1}, {-1.5f, 0, 1},
                      {0, 0, 0},     {0, 0, 1}, {1.5f, 1.5f * rise, 0}, {1.5f, 1.5f * rise, 1}};
    mesh.normals = {up, up, up, up, tilted, tilted, tilted, tilted};
    mesh.uv1 = {{0, 0}, {0.5f, 0}, {0.5f, 1}, {0, 1}, {0.5f, 0}, {0.5f, 1}, {1, 0}, {1, 1}};
    mesh.indices = {0, 2, 1, 0, 3, 2, 4, 7, 6, 4, 5, 7};
    LightmapSettings settings;
    settings.width = 3;
    settings.height = 1;
    settings.subsamplesPerAxis = 4;
    Diagnostics diagnostics(false, false);
    const LightmapAtlas atlas = buildLightmapReceivers(scene, settings, diagnostics).at(0);
    REQUIRE(atlas.receivers.sampleCount(0) == 1u);
    REQUIRE(atlas.receivers.sampleCount(2) == 1u);
    REQUIRE(atlas.receivers.sampleCount(1) == 2u);
    float sum = 0.0f;
    for (uint32_t k = 0; k < 2; ++k) {
        const SurfaceSample& s = atlas.receivers.samples[atlas.receivers.begin[1] + k];
        REQUIRE(s.weight == Approx(0.5f));
        // Each side's sample has its side's normal and lies on its side.
        if (s.position.x < 0.0f) REQUIRE(glm::length(s.normal - up) < 1e-5f);
        else REQUIRE(glm::length(s.normal - tilted) < 1e-5f);
        sum += s.weight;
    }
    REQUIRE(sum == Approx(1.0f));
}

TEST_CASE("Shared atlas: emitters are skipped, a mesh without TEXCOORD_1 is named, overlaps are reported", "[bake]") {
    Scene scene = floorScene();
    Material light;
    light.name = "light";
    light.emissiveFactor = vec3(1.0f);
    scene.materials.push_back(light);
    Mesh emitter = floorMesh("lamp", 0.0f, 0.1f, 0.0f, 0.1f, 1.0f, 1);
    scene.meshes.push_back(emitter);
    Mesh bare = floorMesh("bare", 2.0f, 3.0f, 0.0f, 1.0f, 0.0f, 0);
    bare.uv1.clear();
    scene.meshes.push_back(bare);
    Mesh half = floorMesh("half", 5.0f, 6.0f, 0.0f, 1.0f, 0.0f, 0);
    for (vec2& uv : half.uv1) uv = uv * 0.5f;  // overlaps the floor's top-left quarter
    scene.meshes.push_back(half);

    LightmapSettings settings;
    settings.width = settings.height = 8;
    Diagnostics diagnostics(false, false);
    const auto atlases = buildLightmapReceivers(scene, settings, diagnostics);
    REQUIRE(atlases.size() == 1);
    REQUIRE(atlases[0].meshes == std::vector<uint32_t>{0, 3});
    REQUIRE(atlases[0].overlappingProbes == 16 * 16);  // 4 × 4 texels × 16 probes
    bool namedBare = false, namedOverlap = false;
    for (const std::string& w : diagnostics.warnings()) {
        namedBare = namedBare || (w.find("'bare/0'") != std::string::npos || w.find("'bare'") != std::string::npos);
        namedOverlap = namedOverlap || (w.find("'floor'") != std::string::npos && w.find("'half'") != std::string::npos);
    }
    REQUIRE(namedBare);
    REQUIRE(namedOverlap);
    REQUIRE(diagnostics.warnings().size() == 2);
    // Overlapping texels average both meshes' surfaces.
    REQUIRE(atlases[0].receivers.sampleCount(1) == 2);  // texel (1, 0): off both diagonals

    // One image per mesh instead: no overlap.
    settings.atlasPerMesh = true;
    Diagnostics quiet(false, false);
    const auto perMesh = buildLightmapReceivers(scene, settings, quiet);
    REQUIRE(perMesh.size() == 2);
    REQUIRE(perMesh[1].name == "half");
    REQUIRE(perMesh[1].coveredTexels == 16);

    // Under --strict the missing TEXCOORD_1 is an error naming the mesh.
    Diagnostics strict(true, false);
    REQUIRE_THROWS_AS(buildLightmapReceivers(scene, settings, strict), InputError);
    settings.subsamplesPerAxis = 9;
    REQUIRE_THROWS_AS(buildLightmapReceivers(scene, settings, quiet), SettingsError);
}

TEST_CASE("The Cornell atlas covers the texels Cycles' mask covers", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    for (const std::string name : {"cornell_quad", "cornell_point"}) {
        const std::string dir = vl::test::sharedDir() + "/reference/";
        LoadOptions load;
        load.echoWarnings = false;
        const Scene scene = loadGltf(dir + name + ".gltf", load);
        const Image cycles = readImage(dir + "cycles/" + name + "_lightmap_mask.exr");
        Diagnostics diagnostics(false, false);
        LightmapSettings settings;  // 256², the reference's size
        settings.subsamplesPerAxis = 1;  // texel centres, as Cycles' bake
        const LightmapAtlas centres = buildLightmapReceivers(scene, settings, diagnostics).at(0);
        settings.subsamplesPerAxis = 4;
        const LightmapAtlas probes = buildLightmapReceivers(scene, settings, diagnostics).at(0);
        REQUIRE(diagnostics.warnings().empty());  // the emitter is skipped silently, nothing overlaps
        REQUIRE(centres.meshes.size() == 7);
        size_t cyclesCovered = 0, centreAgree = 0, probesMissing = 0;
        for (int y = 0; y < 256; ++y)
            for (int x = 0; x < 256; ++x) {
                const bool c = cycles.at(x, y, 0) > 0.5f;
                cyclesCovered += c;
                centreAgree += c == (centres.mask.at(x, y) > 0.5f);
                probesMissing += c && !(probes.mask.at(x, y) > 0.5f);
            }
        INFO(name << ": Cycles covers " << cyclesCovered << ", centre masks agree on " << centreAgree
                  << ", probe mask misses " << probesMissing);
        // Flipping v (or u) would disagree on most of the 64.6% covered texels.
        REQUIRE(centreAgree >= 65536 - 65536 / 200);
        REQUIRE(probesMissing == 0);
        REQUIRE(probes.coveredTexels <= cyclesCovered + cyclesCovered / 50);
    }
}

TEST_CASE("Camera receivers: each probe lies on its pinhole ray with the normal toward the camera", "[bake]") {
    Scene scene = floorScene();  // y = 0.5, x ∈ [−1, 1], z ∈ [−2, 2]
    scene.materials[0].emissiveFactor = vec3(0.5f, 0.25f, 1.0f);
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    for (float height : {3.0f, -2.0f}) {  // from above and from below
        Camera camera;
        camera.position = vec3(0.0f, height, 0.0f);
        camera.forward = vec3(0.0f, height > 0.5f ? -1.0f : 1.0f, 0.0f);
        camera.up = vec3(0.0f, 0.0f, -1.0f);
        camera.yfov = 1.4f;  // the plane's x edges cross pixels, its z edges lie outside the view
        const CameraModel model = makeCameraModel(camera, 6, 6);
        const CameraReceivers r = buildCameraReceivers(trace, bvh, model, 2);
        const float facing = height > 0.5f ? 1.0f : -1.0f;
        size_t partial = 0;
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 6; ++x) {
                const size_t i = static_cast<size_t>(y) * 6 + x;
                const uint32_t count = r.receivers.sampleCount(i);
                REQUIRE(r.mask.at(x, y) == Approx(count / 4.0f));
                partial += count > 0 && count < 4;
                for (uint32_t k = 0; k < count; ++k) {
                    const SurfaceSample& s = r.receivers.samples[r.receivers.begin[i] + k];
                    REQUIRE(s.position.y == Approx(0.5f));
                    REQUIRE(s.normal == vec3(0.0f, facing, 0.0f));
                    REQUIRE(s.weight == 0.25f);
                    // On the ray from the camera through one of the pixel's 2 × 2 probe points.
                    const vec3 d = glm::normalize(s.position - camera.position);
                    bool onProbeRay = false;
                    for (int j = 0; j < 2; ++j)
                        for (int m = 0; m < 2; ++m) {
                            const Ray ray = pinholeRay(model, vec2(x + (m + 0.5f) / 2.0f, y + (j + 0.5f) / 2.0f));
                            onProbeRay = onProbeRay || glm::length(ray.direction - d) < 1e-5f;
                        }
                    REQUIRE(onProbeRay);
                }
                // The emitter plane is single-sided: seen from below it emits nothing.
                const float emitted = height > 0.5f ? 0.5f * count / 4.0f : 0.0f;
                REQUIRE(r.emission.at(x, y, 0) == Approx(emitted));
                REQUIRE(r.albedo.at(x, y, 1) == Approx(0.5f * count / 4.0f));
            }
        REQUIRE(partial > 0);  // the plane's edges cross some pixels
    }
}

TEST_CASE("Camera receivers with one sample per triangle merge a pixel's rays on each triangle", "[bake]") {
    Scene scene = floorScene();  // y = 0.5, x ∈ [−1, 1], z ∈ [−2, 2]: two triangles
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    Camera camera;
    camera.position = vec3(0.0f, 3.0f, 0.0f);
    camera.forward = vec3(0.0f, -1.0f, 0.0f);
    camera.up = vec3(0.0f, 0.0f, -1.0f);
    camera.yfov = 1.4f;
    const CameraModel model = makeCameraModel(camera, 6, 6);
    const CameraReceivers rays = buildCameraReceivers(trace, bvh, model, 4);
    const CameraReceivers merged = buildCameraReceivers(trace, bvh, model, 4, 0, true);
    size_t split = 0;  // pixels the floor's diagonal crosses
    for (size_t i = 0; i < rays.receivers.elementCount(); ++i) {
        std::map<uint32_t, std::pair<float, vec3>> expected;  // triangle → (weight, Σ w·position)
        for (uint32_t k = rays.receivers.begin[i]; k < rays.receivers.begin[i + 1]; ++k) {
            const SurfaceSample& s = rays.receivers.samples[k];
            expected[s.triangle].first += s.weight;
            expected[s.triangle].second += s.weight * s.position;
        }
        REQUIRE(merged.receivers.sampleCount(i) == expected.size());
        split += expected.size() > 1;
        for (uint32_t k = merged.receivers.begin[i]; k < merged.receivers.begin[i + 1]; ++k) {
            const SurfaceSample& m = merged.receivers.samples[k];
            REQUIRE(expected.count(m.triangle) == 1);
            const auto& [weight, weighted] = expected[m.triangle];
            CHECK(m.weight == Approx(weight));
            CHECK(glm::distance(m.position, weighted / weight) < 1e-5f);  // the hits' centroid
            CHECK(m.normal == vec3(0.0f, 1.0f, 0.0f));
        }
    }
    CHECK(split > 0);
    // The image's own channels do not depend on how its shading samples are grouped.
    CHECK(merged.mask.pixels == rays.mask.pixels);
    CHECK(merged.albedo.pixels == rays.albedo.pixels);
}

namespace {

// The meshes (indices into Scene::meshes) whose triangles the atlas's texel samples lie on.
std::set<uint32_t> meshesSampled(const Scene& scene, const LightmapAtlas& atlas) {
    std::vector<uint32_t> firstTriangle{0};
    for (const Mesh& mesh : scene.meshes)
        firstTriangle.push_back(firstTriangle.back() + static_cast<uint32_t>(mesh.triangleCount()));
    std::set<uint32_t> meshes;
    for (const SurfaceSample& s : atlas.receivers.samples)
        meshes.insert(static_cast<uint32_t>(std::upper_bound(firstTriangle.begin(), firstTriangle.end(), s.triangle) -
                                            firstTriangle.begin() - 1));
    return meshes;
}

// The texels of `atlas` with a sample on one of `meshes`: what those meshes cover in it.
std::vector<bool> texelsOf(const Scene& scene, const LightmapAtlas& atlas, const std::set<std::string>& meshes) {
    std::vector<uint32_t> meshOfTriangle;
    for (uint32_t m = 0; m < scene.meshes.size(); ++m)
        meshOfTriangle.insert(meshOfTriangle.end(), scene.meshes[m].triangleCount(), m);
    std::vector<bool> texels(atlas.receivers.elementCount(), false);
    for (size_t i = 0; i < texels.size(); ++i)
        for (uint32_t k = atlas.receivers.begin[i]; k < atlas.receivers.begin[i + 1]; ++k)
            texels[i] = texels[i] || meshes.count(scene.meshes[meshOfTriangle[atlas.receivers.samples[k].triangle]].node) > 0;
    return texels;
}

std::vector<bool> maskTexels(const LightmapAtlas& atlas) {
    std::vector<bool> covered;
    for (float v : atlas.mask.pixels) covered.push_back(v > 0.5f);
    return covered;
}

AtlasGroup group(const std::string& name, std::vector<std::string> meshes, int width = 0, int height = 0) {
    AtlasGroup g;
    g.name = name;
    g.meshes = std::move(meshes);
    g.width = width;
    g.height = height;
    g.origin = "job.json: atlases";
    return g;
}

const std::set<std::string> kCornellWalls{"Floor", "BackWall", "RedWall", "GreenWall", "Ceiling"};
const std::set<std::string> kCornellBlocks{"ShortBlock", "TallBlock"};

}  // namespace

TEST_CASE("Atlas groups of the Cornell box cover exactly their meshes' texels of the shared atlas", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    LoadOptions load;
    load.echoWarnings = false;
    const Scene scene = loadGltf(vl::test::sharedDir() + "/reference/cornell_quad.gltf", load);
    Diagnostics diagnostics(false, false);
    LightmapSettings settings;  // 256²
    const LightmapAtlas shared = buildLightmapReceivers(scene, settings, diagnostics).at(0);

    // Every mesh in a group at the shared resolution: the union is the shared atlas, texel
    // for texel, and each group holds its meshes' texels and no other mesh's samples.
    settings.atlases = {group("walls", {"Floor", "BackWall", "RedWall", "GreenWall", "Ceiling"}),
                        group("blocks", {"ShortBlock", "TallBlock/0"})};  // a node name and a full name
    const auto split = buildLightmapReceivers(scene, settings, diagnostics);
    REQUIRE(diagnostics.warnings().empty());
    REQUIRE(split.size() == 2);  // every baked mesh is grouped: no shared atlas
    CHECK(split[0].name == "walls");
    CHECK(split[1].name == "blocks");
    CHECK(split[0].meshes.size() == 5);
    CHECK(split[1].meshes.size() == 2);
    for (size_t g = 0; g < 2; ++g) {
        const std::set<std::string>& names = g == 0 ? kCornellWalls : kCornellBlocks;
        for (uint32_t m : meshesSampled(scene, split[g])) CHECK(names.count(scene.meshes[m].node) == 1);
        CHECK(maskTexels(split[g]) == texelsOf(scene, shared, names));
    }
    size_t unionCovered = 0, unionDiffers = 0, walls = 0, blocks = 0;
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 256; ++x) {
            const bool inWalls = split[0].mask.at(x, y) > 0.5f, inBlocks = split[1].mask.at(x, y) > 0.5f;
            unionDiffers += (inWalls || inBlocks) != (shared.mask.at(x, y) > 0.5f);
            unionCovered += inWalls || inBlocks;
            walls += inWalls;
            blocks += inBlocks;
        }
    CHECK(unionDiffers == 0);
    CHECK(unionCovered == shared.coveredTexels);
    CHECK(walls > 0);
    CHECK(blocks > 0);

    // Groups at their own resolutions: each image has its size and covers what its meshes
    // cover in a shared atlas of that size.
    settings.atlases = {group("walls", {"Floor", "BackWall", "RedWall", "GreenWall", "Ceiling"}, 512, 128),
                        group("blocks", {"ShortBlock", "TallBlock"}, 64, 64)};
    const auto sized = buildLightmapReceivers(scene, settings, diagnostics);
    REQUIRE(sized.size() == 2);
    for (size_t g = 0; g < 2; ++g) {
        const int width = g == 0 ? 512 : 64, height = g == 0 ? 128 : 64;
        CHECK(sized[g].mask.width == width);
        CHECK(sized[g].mask.height == height);
        CHECK(sized[g].receivers.width == width);
        CHECK(sized[g].receivers.height == height);
        LightmapSettings same;
        same.width = width;
        same.height = height;
        const LightmapAtlas sharedAtThatSize = buildLightmapReceivers(scene, same, diagnostics).at(0);
        const std::vector<bool> expected = texelsOf(scene, sharedAtThatSize, g == 0 ? kCornellWalls : kCornellBlocks);
        CHECK(maskTexels(sized[g]) == expected);
        CHECK(sized[g].coveredTexels == static_cast<size_t>(std::count(expected.begin(), expected.end(), true)));
    }

    // Pulling out one mesh: the rest stay in the shared "lightmap", which comes first.
    settings.atlases = {group("tall", {"TallBlock"}, 128, 128)};
    const auto pulled = buildLightmapReceivers(scene, settings, diagnostics);
    REQUIRE(pulled.size() == 2);
    CHECK(pulled[0].name == "lightmap");
    CHECK(pulled[0].mask.width == 256);
    CHECK(pulled[0].meshes.size() == 6);
    CHECK(pulled[1].name == "tall");
    REQUIRE(pulled[1].meshes.size() == 1);
    CHECK(scene.meshes[pulled[1].meshes[0]].node == "TallBlock");
    std::set<std::string> rest = kCornellWalls;
    rest.insert("ShortBlock");
    CHECK(maskTexels(pulled[0]) == texelsOf(scene, shared, rest));
    CHECK(diagnostics.warnings().empty());

    // The emitter is left out of the shared atlas silently, but named when a group asks for it.
    settings.atlases = {group("tall", {"TallBlock", "Light"})};
    Diagnostics warned(false, false);
    CHECK(buildLightmapReceivers(scene, settings, warned).at(1).meshes.size() == 1);
    REQUIRE(warned.warnings().size() == 1);
    CHECK_THAT(warned.warnings()[0], Catch::Contains("'Light/0'") && Catch::Contains("emissive") && Catch::Contains("'tall'"));
}

TEST_CASE("An atlas group names meshes by node name or glTF mesh name or full name", "[bake]") {
    // One glTF mesh "Plane" of two primitives placed by node "Floor", and "Plane.001" by node "Wall".
    Scene scene = floorScene();
    scene.meshes.clear();
    for (const char* name : {"Plane/0", "Plane/1"}) {
        scene.meshes.push_back(floorMesh(name, -1.0f, 1.0f, -2.0f, 2.0f, 0.0f, 0));
        scene.meshes.back().node = "Floor";
    }
    scene.meshes.push_back(floorMesh("Plane.001/0", -1.0f, 1.0f, -2.0f, 2.0f, 1.0f, 0));
    scene.meshes.back().node = "Wall";
    LightmapSettings settings;
    settings.width = settings.height = 8;
    Diagnostics quiet(false, false);
    for (const std::string name : {"Floor", "Plane"}) {
        settings.atlases = {group("floor", {name})};
        const auto atlases = buildLightmapReceivers(scene, settings, quiet);
        REQUIRE(atlases.size() == 2);
        CHECK(atlases[0].meshes == std::vector<uint32_t>{2});
        CHECK(atlases[1].meshes == std::vector<uint32_t>{0, 1});
    }
    settings.atlases = {group("first", {"Plane/0"}), group("second", {"Plane/1", "Wall"})};
    const auto byPrimitive = buildLightmapReceivers(scene, settings, quiet);
    REQUIRE(byPrimitive.size() == 2);
    CHECK(byPrimitive[0].meshes == std::vector<uint32_t>{0});
    CHECK(byPrimitive[1].meshes == std::vector<uint32_t>{1, 2});
    // The node and the mesh name of one primitive in two groups.
    settings.atlases = {group("first", {"Floor"}), group("second", {"Plane/1"})};
    CHECK_THROWS_WITH(buildLightmapReceivers(scene, settings, quiet),
                      Catch::Contains("job.json: atlases") && Catch::Contains("'second'") &&
                          Catch::Contains("'Plane/1'") && Catch::Contains("'first'") && Catch::Contains("one atlas"));
}

TEST_CASE("Atlas groups that cannot be baked are refused naming the group and where it was declared", "[bake]") {
    Scene scene = floorScene();  // "floor", floor.gltf
    scene.meshes.push_back(floorMesh("wall", -1.0f, 1.0f, -2.0f, 2.0f, 1.0f, 0));
    LightmapSettings settings;
    settings.width = settings.height = 8;
    Diagnostics quiet(false, false);
    const auto refused = [&](std::vector<AtlasGroup> groups) {
        settings.atlases = std::move(groups);
        try {
            buildLightmapReceivers(scene, settings, quiet);
        } catch (const SettingsError& e) {
            return std::string(e.what());
        }
        FAIL("accepted");
        return std::string();
    };
    const auto place = Catch::Contains("job.json: atlases");
    CHECK_THAT(refused({group("walls", {"flor"})}),
               place && Catch::Contains("'walls'") && Catch::Contains("floor.gltf") && Catch::Contains("'flor'") &&
                   Catch::Contains("floor, wall"));
    // The same checks a bake runs before any work, without the receivers.
    CHECK_THROWS_AS(checkAtlasGroups(scene, settings), SettingsError);
    settings.atlases = {group("walls", {"wall"})};
    CHECK_NOTHROW(checkAtlasGroups(scene, settings));
    CHECK_THAT(refused({group("a", {"floor"}), group("b", {"wall", "floor"})}),
               place && Catch::Contains("'b'") && Catch::Contains("'floor'") && Catch::Contains("'a'"));
    CHECK_THAT(refused({group("empty", {})}), place && Catch::Contains("'empty'") && Catch::Contains("no meshes"));
    CHECK_THAT(refused({group("walls", {"floor"}), group("Walls", {"wall"})}),
               place && Catch::Contains("'Walls'") && Catch::Contains("taken"));
    for (const std::string& name : std::vector<std::string>{"", "my walls", "../walls", "walls.exr", "walls_direct",
                                                           "walls_Mask", "image", "image_2", std::string(65, 'w')})
        CHECK_THAT(refused({group(name, {"floor"})}), place && Catch::Contains("'" + name + "'"));
    CHECK_THAT(refused({group("lightmap", {"floor"})}),  // "wall" is left over for the shared atlas
               place && Catch::Contains("'lightmap'") && Catch::Contains("shared atlas") && Catch::Contains("'wall'"));
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{0, 8}, {8, -1}, {16385, 8}})
        CHECK_THAT(refused({group("walls", {"floor"}, w, h)}),
                   place && Catch::Contains("'walls'") && Catch::Contains("resolution") && Catch::Contains("1..16384"));
    settings.atlasPerMesh = true;
    CHECK_THAT(refused({group("walls", {"floor"})}), place && Catch::Contains("one atlas per mesh"));
    settings.atlasPerMesh = false;

    // Named "lightmap" when it takes every mesh: it is the shared atlas, at its own size.
    settings.atlases = {group("lightmap", {"floor", "wall"}, 16, 16)};
    const auto whole = buildLightmapReceivers(scene, settings, quiet);
    REQUIRE(whole.size() == 1);
    CHECK(whole[0].name == "lightmap");
    CHECK(whole[0].meshes == std::vector<uint32_t>{0, 1});
    CHECK(whole[0].mask.width == 16);

    // A grouped mesh without TEXCOORD_1 is left out with a warning naming it and its group
    // (an error under --strict); a group left empty makes no image.
    scene.meshes[1].uv1.clear();
    settings.atlases = {group("walls", {"wall"}), group("floors", {"floor"})};
    Diagnostics warned(false, false);
    const auto atlases = buildLightmapReceivers(scene, settings, warned);
    REQUIRE(atlases.size() == 1);
    CHECK(atlases[0].name == "floors");
    REQUIRE(warned.warnings().size() == 2);
    CHECK_THAT(warned.warnings()[0], Catch::Contains("'wall'") && Catch::Contains("TEXCOORD_1") && Catch::Contains("'walls'"));
    CHECK_THAT(warned.warnings()[1], Catch::Contains("'walls'") && Catch::Contains("no mesh to bake"));
    Diagnostics strict(true, false);
    CHECK_THROWS_AS(buildLightmapReceivers(scene, settings, strict), InputError);
}

namespace {

// A uniform emissive rectangle [−a, a] × [−b, b] at z = −depth facing +Z, turned by `angle`
// about the Z axis and shifted by (cx, cy).
Scene emissiveRectangle(float a, float b, float depth, float angle, float cx, float cy, float Le) {
    Scene scene;
    scene.sourcePath = "emitter.gltf";
    Material material;
    material.name = "light";
    material.baseColorFactor = vec4(0.0f, 0.0f, 0.0f, 1.0f);
    material.emissiveFactor = vec3(1.0f);
    material.emissiveStrength = Le;
    scene.materials.push_back(material);
    Mesh mesh;
    mesh.name = "light";
    mesh.material = 0;
    const float c = std::cos(angle), s = std::sin(angle);
    for (vec2 corner : {vec2(-a, -b), vec2(a, -b), vec2(a, b), vec2(-a, b)})
        mesh.positions.push_back(vec3(cx + c * corner.x - s * corner.y, cy + s * corner.x + c * corner.y, -depth));
    mesh.normals.assign(4, vec3(0, 0, 1));
    mesh.indices = {0, 1, 2, 0, 2, 3};  // counter-clockwise seen from +Z: the front faces the camera
    scene.meshes.push_back(mesh);
    return scene;
}

}  // namespace

TEST_CASE("A pixel on a uniform emitter's edge shows the emitter's radiance times the share of the pixel it covers", "[bake]") {
    // Camera at the origin looking down −Z; the emitter lies in a plane parallel to the film,
    // so its image is the rectangle's projection, scaled by W / (2·depth·tan(fov/2)·aspect).
    // The truth per pixel: the area of that projection inside the pixel; unturned, the product
    // of the overlaps along x and y (exact); turned, from a 500 × 500 grid of points per pixel
    // (off by less than 1/500 per unit of edge crossing the pixel). An 8 × 8 grid of rays
    // alone moves in steps of 1/8 across a straight edge (up to 1/16 of the radiance off).
    const int W = 24, H = 16;
    const float Le = 18.6f, depth = 3.0f;
    Camera camera;
    camera.position = vec3(0.0f);
    camera.forward = vec3(0.0f, 0.0f, -1.0f);
    camera.up = vec3(0.0f, 1.0f, 0.0f);
    camera.yfov = 0.8f;
    const CameraModel model = makeCameraModel(camera, W, H);
    for (float angle : {0.0f, 0.4f}) {
        const float a = 0.61f, b = 0.37f, cx = 0.093f, cy = -0.041f;
        const Scene scene = emissiveRectangle(a, b, depth, angle, cx, cy, Le);
        const SceneTriangles triangles = gatherTriangles(scene);
        const Bvh bvh = Bvh::build(triangles);
        const TraceScene trace = TraceScene::build(scene, triangles);
        const CameraReceivers r = buildCameraReceivers(trace, bvh, model, 2, 8, true);
        const double scaleX = W / (2.0 * depth * std::tan(0.4) * double(W) / H), scaleY = H / (2.0 * depth * std::tan(0.4));
        const auto covered = [&](double fx, double fy) {  // film point → inside the rectangle
            const double X = (fx - 0.5 * W) / scaleX - cx, Y = (0.5 * H - fy) / scaleY - cy;
            const double u = std::cos(angle) * X + std::sin(angle) * Y, v = -std::sin(angle) * X + std::cos(angle) * Y;
            return std::abs(u) <= a && std::abs(v) <= b;
        };
        const auto overlap = [](double lo, double hi, int pixel) {
            return std::max(0.0, std::min(hi, pixel + 1.0) - std::max(lo, double(pixel)));
        };
        double worst = 0.0;
        int edgePixels = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                double share;
                if (angle == 0.0f) {
                    share = overlap(0.5 * W + (cx - a) * scaleX, 0.5 * W + (cx + a) * scaleX, x) *
                            overlap(0.5 * H - (cy + b) * scaleY, 0.5 * H - (cy - b) * scaleY, y);
                } else {
                    constexpr int kGrid = 500;
                    int inside = 0;
                    for (int j = 0; j < kGrid; ++j)
                        for (int i = 0; i < kGrid; ++i) inside += covered(x + (i + 0.5) / kGrid, y + (j + 0.5) / kGrid);
                    share = double(inside) / (kGrid * kGrid);
                }
                edgePixels += share > 0.0 && share < 1.0;
                worst = std::max(worst, std::abs(r.emission.at(x, y, 0) / Le - share));
            }
        INFO("turned " << angle << " rad: " << edgePixels << " edge pixels, worst |pixel / Le − covered share| " << worst);
        CHECK(edgePixels > 20);
        CHECK(worst < (angle == 0.0f ? 1e-4 : 4e-3));
    }
}
