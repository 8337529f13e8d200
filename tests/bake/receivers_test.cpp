// Lightmap receivers: texel-space rasterisation of TEXCOORD_1 (glTF v runs down the image),
// sub-texel probes owned by exactly one triangle on a shared edge, the shared atlas and its
// warnings, and the coverage of the Cornell atlas against Cycles' own mask.
#include "bake/dilate.h"
#include "bake/receivers.h"

#include "core/error.h"
#include "core/image_io.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>

#include <cmath>

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
    // Merged per triangle: texels the diagonal crosses hold two samples whose weights add to 1.
    settings.samplePerTriangle = true;
    const LightmapAtlas merged = buildLightmapReceivers(scene, settings, diagnostics).at(0);
    for (size_t i = 0; i < 64; ++i) {
        const int x = static_cast<int>(i % 8), y = static_cast<int>(i / 8);
        REQUIRE(merged.receivers.sampleCount(i) == (x == y ? 2u : 1u));
        float sum = 0.0f;
        for (uint32_t k = 0; k < merged.receivers.sampleCount(i); ++k) sum += merged.receivers.samples[merged.receivers.begin[i] + k].weight;
        REQUIRE(sum == Approx(1.0f));
        if (x != y) {  // the centroid of a fully covered texel's probes is its centre
            const SurfaceSample& s = merged.receivers.samples[merged.receivers.begin[i]];
            REQUIRE(glm::length(s.position - floorPoint((x + 0.5f) / 8.0f, (y + 0.5f) / 8.0f)) < 1e-5f);
        }
    }
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

TEST_CASE("Dilation fills padding ring by ring from covered neighbours and keeps covered texels", "[bake]") {
    Image image(5, 1, 1, 0.0f), mask(5, 1, 1, 0.0f);
    image.at(1, 0) = 2.0f;
    image.at(3, 0) = 4.0f;
    mask.at(1, 0) = mask.at(3, 0) = 1.0f;
    image.at(0, 0) = 99.0f;  // padding content is replaced
    REQUIRE(dilatePadding(image, mask) == 3);
    REQUIRE(image.at(0, 0) == 2.0f);
    REQUIRE(image.at(2, 0) == 3.0f);  // mean of both neighbours
    REQUIRE(image.at(4, 0) == 4.0f);
    REQUIRE(image.at(1, 0) == 2.0f);
    Image wide(6, 1, 1, 0.0f), wideMask(6, 1, 1, 0.0f);
    wide.at(0, 0) = 1.0f;
    wideMask.at(0, 0) = 1.0f;
    REQUIRE(dilatePadding(wide, wideMask, 2) == 2);  // two passes reach two texels
    REQUIRE(wide.at(2, 0) == 1.0f);
    REQUIRE(wide.at(3, 0) == 0.0f);
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
