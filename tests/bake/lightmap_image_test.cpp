// The lightmap-lit image (lightmap/lightmap_image.h): each pixel is albedo × the lightmap read
// bilinearly at TEXCOORD_1 (v down the image, as the viewer reads it), plus emission; a
// surface outside every lightmap shows albedo × the viewer's unlit level; n × n reads a pixel
// give the lightmap's mean over the pixel; the bake writes it beside its own image, and it
// agrees with that image where the lightmap resolves the light.
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/bake_settings.h"
#include "core/settings_table.h"
#include "lightmap/lightmap_image.h"
#include "receivers/receivers.h"

#include "core/image_io.h"
#include "export/lightmap_encoding.h"
#include "metrics/metrics.h"
#include "support/paths.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/trace_scene.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

using namespace vl;
namespace fs = std::filesystem;

namespace {

// The square [x0, x1] × [z0, z1] at height 0 facing +Y (toward a camera above it);
// TEXCOORD_1 u = (x − x0)/(x1 − x0), v = (z − z0)/(z1 − z0), unless `withUv1` is false.
Mesh groundQuad(const std::string& name, float x0, float x1, float z0, float z1, int material, bool withUv1 = true) {
    Mesh mesh;
    mesh.name = name;
    mesh.material = material;
    mesh.positions = {{x0, 0, z0}, {x1, 0, z0}, {x1, 0, z1}, {x0, 0, z1}};
    mesh.normals.assign(4, vec3(0, 1, 0));
    if (withUv1) mesh.uv1 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    mesh.indices = {0, 2, 1, 0, 3, 2};
    return mesh;
}

int addMaterial(Scene& scene, vec3 albedo, vec3 emission = vec3(0.0f)) {
    Material m;
    m.baseColorFactor = vec4(albedo, 1.0f);
    m.emissiveFactor = emission;
    m.metallic = 0.0f;
    m.doubleSided = true;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

// A camera at `position` looking straight down at the ground, +x to the image's right, 1 rad high.
Camera cameraLookingDown(vec3 position) {
    Camera camera;
    camera.position = position;
    camera.forward = vec3(0.0f, -1.0f, 0.0f);
    camera.up = vec3(0.0f, 0.0f, -1.0f);
    camera.yfov = 1.0f;
    return camera;
}

// A lightmap whose every texel differs from the others, and from its mirror image in v.
Image patternLightmap(int width, int height) {
    Image texels(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) texels.setRgb(x, y, vec3(1.0f + x, 0.5f + 2.0f * y, 0.25f * (1 + x) * (1 + y)));
    return texels;
}

// Bilinear between texel centres (i + ½)/size, clamped to the edge, row 0 at v = 0: what the
// viewer's lightmapAt computes, written out again here in double.
glm::dvec3 expectedLight(const Image& texels, double u, double v) {
    const double px = u * texels.width - 0.5, py = v * texels.height - 0.5;
    const double x0 = std::floor(px), y0 = std::floor(py);
    const auto at = [&](double x, double y) {
        const int xi = std::clamp(int(x), 0, texels.width - 1), yi = std::clamp(int(y), 0, texels.height - 1);
        return glm::dvec3(texels.rgb(xi, yi));
    };
    const double fx = px - x0, fy = py - y0;
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

}  // namespace

TEST_CASE("The lightmap is read bilinearly between texel centres with v down the image, clamped at its edges",
          "[bake]") {
    const Image texels = patternLightmap(8, 4);
    // A texel's centre gives the texel; v near 0 is the image's top row, not its bottom.
    CHECK(sampleLightmap(texels, vec2(2.5f / 8, 1.5f / 4)) == texels.rgb(2, 1));
    CHECK(sampleLightmap(texels, vec2(0.5f / 8, 0.5f / 4)) == texels.rgb(0, 0));
    CHECK(sampleLightmap(texels, vec2(0.5f / 8, 3.5f / 4)) == texels.rgb(0, 3));
    // Half way between two centres: their mean.
    const vec3 between = sampleLightmap(texels, vec2(3.0f / 8, 1.5f / 4));
    for (int c = 0; c < 3; ++c) CHECK(between[c] == Approx(0.5f * (texels.rgb(2, 1)[c] + texels.rgb(3, 1)[c])).epsilon(1e-6));
    // Outside the image the edge texels hold, as the viewer's clamped texelFetch.
    CHECK(sampleLightmap(texels, vec2(-3.0f, 0.5f / 4)) == texels.rgb(0, 0));
    CHECK(sampleLightmap(texels, vec2(5.0f, 7.0f)) == texels.rgb(7, 3));
    CHECK(sampleLightmap(texels, vec2(NAN, 0.5f)) == vec3(0.0f));
}

TEST_CASE("A lightmap-lit pixel is albedo × the bilinear lightmap at its TEXCOORD_1, and a surface outside every "
          "lightmap is albedo × the viewer's unlit level plus its emission",
          "[bake]") {
    Scene scene;
    scene.sourcePath = "lightmap-image.gltf";
    const vec3 floorAlbedo(0.25f, 0.5f, 0.75f), lampAlbedo(0.5f, 0.4f, 0.3f), lampEmission(2.0f, 3.0f, 4.0f);
    const vec3 plainAlbedo(0.8f, 0.4f, 0.2f);
    scene.meshes.push_back(groundQuad("floor", -2.0f, 0.0f, -1.0f, 1.0f, addMaterial(scene, floorAlbedo)));
    scene.meshes.push_back(groundQuad("lamp", 0.2f, 1.0f, -1.0f, 0.0f, addMaterial(scene, lampAlbedo, lampEmission)));
    // Listed in the lightmap below but without TEXCOORD_1: the viewer has nothing to read it by.
    scene.meshes.push_back(groundQuad("plain", 0.2f, 1.0f, 0.1f, 1.0f, addMaterial(scene, plainAlbedo), false));

    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    const CameraModel model = makeCameraModel(cameraLookingDown(vec3(-0.5f, 4.0f, 0.0f)), 48, 40);
    const CameraReceivers receivers = buildCameraReceivers(trace, bvh, model);  // the same single ray a pixel

    const Image texels = patternLightmap(8, 4);
    const Image image = renderLightmapImage(receivers, trace, bvh, model, 1, scene, triangles, {{{0, 2}, texels}});
    REQUIRE(image.width == 48);
    REQUIRE(image.height == 40);

    int counted[3] = {0, 0, 0};
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const size_t element = size_t(y) * size_t(image.width) + size_t(x);
            INFO("pixel " << x << ", " << y);
            if (!receivers.receivers.covered(element)) {
                CHECK(image.rgb(x, y) == vec3(0.0f));  // no sky: the background is black
                continue;
            }
            REQUIRE(receivers.receivers.sampleCount(element) == 1);  // one ray per pixel
            const SurfaceSample& s = receivers.receivers.samples[receivers.receivers.begin[element]];
            REQUIRE(s.weight == 1.0f);
            const uint32_t mesh = triangles.meshIndex[s.triangle];
            glm::dvec3 expected;
            if (mesh == 0) {
                const double u = (s.position.x + 2.0) / 2.0, v = (s.position.z + 1.0) / 2.0;
                expected = glm::dvec3(floorAlbedo) * expectedLight(texels, u, v);
            } else if (mesh == 1) {
                expected = glm::dvec3(lampAlbedo) * double(kUnlitLight) + glm::dvec3(lampEmission);
            } else {
                expected = glm::dvec3(plainAlbedo) * double(kUnlitLight);
            }
            ++counted[mesh];
            for (int c = 0; c < 3; ++c) CHECK(std::abs(image.rgb(x, y)[c] - expected[c]) <= 1e-5 * std::max(1.0, expected[c]));
        }
    INFO("pixels on the floor, the lamp, the plain quad: " << counted[0] << ", " << counted[1] << ", " << counted[2]);
    CHECK(counted[0] > 300);
    CHECK(counted[1] > 50);
    CHECK(counted[2] > 50);
    CHECK(kUnlitLight == 0.1f);  // tools/viewer/viewer.js UNLIT_LEVEL
}

TEST_CASE("A lightmap-lit pixel of n × n reads is the lightmap's mean over the pixel, where one read shows one "
          "side of a sharp edge",
          "[bake]") {
    // A floor seen from straight above, its lightmap dark (0) left of u = ½ and bright (1)
    // right of it, 128 texels across: about 3.3 texels a pixel, so the bilinear step (one texel
    // wide) lies inside a pixel. The truth is the lightmap's integral over each pixel's
    // footprint, here by 64 × 64 points on the floor. With n × n rays the error is the
    // midpoint rule's on strata of side 1/n: at most L / (4n) for a light changing by L a pixel.
    Scene scene;
    scene.sourcePath = "lightmap-image-box.gltf";
    const vec3 albedo(0.5f);
    scene.meshes.push_back(groundQuad("floor", -2.0f, 0.0f, -1.0f, 1.0f, addMaterial(scene, albedo)));
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    const TraceScene trace = TraceScene::build(scene, triangles);
    // The step a quarter of a pixel (1.28 cm on the floor) right of the image's middle column
    // edge: the pixel it crosses is three quarters bright, and its centre reads all bright.
    const CameraModel model = makeCameraModel(cameraLookingDown(vec3(-1.0128f, 1.5f, 0.0f)), 32, 32);
    const CameraReceivers receivers = buildCameraReceivers(trace, bvh, model);
    Image texels(128, 4, 3);
    for (int y = 0; y < texels.height; ++y)
        for (int x = 0; x < texels.width; ++x) texels.setRgb(x, y, vec3(x < 64 ? 0.0f : 1.0f));

    // The floor's u at a film point, by the ray's crossing of y = 0.
    const auto uAt = [&](double fx, double fy) {
        const Ray ray = pinholeRay(model, vec2(float(fx), float(fy)));
        const double t = -double(ray.origin.y) / double(ray.direction.y);
        return (double(ray.origin.x) + t * double(ray.direction.x) + 2.0) / 2.0;
    };
    const double texelsPerPixel = (uAt(16.5, 16.0) - uAt(15.5, 16.0)) * texels.width;
    INFO("texels a pixel: " << texelsPerPixel);
    REQUIRE(texelsPerPixel > 2.0);
    const double L = albedo.x * texelsPerPixel;  // the light's change a pixel across the step
    const Image box = renderLightmapImage(receivers, trace, bvh, model, 8, scene, triangles, {{{0}, texels}});
    const Image centre = renderLightmapImage(receivers, trace, bvh, model, 1, scene, triangles, {{{0}, texels}});
    double worstBox = 0.0, worstCentre = 0.0;
    int edgePixels = 0;
    for (int y = 0; y < model.height; ++y)
        for (int x = 0; x < model.width; ++x) {
            double truth = 0.0;
            constexpr int kPoints = 64;
            for (int j = 0; j < kPoints; ++j)
                for (int i = 0; i < kPoints; ++i)
                    truth += expectedLight(texels, uAt(x + (i + 0.5) / kPoints, y + (j + 0.5) / kPoints), 0.5).x;
            truth *= albedo.x / double(kPoints * kPoints);
            if (truth > 0.01 && truth < albedo.x - 0.01) ++edgePixels;
            worstBox = std::max(worstBox, std::abs(double(box.at(x, y, 0)) - truth));
            worstCentre = std::max(worstCentre, std::abs(double(centre.at(x, y, 0)) - truth));
        }
    INFO("pixels the step crosses: " << edgePixels << "; worst error, 8 x 8 reads " << worstBox << ", one read "
                                      << worstCentre << ", bound " << L / 32.0);
    CHECK(edgePixels >= 32);
    CHECK(worstBox <= L / (4.0 * 8));
    CHECK(worstCentre > 0.2 * albedo.x);  // one read a pixel: a fifth of the step or more
}

TEST_CASE("The lightmap-lit image reads the texels scene.glb carries, as the viewer decodes them", "[bake]") {
    Image total(5, 3, 3);
    for (size_t k = 0; k < total.pixels.size(); ++k) total.pixels[k] = 0.003f * float(k * k) + 0.01f;
    const RgbmImage encoded = encodeRgbm(total);
    const Image shipped = shippedLightmapTexels(total);
    for (int y = 0; y < total.height; ++y)
        for (int x = 0; x < total.width; ++x)
            for (int c = 0; c < 3; ++c) {
                // The viewer: texel.rgb · texel.a · intensity, each byte / 255.
                const uint8_t* t = &encoded.rgba[(size_t(y) * size_t(total.width) + size_t(x)) * 4];
                const double viewer = (t[c] / 255.0) * (t[3] / 255.0) * encoded.range;
                CHECK(shipped.at(x, y, c) == Approx(viewer).epsilon(1e-6));
                CHECK(shipped.at(x, y, c) == Approx(total.at(x, y, c)).epsilon(0.02).margin(encoded.range / 255.0 / 255.0));
            }
}

TEST_CASE("A bake writes each camera's lightmap-lit image beside its own", "[bake]") {
    // The Cornell box with a 128² lightmap and a 96² image: the two images differ by where the
    // light comes from (a texel's, read bilinearly, against each pixel's own gather) and by
    // RGBM's steps. 2.3% here; the 4% bound leaves room for changes to the gather.
    const fs::path out = fs::path(test::tempDir("lightmap-image")) / "cornell";
    fs::remove_all(out);
    BakeJob job;
    job.scenePath = test::sourceDir() + "/scenes/cornell_box.gltf";
    job.outputDir = out.string();
    job.settings.quiet = true;
    job.settings.outputs.grids = false;
    job.settings.outputs.gltf = false;
    job.settings.lightmap.width = job.settings.lightmap.height = 128;
    job.settings.imageWidth = job.settings.imageHeight = 96;
    // The image's own 2 × 2 rays a pixel, so the two find the same edges.
    job.settings.lightmapImageSubsamples = job.settings.imageSubsamples;
    const BakeReport report = runBake(job);
    INFO(report.error);
    REQUIRE(report.ok);
    for (const char* file : {"image_lightmapped.exr", "image_lightmapped.png"}) {
        INFO(file);
        CHECK(std::find(report.files.begin(), report.files.end(), file) != report.files.end());
    }
    const Image lit = readImage((out / "image_lightmapped.exr").string());
    const Image image = readImage((out / "image.exr").string());
    REQUIRE(lit.width == 96);
    REQUIRE(lit.height == 96);
    // The emitter seen directly is the same emission in both; leave it out, as the bench does.
    Image mask(image.width, image.height, 1, 1.0f);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            if (maxComponent(image.rgb(x, y)) > 5.0f) mask.at(x, y) = 0.0f;
    MetricOptions options;
    options.mask = &mask;
    const ErrorMetrics error = compareImages(lit, image, options);
    INFO("lightmap-lit against the bake's image: relative RMSE " << error.relativeRmse);
    CHECK(error.relativeRmse < 0.04);

    // Without the setting, no such file.
    fs::remove_all(out);
    job.settings.outputs.lightmapImage = false;
    const BakeReport without = runBake(job);
    REQUIRE(without.ok);
    CHECK_FALSE(fs::exists(out / "image_lightmapped.exr"));
    CHECK(std::find(without.files.begin(), without.files.end(), "image_lightmapped.png") == without.files.end());
}

TEST_CASE("lightmap-image-subsamples takes 1 to 16 rays a side and refuses the rest by name", "[bake]") {
    BakeSettings settings;
    CHECK(settings.lightmapImageSubsamples == 4);
    applySetting(bakeSettingsTable(), settings, "lightmap-image-subsamples", "16");
    CHECK(settings.lightmapImageSubsamples == 16);
    for (const char* bad : {"0", "17", "-1", "four"}) {
        INFO(bad);
        CHECK_THROWS_WITH(applySetting(bakeSettingsTable(), settings, "lightmap-image-subsamples", bad),
                          Catch::Contains("lightmap-image-subsamples"));
    }
    CHECK(settings.lightmapImageSubsamples == 16);
    CHECK_THAT(describeBakeSettings(settings), Catch::Contains("lightmap-image-subsamples=16"));
}

TEST_CASE("A sun the engine draws (light bake indirect): the lightmap leaves its direct light out and the "
          "lightmap-lit image draws it exact per read, sharp at a slit's edge",
          "[bake]") {
    // A floor 2 × 2 m (albedo 0.5, a 32² lightmap: 6.25 cm texels) under a sun straight down
    // through a slit 20 cm wide in a roof 0.5 m up. A camera 0.4 m over the floor, under the
    // roof, sees the floor 0.44 m across in 64 pixels (6.8 mm each). The sun lights the floor
    // exactly over |x| < 0.1: E = 3 W/m², so a pixel there shows 0.5 · 3/π plus a little
    // indirect light, and one beside it in the shade only that little.
    Scene scene;
    scene.sourcePath = "slit (test)";
    const float albedo = 0.5f, sunE = 3.0f, slit = 0.1f;
    const int floor = addMaterial(scene, vec3(albedo));
    const int roof = addMaterial(scene, vec3(albedo));
    scene.meshes.push_back(groundQuad("floor", -1.0f, 1.0f, -1.0f, 1.0f, floor));
    for (const float side : {-1.0f, 1.0f}) {
        Mesh half = groundQuad(side < 0 ? "roof-" : "roof+", side < 0 ? -1.5f : slit, side < 0 ? -slit : 1.5f, -1.5f,
                               1.5f, roof, false);
        for (vec3& p : half.positions) p.y = 0.5f;
        scene.meshes.push_back(half);
    }
    Light sun;
    sun.name = "sun";
    sun.type = LightType::Directional;
    sun.direction = vec3(0, -1, 0);
    sun.intensity = sunE;
    scene.lights.push_back(sun);
    Camera camera = cameraLookingDown(vec3(0.0f, 0.4f, 0.0f));
    camera.name = "down";
    scene.cameras.push_back(camera);

    BakeSettings settings;
    settings.quiet = true;
    settings.generateLightmapUvs = false;  // the roof, unseen, keeps no lightmap
    settings.outputs.grids = settings.outputs.gltf = false;
    settings.lightmap.width = settings.lightmap.height = 32;
    settings.imageWidth = settings.imageHeight = 64;
    const auto bakeIn = [&](LightBake mode) {
        settings.lightBake = mode;
        Diagnostics diagnostics(false, false);
        return bake(scene, settings, diagnostics);
    };
    const BakeResult all = bakeIn(LightBake::All), drawn = bakeIn(LightBake::Indirect);
    REQUIRE(drawn.lightmaps.size() == 1);
    REQUIRE(drawn.images.size() == 1);

    // The lightmap holds no direct light (the sun is the only light), and the same indirect
    // light as when the sun is baked whole: its bounces are the bake's either way.
    double directAll = 0.0, indirectAll = 0.0, indirectDrawn = 0.0;
    for (size_t k = 0; k < drawn.lightmaps[0].direct.pixels.size(); ++k) {
        CHECK(drawn.lightmaps[0].direct.pixels[k] == 0.0f);
        directAll += all.lightmaps[0].direct.pixels[k];
        indirectAll += all.lightmaps[0].indirect.pixels[k];
        indirectDrawn += drawn.lightmaps[0].indirect.pixels[k];
    }
    CHECK(directAll > 0.0);
    CHECK(indirectDrawn == Approx(indirectAll).epsilon(0.01));

    // Along the middle row: pixels whose footprint lies wholly in the sun or wholly in the
    // shade, a pixel or more from the edge.
    const float halfWidth = 0.4f * std::tan(0.5f), pixel = 2.0f * halfWidth / 64.0f;
    const double lit = albedo * sunE / kPi;
    const auto worst = [&](const BakeResult& result, bool inSun) {
        double err = 0.0;
        for (int x = 0; x < 64; ++x) {
            const float worldX = ((x + 0.5f) / 64.0f * 2.0f - 1.0f) * halfWidth;
            const float fromEdge = std::abs(worldX) - slit;  // < 0 in the sun
            if (inSun ? fromEdge > -1.5f * pixel : fromEdge < 1.5f * pixel) continue;
            const double value = result.images[0].lightmapped.at(x, 32, 1);
            err = std::max(err, std::abs(value - (inSun ? lit : 0.0)) / lit);
        }
        return err;
    };
    // Exact per read: the sun's pixels within the indirect light (a few percent), the shade's too.
    CHECK(worst(drawn, true) < 0.05);
    CHECK(worst(drawn, false) < 0.05);
    // Baked whole, the sun's edge is a texel's blur: pixels a pixel or two off the edge are
    // far from either side.
    CHECK(std::max(worst(all, true), worst(all, false)) > 0.15);
    // The camera's own image is the whole light in both.
    CHECK(compareImages(drawn.images[0].beauty, all.images[0].beauty).relativeRmse < 1e-6);
}

namespace {

// The share of a sun's cap (half-angle `halfAngle` about straight up, uniform in solid angle)
// that a floor point `x` metres beside a roof's straight edge (the roof over x < 0, `height` up)
// sees: a direction w passes the edge where x + height · w_x / w_y ≥ 0. By a midpoint sum over
// the cap, 400 × 400 cells in (cos θ, φ), independent of the bake's sampling.
double visibleCapShare(double x, double height, double halfAngle) {
    constexpr int kCells = 400;
    const double cosMax = std::cos(halfAngle);
    int open = 0;
    for (int i = 0; i < kCells; ++i) {
        const double cosTheta = 1.0 - (i + 0.5) / kCells * (1.0 - cosMax);
        const double sinTheta = std::sqrt(1.0 - cosTheta * cosTheta);
        for (int j = 0; j < kCells; ++j) {
            const double phi = 2.0 * kPi * (j + 0.5) / kCells;
            if (x + height * sinTheta * std::cos(phi) / cosTheta >= 0.0) ++open;
        }
    }
    return double(open) / double(kCells * kCells);
}

}  // namespace

TEST_CASE("A shadowmask holds a sun's visibility per texel: over a penumbra, the disk's visible share, and the "
          "lightmap-lit image draws the sun unshadowed times the mask",
          "[bake]") {
    // A floor 2 × 2 m (128² lightmap: 1.56 cm texels) under a roof over x < 0, 0.5 m up, and a
    // sun 20° across straight down: the penumbra runs over |x| < 0.5 · tan 10° = 8.8 cm, about
    // eleven texels. The mask there is the share of the sun's disk a texel's centre sees
    // (visibleCapShare); 64 strata over the disk (kShadowmaskStrata) give it to a few 1/64
    Scene scene;
    scene.sourcePath = "edge (test)";
    const float albedo = 0.5f, sunE = 3.0f, height = 0.5f, diameter = 20.0f * kPi / 180.0f;
    const int floor = addMaterial(scene, vec3(albedo));
    scene.meshes.push_back(groundQuad("floor", -1.0f, 1.0f, -1.0f, 1.0f, floor));
    Mesh roof = groundQuad("roof", -2.0f, 0.0f, -2.0f, 2.0f, addMaterial(scene, vec3(albedo)), false);
    for (vec3& p : roof.positions) p.y = height;
    scene.meshes.push_back(roof);
    Light sun;
    sun.name = "sun";
    sun.type = LightType::Directional;
    sun.direction = vec3(0, -1, 0);
    sun.intensity = sunE;
    sun.angularDiameter = diameter;
    scene.lights.push_back(sun);
    // A second sun, a point, slanted along +x: the roof's edge hides it over x < 0.5 · 0.5 =
    // 0.25, so its channel (1) differs from the first's, and the view must read each light's own.
    Light slanted = sun;
    slanted.name = "slanted";
    slanted.direction = glm::normalize(vec3(0.5f, -1.0f, 0.0f));
    slanted.angularDiameter = 0.0f;
    slanted.intensity = 1.0f;
    scene.lights.push_back(slanted);
    Camera camera = cameraLookingDown(vec3(0.0f, 0.3f, 0.0f));
    camera.name = "down";
    scene.cameras.push_back(camera);

    BakeSettings settings;
    settings.quiet = true;
    settings.generateLightmapUvs = false;
    settings.outputs.grids = settings.outputs.gltf = false;
    const int N = 128;
    settings.lightmap.width = settings.lightmap.height = N;
    settings.imageWidth = settings.imageHeight = 64;
    const auto bakeIn = [&](LightBake mode) {
        settings.lightBake = mode;
        Diagnostics diagnostics(false, false);
        return bake(scene, settings, diagnostics);
    };
    const BakeResult masked = bakeIn(LightBake::Shadowmask), drawn = bakeIn(LightBake::Indirect);
    REQUIRE(masked.lightmaps.size() == 1);
    const BakedLightmap& lightmap = masked.lightmaps[0];
    REQUIRE(lightmap.shadowmask.channels == kShadowmaskChannels);
    REQUIRE(lightmap.shadowmask.width == N);
    CHECK(drawn.lightmaps[0].shadowmask.empty());

    // The lightmap holds none of the sun's direct light, as in indirect mode.
    for (float v : lightmap.direct.pixels) CHECK(v == 0.0f);

    // Row N/2 (z = 1/N), texel i at x = 2(i + ½)/N − 1.
    const double halfAngle = 0.5 * diameter, penumbra = height * std::tan(halfAngle);
    double maskSum = 0.0, shareSum = 0.0, worst = 0.0;
    int inPenumbra = 0;
    for (int i = 0; i < N; ++i) {
        const double x = 2.0 * (i + 0.5) / N - 1.0;
        const double share = visibleCapShare(x, height, halfAngle);
        const float mask = lightmap.shadowmask.at(i, N / 2, 0);
        if (std::abs(x) > penumbra + 0.02) {  // beyond the penumbra: wholly seen or wholly hidden
            CHECK(mask == (x > 0.0 ? 1.0f : 0.0f));
            continue;
        }
        if (std::abs(x) >= penumbra) continue;
        ++inPenumbra;
        maskSum += mask;
        shareSum += share;
        worst = std::max(worst, std::abs(double(mask) - share));
    }
    // The slanted sun's channel: hidden over x < 0.25, seen beyond (a texel from the edge);
    // the channels without a light hold 1 (opaque alpha).
    for (int i = 0; i < N; ++i) {
        const double x = 2.0 * (i + 0.5) / N - 1.0;
        if (std::abs(x - 0.25) > 2.0 / N) CHECK(lightmap.shadowmask.at(i, N / 2, 1) == (x > 0.25 ? 1.0f : 0.0f));
    }
    for (size_t t = 0; t < size_t(N) * N; ++t)
        for (int c = 2; c < kShadowmaskChannels; ++c) CHECK(lightmap.shadowmask.pixels[4 * t + size_t(c)] == 1.0f);
    REQUIRE(inPenumbra >= 10);
    CHECK(maskSum / inPenumbra == Approx(shareSum / inPenumbra).margin(0.01));
    CHECK(worst < 0.05);

    // The lightmap-lit view: each sun unshadowed times its channel of the bilinear mask, against
    // the same view with the suns drawn exact per read (indirect mode, 16 stratified directions
    // a read in the penumbra: a few percent of noise a pixel). The edge runs along the image's columns, so
    // each column's mean over 48 rows takes that noise down: they must hold the same light
    // within 2% of the sunlit level, the penumbra included (its ramp spans eleven texels).
    const double lit = albedo * sunE / kPi;
    double worstColumn = 0.0;
    for (int x = 0; x < 64; ++x) {
        double difference = 0.0;
        for (int y = 8; y < 56; ++y)
            difference += double(masked.images[0].lightmapped.at(x, y, 1)) - double(drawn.images[0].lightmapped.at(x, y, 1));
        worstColumn = std::max(worstColumn, std::abs(difference / 48.0) / lit);
    }
    CHECK(worstColumn < 0.02);
}

TEST_CASE("A fifth shadowmask light, or one glTF light placed twice as a shadowmask light, is refused by name",
          "[bake]") {
    Scene scene;
    scene.sourcePath = "lamps.gltf";
    for (int k = 0; k < 5; ++k) {
        Light lamp;
        lamp.name = "lamp" + std::to_string(k);
        lamp.bake = LightBake::Shadowmask;
        lamp.sourceLight = k;
        scene.lights.push_back(lamp);
    }
    Scene four = scene;
    four.lights.pop_back();
    resolveLightBake(four, LightBake::All);
    for (int k = 0; k < 4; ++k) CHECK(four.lights[size_t(k)].maskChannel == k);
    CHECK_THROWS_WITH(resolveLightBake(scene, LightBake::All),
                      Catch::Contains("lamps.gltf") && Catch::Contains("light 'lamp4' is a fifth shadowmask light") &&
                          Catch::Contains("'lamp0', 'lamp1', 'lamp2', 'lamp3'"));
    // The setting makes every light without a mode of its own a shadowmask light.
    Scene bySetting = four;
    for (Light& light : bySetting.lights) light.bake = LightBake::Unset;
    bySetting.lights[0].bake = LightBake::All;
    resolveLightBake(bySetting, LightBake::Shadowmask);
    CHECK(bySetting.lights[0].maskChannel == -1);
    CHECK(bySetting.lights[3].maskChannel == 2);
    Scene twice = four;
    twice.lights[1].sourceLight = 0;
    CHECK_THROWS_WITH(resolveLightBake(twice, LightBake::All),
                      Catch::Contains("light 'lamp1' (KHR_lights_punctual light 0) is placed by several nodes"));
}
