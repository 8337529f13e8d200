// glTF out (export/gltf_export.h): the scene written back whole, its lightmaps attached.
#include "export/gltf_export.h"
#include "scene/gltf_loader.h"
#include "scene/gltf_model.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>

using namespace vl;

namespace {

ExportedLightmap grey(const std::string& name, std::vector<uint32_t> meshes, float value) {
    Image image(8, 8, 3, value);
    return {name, std::move(meshes), encodeRgbm(image)};
}

tinygltf::Model reread(const std::string& path) {
    tinygltf::Model model;
    gltf::EncodedImages encoded;
    readGltfModel(path, model, encoded);
    return model;
}

const tinygltf::Value* lightmapOf(const tinygltf::Material& material) {
    const auto it = material.extensions.find("MOZ_lightmap");
    return it == material.extensions.end() ? nullptr : &it->second;
}

}  // namespace

TEST_CASE("glTF out holds the scene's buffers and images in one .glb and points each material at its lightmap",
          "[export]") {
    // BoxTextured keeps its texture in a file beside it and its geometry in a .bin: the .glb
    // must carry both, and the box's one material must carry MOZ_lightmap.
    VL_SKIP_WITHOUT_SHARED();
    const std::string source = test::sharedDir() + "/scenes/khronos-sample-assets/Models/BoxTextured/glTF/BoxTextured.gltf";
    const Scene scene = loadGltf(source);
    REQUIRE(scene.meshes.size() == 1);
    const tinygltf::Model before = reread(source);
    std::vector<Mesh::Source> sources{scene.meshes[0].source};
    CHECK(sources[0].mesh == 0);
    CHECK(sources[0].primitive == 0);
    const std::string out = test::tempDir("gltf-out") + "/box.glb";
    Diagnostics diagnostics(false, false);
    writeLightmappedGlb(source, sources, {}, {grey("lightmap", {0}, 3.0f)}, {}, out, diagnostics);
    CHECK(diagnostics.warnings().empty());

    const tinygltf::Model after = reread(out);
    CHECK(after.nodes.size() == before.nodes.size());
    CHECK(after.meshes.size() == before.meshes.size());
    CHECK(after.materials.size() == before.materials.size());  // in place: one material, one lightmap
    REQUIRE(after.buffers.size() == 1);
    CHECK(after.buffers[0].uri.empty());
    for (const tinygltf::Image& image : after.images) {
        CHECK(image.uri.empty());
        CHECK(image.bufferView >= 0);
    }
    CHECK(std::count(after.extensionsUsed.begin(), after.extensionsUsed.end(), "MOZ_lightmap") == 1);
    const tinygltf::Value* lightmap = lightmapOf(after.materials[0]);
    REQUIRE(lightmap);
    CHECK(lightmap->Get("texCoord").GetNumberAsInt() == 1);
    CHECK(lightmap->Get("intensity").GetNumberAsDouble() == 4.0);  // the RGBM range above 3
    const int texture = lightmap->Get("index").GetNumberAsInt();
    REQUIRE(texture >= 0);
    REQUIRE(static_cast<size_t>(texture) < after.textures.size());
    CHECK(after.images[size_t(after.textures[size_t(texture)].source)].name == "lightmap");
    CHECK(after.images[size_t(after.textures[size_t(texture)].source)].mimeType == "image/png");
    // The loader reads it back: the same triangles, the box's own texture still decodes.
    const Scene back = loadGltf(out);
    REQUIRE(back.meshes.size() == 1);
    CHECK(back.meshes[0].indices == scene.meshes[0].indices);
    CHECK(back.meshes[0].positions == scene.meshes[0].positions);
    CHECK(back.warnings == scene.warnings);
    CHECK_FALSE(after.scenes.at(0).extras.Has("voxlight"));  // no sky, nothing said of one

    // A bake under a sky says so in the scene's extras, for viewers (glTF has no sky).
    writeLightmappedGlb(source, sources, {}, {grey("lightmap", {0}, 3.0f)}, {}, out, diagnostics, vec3(0.6f, 0.75f, 1.0f));
    const tinygltf::Model skyLit = reread(out);
    const tinygltf::Value& sky = skyLit.scenes.at(0).extras.Get("voxlight").Get("sky");
    REQUIRE(sky.ArrayLen() == 3);
    CHECK(sky.Get(0).GetNumberAsDouble() == Approx(0.6));
    CHECK(sky.Get(1).GetNumberAsDouble() == Approx(0.75));
    CHECK(sky.Get(2).GetNumberAsDouble() == Approx(1.0));
}

TEST_CASE("glTF out copies a material that serves several lightmaps or unlit primitives", "[export]") {
    // The Cycles quad box's meshes share materials (the white walls, the blocks): baked into
    // two lightmaps, a material used in both must become one copy per lightmap, and one also
    // used by an unbaked primitive keeps the original for it.
    VL_SKIP_WITHOUT_SHARED();
    const std::string source = test::sharedDir() + "/reference/cornell_quad.gltf";
    const Scene scene = loadGltf(source);
    REQUIRE(scene.meshes.size() >= 4);
    std::vector<Mesh::Source> sources;
    for (const Mesh& mesh : scene.meshes) sources.push_back(mesh.source);
    const tinygltf::Model before = reread(source);
    // Meshes by material: the first material used by two meshes.
    int shared = -1;
    std::vector<uint32_t> users;
    for (size_t m = 0; m < scene.meshes.size() && shared < 0; ++m) {
        users.clear();
        for (size_t k = 0; k < scene.meshes.size(); ++k)
            if (scene.meshes[k].material == scene.meshes[m].material) users.push_back(uint32_t(k));
        if (users.size() >= 2) shared = scene.meshes[m].material;
    }
    REQUIRE(shared >= 0);
    const std::string out = test::tempDir("gltf-out") + "/quad.glb";
    Diagnostics diagnostics(false, false);
    // users[0] in lightmap A, users[1] in lightmap B, any further users unbaked.
    writeLightmappedGlb(source, sources, {}, {grey("A", {users[0]}, 0.5f), grey("B", {users[1]}, 0.5f)}, {}, out,
                        diagnostics);
    const tinygltf::Model after = reread(out);
    const auto materialOf = [&](uint32_t sceneMesh) {
        const Mesh::Source& s = scene.meshes[sceneMesh].source;
        return after.meshes[size_t(s.mesh)].primitives[size_t(s.primitive)].material;
    };
    const int a = materialOf(users[0]), b = materialOf(users[1]);
    CHECK(a != b);
    CHECK(a != shared);
    CHECK(b != shared);
    CHECK(after.materials.size() == before.materials.size() + 2);
    REQUIRE(lightmapOf(after.materials[size_t(a)]));
    REQUIRE(lightmapOf(after.materials[size_t(b)]));
    CHECK(lightmapOf(after.materials[size_t(a)])->Get("index").GetNumberAsInt() !=
          lightmapOf(after.materials[size_t(b)])->Get("index").GetNumberAsInt());
    CHECK(after.materials[size_t(a)].name == before.materials[size_t(shared)].name + " (lightmap A)");
    CHECK(after.materials[size_t(a)].pbrMetallicRoughness.baseColorFactor ==
          before.materials[size_t(shared)].pbrMetallicRoughness.baseColorFactor);
    CHECK_FALSE(lightmapOf(after.materials[size_t(shared)]));
    for (size_t k = 2; k < users.size(); ++k) CHECK(materialOf(users[k]) == shared);
}

TEST_CASE("glTF out marks every light's bake mode and adds the job file's lights the engine must draw", "[export]") {
    // The point-lit Cornell box has one light of its own (no mode: the setting's, all). A job
    // file adds a sun the engine draws and a lamp baked whole: only the sun is written, with
    // its intensity back in lux and its node's −Z along its direction, and the file read back
    // gives the same light.
    const std::string source = test::sourceDir() + "/scenes/cornell_box_point.gltf";
    const Scene scene = loadGltf(source);
    REQUIRE(scene.lights.size() == 1);
    std::vector<Mesh::Source> sources;
    for (const Mesh& mesh : scene.meshes) sources.push_back(mesh.source);
    Light sun;
    sun.name = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(vec3(0.75f, -0.45f, -0.2f));
    sun.color = vec3(1.0f, 0.95f, 0.85f);
    sun.intensity = 15.0f;
    sun.angularDiameter = 0.0093f;  // the sun's disk, which glTF cannot hold: the extension carries it
    sun.bake = LightBake::Indirect;
    Light lamp;
    lamp.name = "lamp";
    lamp.position = vec3(0.1f, 0.4f, 0.2f);
    const std::string out = test::tempDir("gltf-out-lights") + "/box.glb";
    Diagnostics diagnostics(false, false);
    writeLightmappedGlb(source, sources, {}, {}, {}, out, diagnostics, vec3(0.0f), {sun, lamp}, LightBake::All);

    const tinygltf::Model after = reread(out);
    REQUIRE(after.lights.size() == 2);
    const auto modeOf = [](const tinygltf::Light& light) {
        const auto it = light.extensions.find("VOXLIGHT_light_bake");
        return it == light.extensions.end() ? std::string("none") : it->second.Get("mode").Get<std::string>();
    };
    CHECK(modeOf(after.lights[0]) == "all");
    CHECK(modeOf(after.lights[1]) == "indirect");
    CHECK(after.lights[1].name == "sun");
    CHECK(after.lights[1].intensity == Approx(15.0 * 683.0));
    CHECK(std::count(after.extensionsUsed.begin(), after.extensionsUsed.end(), "VOXLIGHT_light_bake") == 1);

    const Scene reloaded = loadGltf(out);
    REQUIRE(reloaded.lights.size() == 2);
    const auto drawn = std::find_if(reloaded.lights.begin(), reloaded.lights.end(),
                                    [](const Light& l) { return l.name == "sun"; });
    REQUIRE(drawn != reloaded.lights.end());
    CHECK(drawn->bake == LightBake::Indirect);
    CHECK(drawn->type == LightType::Directional);
    CHECK(glm::length(drawn->direction - sun.direction) < 1e-5f);
    CHECK(drawn->intensity == Approx(15.0f));
    CHECK(drawn->angularDiameter == Approx(0.0093f));
    CHECK(glm::length(drawn->color - sun.color) < 1e-6f);
    const auto own = std::find_if(reloaded.lights.begin(), reloaded.lights.end(),
                                  [](const Light& l) { return l.name != "sun"; });
    CHECK(own->bake == LightBake::All);
}

TEST_CASE("A glTF light's bake mode other than all or indirect is refused naming the light", "[export]") {
    const std::string dir = test::tempDir("gltf-light-bake");
    std::ofstream(dir + "/bad.gltf") << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual", "VOXLIGHT_light_bake"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"name": "lamp", "type": "point", "intensity": 10,
            "extensions": {"VOXLIGHT_light_bake": {"mode": "sometimes"}}}]}},
        "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}], "scenes": [{"nodes": [0]}], "scene": 0})";
    CHECK_THROWS_WITH(loadGltf(dir + "/bad.gltf"), Catch::Contains("bad.gltf") && Catch::Contains("'lamp'") &&
                                                        Catch::Contains("VOXLIGHT_light_bake.mode"));
    // A sun's disk that is not a number, or a disk on a point light.
    std::ofstream(dir + "/disk.gltf") << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual", "VOXLIGHT_light_bake"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"name": "sun", "type": "directional", "intensity": 10,
            "extensions": {"VOXLIGHT_light_bake": {"mode": "indirect", "angularDiameter": "wide"}}}]}},
        "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}], "scenes": [{"nodes": [0]}], "scene": 0})";
    CHECK_THROWS_WITH(loadGltf(dir + "/disk.gltf"), Catch::Contains("disk.gltf") && Catch::Contains("'sun'") &&
                                                        Catch::Contains("angularDiameter must be a number"));
    std::ofstream(dir + "/lamp.gltf") << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual", "VOXLIGHT_light_bake"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"name": "lamp", "type": "point", "intensity": 10,
            "extensions": {"VOXLIGHT_light_bake": {"mode": "indirect", "angularDiameter": 0.01}}}]}},
        "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}], "scenes": [{"nodes": [0]}], "scene": 0})";
    CHECK_THROWS_WITH(loadGltf(dir + "/lamp.gltf"), Catch::Contains("'lamp'") && Catch::Contains("for directional lights"));
}

TEST_CASE("glTF out writes shadowmask lights with their channels and points each lightmapped material at its "
          "shadowmask",
          "[export]") {
    // The point-lit box's own light and a job file's sun, both shadowmask lights as the bake
    // resolved them (channels 0 and 1); one lightmap over every mesh, with a shadowmask.
    const std::string source = test::sourceDir() + "/scenes/cornell_box_point.gltf";
    Scene scene = loadGltf(source);
    REQUIRE(scene.lights.size() == 1);
    CHECK(scene.lights[0].sourceLight == 0);
    std::vector<Mesh::Source> sources;
    std::vector<uint32_t> all;
    for (const Mesh& mesh : scene.meshes) {
        sources.push_back(mesh.source);
        all.push_back(uint32_t(all.size()));
    }
    Light sun;
    sun.name = "sun";
    sun.type = LightType::Directional;
    sun.intensity = 15.0f;
    scene.lights.push_back(sun);
    for (Light& light : scene.lights) light.bake = LightBake::Shadowmask;
    scene.lights[0].maskChannel = 0;
    scene.lights[1].maskChannel = 1;
    ExportedLightmap lightmap = grey("lightmap", all, 1.0f);
    Image mask(8, 8, kShadowmaskChannels, 0.0f);
    for (size_t t = 0; t < 64; ++t) mask.pixels[4 * t] = float(t) / 63.0f;
    lightmap.shadowmask = shadowmaskBytes(mask);
    const std::string out = test::tempDir("gltf-out-shadowmask") + "/box.glb";
    Diagnostics diagnostics(false, false);
    writeLightmappedGlb(source, sources, {}, {lightmap}, {}, out, diagnostics, vec3(0.0f), {sun}, LightBake::All,
                        scene.lights);

    const tinygltf::Model after = reread(out);
    REQUIRE(after.lights.size() == 2);
    for (int k = 0; k < 2; ++k) {
        const tinygltf::Value& bake = after.lights[size_t(k)].extensions.at("VOXLIGHT_light_bake");
        CHECK(bake.Get("mode").Get<std::string>() == "shadowmask");
        CHECK(bake.Get("channel").Get<int>() == k);
    }
    CHECK(std::count(after.extensionsUsed.begin(), after.extensionsUsed.end(), "VOXLIGHT_shadowmask") == 1);
    int masked = 0;
    for (const tinygltf::Material& material : after.materials) {
        const auto it = material.extensions.find("VOXLIGHT_shadowmask");
        CHECK((it != material.extensions.end()) == (lightmapOf(material) != nullptr));  // every lightmapped one
        if (it == material.extensions.end()) continue;
        ++masked;
        REQUIRE(lightmapOf(material));
        CHECK(it->second.Get("texCoord").Get<int>() == 1);
        const int texture = it->second.Get("index").Get<int>();
        REQUIRE(texture >= 0);
        REQUIRE(size_t(texture) < after.textures.size());
        CHECK(texture != lightmapOf(material)->Get("index").Get<int>());
        CHECK(after.images.at(size_t(after.textures[size_t(texture)].source)).name == "lightmap shadowmask");
    }
    CHECK(masked > 0);
    // Read back, the light keeps its mode.
    const Scene reloaded = loadGltf(out);
    REQUIRE(reloaded.lights.size() == 2);
    for (const Light& light : reloaded.lights) CHECK(light.bake == LightBake::Shadowmask);

    // Baked again without a shadowmask, the file keeps none of the old one's references.
    const std::string again = test::tempDir("gltf-out-shadowmask") + "/again.glb";
    writeLightmappedGlb(out, sources, {}, {grey("lightmap", all, 1.0f)}, {}, again, diagnostics);
    const tinygltf::Model rewritten = reread(again);
    for (const tinygltf::Material& material : rewritten.materials) CHECK(!material.extensions.count("VOXLIGHT_shadowmask"));
    CHECK(std::count(rewritten.extensionsUsed.begin(), rewritten.extensionsUsed.end(), "VOXLIGHT_shadowmask") == 0);
}

TEST_CASE("A shadowmask ships as 8-bit linear bytes, each within half a step of its value", "[export]") {
    Image mask(3, 1, kShadowmaskChannels, 0.0f);
    const float values[] = {0.0f, 1.0f, 0.5f, 0.25f, 1.5f, -0.5f, 0.1f, 0.9f, 0.002f, 0.998f, 0.3333f, 0.6667f};
    std::copy(std::begin(values), std::end(values), mask.pixels.begin());
    const std::vector<uint8_t> bytes = shadowmaskBytes(mask);
    const Image back = decodeShadowmask(3, 1, bytes);
    for (size_t k = 0; k < 12; ++k)
        CHECK(back.pixels[k] == Approx(std::clamp(values[k], 0.0f, 1.0f)).margin(0.5 / 255.0 + 1e-6));
    CHECK(bytes[4] == 255);  // 1.5 clamps to 1
    CHECK(bytes[5] == 0);    // −0.5 to 0
    CHECK_THROWS(shadowmaskBytes(Image(2, 2, 3)));
}
