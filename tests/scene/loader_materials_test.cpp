// Materials, textures, punctual lights and cameras: values and units as scene.h states.
#include "gltf_builder.h"
#include "scene_checks.h"

#include "core/image_io.h"
#include "scene/surface.h"

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

std::string dir() { return tempDir("scene-loader-materials"); }

// sRGB decoding, written out here so the test does not use the code it checks.
float srgbByte(int byte) {
    const double c = byte / 255.0;
    return static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

// A 2×2 PNG whose bytes are exactly the sRGB codes given (row-major from the top).
std::vector<unsigned char> png2x2(const std::vector<std::array<int, 4>>& texels) {
    Image image(2, 2, 4);
    for (int i = 0; i < 4; ++i)
        for (int c = 0; c < 4; ++c)
            image.pixels[static_cast<size_t>(4 * i + c)] =
                c < 3 ? srgbByte(texels[static_cast<size_t>(i)][static_cast<size_t>(c)])
                      : texels[static_cast<size_t>(i)][3] / 255.0f;
    const std::string path = dir() + "/texture.png";
    writePngSrgb(image, path);
    return readBytes(path);
}

const std::vector<std::array<int, 4>> kTexels{
    {255, 0, 0, 255},     // top left
    {128, 255, 64, 255},  // top right
    {0, 0, 255, 255},     // bottom left
    {255, 255, 255, 51},  // bottom right
};

vec4 texelValue(int i) {
    const auto& t = kTexels[static_cast<size_t>(i)];
    return vec4(srgbByte(t[0]), srgbByte(t[1]), srgbByte(t[2]), t[3] / 255.0f);
}

std::string oneTriangle(GltfBuilder& b, const std::string& extraAttributes, int material) {
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    return R"("meshes": [{"name": "Tri", "primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
           extraAttributes + R"(}, "material": )" + std::to_string(material) + R"(}]}],
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}])";
}

}  // namespace

TEST_CASE("Material factors and extensions are read with their units", "[scene]") {
    GltfBuilder b;
    const std::string members = oneTriangle(b, "", 0) + R"(, "materials": [{
        "name": "Lamp", "doubleSided": true, "alphaMode": "MASK", "alphaCutoff": 0.25,
        "emissiveFactor": [1, 0.5, 0.25],
        "pbrMetallicRoughness": {"baseColorFactor": [0.73, 0.5, 0.25, 0.75], "metallicFactor": 0.125, "roughnessFactor": 0.375},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 17},
                       "KHR_materials_transmission": {"transmissionFactor": 0.875},
                       "KHR_materials_ior": {"ior": 1.33}}}],
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior"],
        "extensionsRequired": ["KHR_materials_emissive_strength"])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "material", members));
    REQUIRE(scene.materials.size() == 1);
    const Material& m = scene.materials[0];
    CHECK(m.name == "Lamp");
    CHECK_NEAR(m.baseColorFactor, vec4(0.73f, 0.5f, 0.25f, 0.75f));
    CHECK(m.metallic == 0.125f);
    CHECK(m.roughness == 0.375f);
    CHECK_NEAR(m.emission(), vec3(17, 8.5f, 4.25f), 1e-5f);
    CHECK(m.alphaMode == AlphaMode::Mask);
    CHECK(m.alphaCutoff == 0.25f);
    CHECK(m.doubleSided);
    CHECK(m.transmission == 0.875f);
    CHECK(m.ior == Approx(1.33f));
    REQUIRE(scene.meshes.size() == 1);
    CHECK(scene.meshes[0].material == 0);
    CHECK(scene.hasEmitters());
    CHECK_NEAR(baseColorAt(scene, scene.meshes[0], 0, vec2(0.3f, 0.3f)), vec4(0.73f, 0.5f, 0.25f, 0.75f));
    CHECK_NEAR(emissionAt(scene, scene.meshes[0], 0, vec2(0.3f, 0.3f)), vec3(17, 8.5f, 4.25f), 1e-5f);
    CHECK(scene.warnings.empty());
}

TEST_CASE("A primitive without a material gets the glTF default material", "[scene]") {
    GltfBuilder b;
    const Scene scene = loadQuiet(b.writeGltf(dir(), "default_material", oneTriangle(b, "", -1)));
    REQUIRE(scene.meshes.size() == 1);
    CHECK(scene.meshes[0].material == -1);
    const Material& m = scene.materialOf(scene.meshes[0]);
    CHECK_NEAR(m.baseColorFactor, vec4(1.0f));
    CHECK_FALSE(scene.hasEmitters());
    CHECK_NEAR(emissionAt(scene, scene.meshes[0], 0, vec2(0.2f)), vec3(0.0f));
}

TEST_CASE("emissiveFactor above 1 is kept with a warning and refused under strict", "[scene]") {
    GltfBuilder b;
    const std::string members = oneTriangle(b, "", 0) + R"(, "materials": [{"name": "Hot", "emissiveFactor": [10, 10, 10]}])";
    const std::string path = b.writeGltf(dir(), "emissive_above_one", members);
    const Scene scene = loadQuiet(path);
    CHECK_NEAR(scene.materials[0].emission(), vec3(10.0f));
    REQUIRE(scene.warnings.size() == 1);
    CHECK_THAT(scene.warnings[0], Catch::Contains(path) && Catch::Contains("material 0 'Hot'") &&
                                      Catch::Contains("emissiveFactor above 1"));
    CHECK_THROWS_AS(loadQuiet(path, true), InputError);
}

TEST_CASE("Base colour textures are sRGB-decoded and sampled through KHR_texture_transform and COLOR_0", "[scene]") {
    GltfBuilder b;
    // Vertex 0: TEXCOORD_0 (0, 1.9), TEXCOORD_1 (0.2, 0.6), COLOR_0 (1, 0.5, 1, 1).
    // The transform (scale 0.5, offset (0.5, 0)) on set 1 — the extension's texCoord overrides
    // the textureInfo's 0 — gives uv (0.6, 0.3): texel (1, 0), top right. Set 0 would give
    // (0.5, 0.95) → bottom right; set 1 without the transform (0.2, 0.6) → bottom left.
    const int uv0 = b.vec2({0, 1.9f, 0, 0, 0, 0});
    const int uv1 = b.vec2({0.2f, 0.6f, 0, 0, 0, 0});
    const int color = b.floats({1, 0.5f, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1}, 4, "VEC4");
    const std::string attributes = R"(, "TEXCOORD_0": )" + std::to_string(uv0) + R"(, "TEXCOORD_1": )" +
                                   std::to_string(uv1) + R"(, "COLOR_0": )" + std::to_string(color);
    const std::string members = oneTriangle(b, attributes, 0) + R"(,
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1, 1, 1],
            "baseColorTexture": {"index": 0, "texCoord": 0, "extensions": {"KHR_texture_transform":
                {"offset": [0.5, 0], "scale": [0.5, 0.5], "texCoord": 1}}}}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "wrapS": 33071, "wrapT": 33648}],
        "images": [{"name": "checker", "uri": "data:image/png;base64,)" + base64(png2x2(kTexels)) + R"("}],
        "extensionsUsed": ["KHR_texture_transform"])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "textured", members));
    REQUIRE(scene.textures.size() == 1);
    const Texture& texture = scene.textures[0];
    CHECK(texture.name == "checker");
    CHECK(texture.nearest);
    CHECK(texture.wrapS == WrapMode::ClampToEdge);
    CHECK(texture.wrapT == WrapMode::MirroredRepeat);
    REQUIRE(texture.image.width == 2);
    REQUIRE(texture.image.channels == 4);
    for (int i = 0; i < 4; ++i)
        CHECK_NEAR(vec4(texture.image.pixels[4 * i], texture.image.pixels[4 * i + 1], texture.image.pixels[4 * i + 2],
                        texture.image.pixels[4 * i + 3]),
                   texelValue(i), 1e-6f);

    const Material& m = scene.materials[0];
    REQUIRE(m.baseColorTexture.valid());
    CHECK(m.baseColorTexture.texCoord == 1);
    CHECK_NEAR(m.baseColorTexture.transform.offset, vec2(0.5f, 0.0f));
    CHECK_NEAR(m.baseColorTexture.transform.scale, vec2(0.5f));

    const vec4 expected = vec4(0.5f, 1, 1, 1) * texelValue(1) * vec4(1, 0.5f, 1, 1);
    CHECK_NEAR(baseColorAt(scene, scene.meshes[0], 0, vec2(0.0f)), expected, 1e-6f);
}

TEST_CASE("Emissive textures from a GLB buffer view scale the emission", "[scene]") {
    GltfBuilder b;
    const std::vector<unsigned char> png = png2x2(kTexels);
    const int imageView = b.view(png);
    const int uv0 = b.vec2({0.75f, 0.75f, 0.75f, 0.75f, 0.75f, 0.75f});  // bottom-right texel centre
    const std::string members = oneTriangle(b, R"(, "TEXCOORD_0": )" + std::to_string(uv0), 0) + R"(,
        "materials": [{"emissiveFactor": [1, 1, 0.5], "emissiveTexture": {"index": 0},
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": )" + std::to_string(imageView) + R"(, "mimeType": "image/png"}])";
    const Scene scene = loadQuiet(b.writeGlb(dir(), "emissive_texture", members));
    REQUIRE(scene.textures.size() == 1);
    CHECK_FALSE(scene.textures[0].nearest);
    CHECK(scene.textures[0].wrapS == WrapMode::Repeat);
    // Bilinear at a texel centre is that texel: white (alpha ignored for emission).
    CHECK_NEAR(emissionAt(scene, scene.meshes[0], 0, vec2(0.2f, 0.3f)), vec3(4, 4, 2), 1e-5f);
}

TEST_CASE("A missing image is a warning naming it and the texture is ignored", "[scene]") {
    GltfBuilder b;
    const std::string members = oneTriangle(b, "", 0) + R"(,
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.5, 1, 1], "baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}], "images": [{"uri": "no_such_image.png"}])";
    const std::string path = b.writeGltf(dir(), "missing_image", members);
    const Scene scene = loadQuiet(path);
    CHECK(scene.textures.empty());
    CHECK_FALSE(scene.materials[0].baseColorTexture.valid());
    CHECK(anyWarningContains(scene, "image 0 ('no_such_image.png') is missing"));
    CHECK_NEAR(baseColorAt(scene, scene.meshes[0], 0, vec2(0.1f)), vec4(0.25f, 0.5f, 1, 1));
    CHECK_THROWS_WITH(loadQuiet(path, true), Catch::Contains(path) && Catch::Contains("no_such_image.png"));
}

TEST_CASE("A texture without an image is a warning naming the texture", "[scene]") {
    GltfBuilder b;
    const std::string members = oneTriangle(b, "", 0) + R"(,
        "materials": [{"emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0}}],
        "textures": [{"name": "tex", "source": 0}])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "texture_without_image", members));
    CHECK(anyWarningContains(scene, "texture 0 'tex' refers to image 0, which does not exist"));
    CHECK_NEAR(emissionAt(scene, scene.meshes[0], 0, vec2(0.1f)), vec3(1.0f));
}

TEST_CASE("Punctual lights take the node's world transform and intensity over 683", "[scene]") {
    GltfBuilder b;
    // Node 0 translates by (1,0,0) and carries node 1 (spot, translated (0,3,0), rotated +90°
    // about X so its −Z axis points along +Y); node 2 has the point light; node 3 the
    // directional one with the default orientation.
    const std::string members = R"("extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "Bulb", "type": "point", "intensity": 683, "color": [1, 0.5, 0.25], "range": 12},
            {"type": "spot", "intensity": 1366, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
            {"type": "directional", "intensity": 341.5}]}},
        "scene": 0, "scenes": [{"nodes": [0, 2, 3]}],
        "nodes": [{"children": [1], "translation": [1, 0, 0]},
                  {"name": "SpotNode", "translation": [0, 3, 0], "rotation": [0.70710678118654752, 0, 0, 0.70710678118654752],
                   "extensions": {"KHR_lights_punctual": {"light": 1}}},
                  {"translation": [0, 2, -1], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                  {"extensions": {"KHR_lights_punctual": {"light": 2}}}])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "lights", members));
    REQUIRE(scene.lights.size() == 3);
    // Traversal order: node 0's subtree (the spot), then node 2, then node 3.
    const Light& spot = scene.lights[0];
    CHECK(spot.type == LightType::Spot);
    CHECK(spot.name == "SpotNode");
    CHECK(spot.intensity == Approx(2.0f));
    CHECK(spot.innerConeAngle == Approx(0.2f));
    CHECK(spot.outerConeAngle == Approx(0.5f));
    CHECK_NEAR(vl::test::world(scene, spot.position), vec3(1, 3, 0), 1e-6f);
    CHECK_NEAR(spot.direction, vec3(0, 1, 0), 1e-6f);

    const Light& point = scene.lights[1];
    CHECK(point.type == LightType::Point);
    CHECK(point.name == "Bulb");
    CHECK(point.intensity == Approx(1.0f));  // 683 cd → 1 W/sr
    CHECK(point.range == 12.0f);
    CHECK_NEAR(point.radiantIntensity(), vec3(1, 0.5f, 0.25f));
    CHECK_NEAR(vl::test::world(scene, point.position), vec3(0, 2, -1));

    const Light& sun = scene.lights[2];
    CHECK(sun.type == LightType::Directional);
    CHECK(sun.intensity == Approx(0.5f));  // 341.5 lx → 0.5 W/m²
    CHECK_NEAR(sun.direction, vec3(0, 0, -1));
    CHECK(sun.range == 0.0f);
}

TEST_CASE("Perspective cameras take the node's position forward and up", "[scene]") {
    GltfBuilder b;
    // Rotation +90° about Y maps −Z to −X; +Y stays +Y.
    const std::string members = R"("cameras": [{"name": "Main", "type": "perspective",
            "perspective": {"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1}},
            {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}],
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"camera": 0, "translation": [0, 1, 5], "rotation": [0, 0.70710678118654752, 0, 0.70710678118654752]},
                  {"camera": 1}])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "camera", members));
    REQUIRE(scene.cameras.size() == 1);
    const Camera& camera = scene.cameras[0];
    CHECK(camera.name == "Main");
    CHECK_NEAR(vl::test::world(scene, camera.position), vec3(0, 1, 5));
    CHECK_NEAR(camera.forward, vec3(-1, 0, 0), 1e-6f);
    CHECK_NEAR(camera.up, vec3(0, 1, 0), 1e-6f);
    CHECK(camera.yfov == 0.5f);
    CHECK(camera.aspectRatio == 1.5f);
    CHECK(anyWarningContains(scene, "camera 1 is orthographic"));
}
