// The loader against glTF made elsewhere (../shared/scenes, ../shared/reference): malformed
// corpora must give InputError or load, never anything else; real models must load with the
// triangle counts their own JSON declares; the Cornell references with their stated values.
#include "scene_checks.h"

#include "scene/surface.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace vl;
using namespace vl::test;
using Catch::Contains;
namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

std::vector<std::string> gltfFilesUnder(const std::string& root) {
    std::vector<std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        const std::string ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".gltf" || ext == ".glb")) files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
    return files;
}

// The file's JSON (a .glb's first chunk), read here independently of the loader.
Json readJson(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.compare(0, 4, "glTF") == 0) {
        uint32_t length = 0;
        std::memcpy(&length, bytes.data() + 12, 4);
        return Json::parse(bytes.substr(20, length));
    }
    return Json::parse(bytes);
}

struct Declared {
    size_t triangles = 0;
    size_t lights = 0;
    size_t perspectiveCameras = 0;
    bool unsupportedRequired = false;
};

// What the JSON declares for the scene a viewer shows: the default scene (or scene 0; all
// parentless nodes when there are no scenes), each node's mesh once per node. Triangles per
// primitive from the spec: mode 4 → n/3, modes 5 and 6 → n − 2, points and lines none,
// with n the index count (or the POSITION count when not indexed).
Declared declared(const Json& gltf) {
    Declared d;
    const auto& supported = supportedGltfExtensions();
    for (const auto& name : gltf.value("extensionsRequired", Json::array()))
        if (std::find(supported.begin(), supported.end(), name.get<std::string>()) == supported.end())
            d.unsupportedRequired = true;

    const Json nodes = gltf.value("nodes", Json::array());
    std::vector<int> roots;
    if (gltf.contains("scenes") && !gltf["scenes"].empty()) {
        roots = gltf["scenes"][gltf.value("scene", 0)].value("nodes", std::vector<int>{});
    } else {
        std::vector<bool> child(nodes.size(), false);
        for (const auto& node : nodes)
            for (int c : node.value("children", std::vector<int>{})) child[static_cast<size_t>(c)] = true;
        for (size_t n = 0; n < nodes.size(); ++n)
            if (!child[n]) roots.push_back(static_cast<int>(n));
    }
    std::vector<int> stack(roots.rbegin(), roots.rend());
    while (!stack.empty()) {
        const Json& node = nodes[static_cast<size_t>(stack.back())];
        stack.pop_back();
        if (node.contains("mesh")) {
            for (const auto& primitive : gltf["meshes"][node["mesh"].get<int>()]["primitives"]) {
                const int mode = primitive.value("mode", 4);
                const int accessor = primitive.contains("indices") ? primitive["indices"].get<int>()
                                                                   : primitive["attributes"]["POSITION"].get<int>();
                const size_t n = gltf["accessors"][accessor]["count"].get<size_t>();
                if (mode == 4) d.triangles += n / 3;
                if ((mode == 5 || mode == 6) && n >= 3) d.triangles += n - 2;
            }
        }
        if (node.contains("camera") && gltf["cameras"][node["camera"].get<int>()]["type"] == "perspective")
            ++d.perspectiveCameras;
        if (node.contains("extensions") && node["extensions"].contains("KHR_lights_punctual")) ++d.lights;
        const auto children = node.value("children", std::vector<int>{});
        stack.insert(stack.end(), children.rbegin(), children.rend());
    }
    return d;
}

const Mesh& meshNamed(const Scene& scene, const std::string& name) {
    static const Mesh none;
    for (const Mesh& mesh : scene.meshes)
        if (mesh.name == name) return mesh;
    FAIL("no mesh named " << name);
    return none;
}

}  // namespace

TEST_CASE("Every validator and tinygltf corpus file loads or is refused with an InputError", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    std::vector<std::string> files = gltfFilesUnder(sharedDir() + "/scenes/gltf-validator-tests");
    const std::vector<std::string> more = gltfFilesUnder(sharedDir() + "/scenes/tinygltf-test-models");
    files.insert(files.end(), more.begin(), more.end());
    REQUIRE(files.size() > 380);

    size_t loaded = 0, refused = 0;
    for (const std::string& path : files) {
        INFO(path);
        try {
            const Scene scene = loadQuiet(path);
            ++loaded;
            for (const Mesh& mesh : scene.meshes) {  // whatever loads is usable: finite, in range, unit normals
                for (const vec3& p : mesh.positions) REQUIRE(isFinite(p));
                for (const vec3& n : mesh.normals) REQUIRE(std::abs(glm::length(n) - 1.0f) < 1e-4f);
                for (uint32_t i : mesh.indices) REQUIRE(i < mesh.positions.size());
                REQUIRE(mesh.indices.size() % 3 == 0);
            }
        } catch (const InputError& e) {
            ++refused;
            // The message starts with the file, so the user knows which one.
            CHECK_THAT(e.what(), Catch::StartsWith(path));
        } catch (const std::exception& e) {
            FAIL("not an InputError: " << e.what());
        }
    }
    CHECK(loaded + refused == files.size());
    WARN("corpus: " << loaded << " loaded, " << refused << " refused");
}

TEST_CASE("Khronos sample models load with the triangle lights and camera counts their files declare", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    std::vector<std::string> files = gltfFilesUnder(sharedDir() + "/scenes/khronos-sample-assets");
    for (const char* folder : {"Mesh_PrimitiveMode", "Mesh_PrimitivesUV", "Mesh_PrimitiveAttribute", "Mesh_Primitives",
                               "Buffer_Interleaved"}) {
        const auto more = gltfFilesUnder(sharedDir() + "/scenes/gltf-asset-generator-2018/Output/" + folder);
        files.insert(files.end(), more.begin(), more.end());
    }
    REQUIRE(files.size() > 80);
    size_t refusedForExtensions = 0;
    for (const std::string& path : files) {
        INFO(path);
        const Declared expected = declared(readJson(path));
        if (expected.unsupportedRequired) {
            CHECK_THROWS_WITH(loadQuiet(path), Contains("requires extension"));
            ++refusedForExtensions;
            continue;
        }
        const Scene scene = loadQuiet(path);
        CHECK(scene.triangleCount() + scene.degenerateTrianglesDropped == expected.triangles);
        CHECK(scene.lights.size() == expected.lights);
        CHECK(scene.cameras.size() == expected.perspectiveCameras);
    }
    // Box (Draco) and UnlitTest (.gltf, .glb) require extensions outside the supported set.
    CHECK(refusedForExtensions == 3);
}

TEST_CASE("Sample models carry the attributes and materials their files declare", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string models = sharedDir() + "/scenes/khronos-sample-assets/Models/";

    const Scene multiUv = loadQuiet(models + "MultiUVTest/glTF-Binary/MultiUVTest.glb");
    REQUIRE_FALSE(multiUv.meshes.empty());
    CHECK(multiUv.meshes[0].uv1.size() == multiUv.meshes[0].positions.size());
    REQUIRE_FALSE(multiUv.textures.empty());

    // EmissiveStrengthTest: emissiveStrength values from its JSON reach Material::emission().
    const std::string emissivePath = models + "EmissiveStrengthTest/glTF/EmissiveStrengthTest.gltf";
    const Json json = readJson(emissivePath);
    const Scene emissive = loadQuiet(emissivePath);
    REQUIRE(emissive.materials.size() == json["materials"].size());
    for (size_t m = 0; m < json["materials"].size(); ++m) {
        const Json& material = json["materials"][m];
        const float strength =
            material.contains("extensions")
                ? material["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"].get<float>()
                : 1.0f;
        const auto factor = material.value("emissiveFactor", std::vector<float>{0, 0, 0});
        CHECK_NEAR(emissive.materials[m].emission(), vec3(factor[0], factor[1], factor[2]) * strength, 1e-5f);
    }

    // Vertex colours, normalized or float, end in [0, 1].
    const Scene colors = loadQuiet(models + "VertexColorTest/glTF-Binary/VertexColorTest.glb");
    size_t colored = 0;
    for (const Mesh& mesh : colors.meshes)
        for (const vec4& c : mesh.colors) {
            ++colored;
            CHECK((glm::all(glm::greaterThanEqual(c, vec4(0.0f))) && glm::all(glm::lessThanEqual(c, vec4(1.0f)))));
        }
    CHECK(colored > 0);
}

TEST_CASE("The asset generator's compatibility files load or are refused as its README says", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string dir = sharedDir() + "/scenes/gltf-asset-generator-2018/Output/Compatibility/";
    for (const char* loads : {"Compatibility_00.gltf", "Compatibility_01.gltf", "Compatibility_02.gltf",
                              "Compatibility_03.gltf"}) {
        INFO(loads);
        CHECK(loadQuiet(dir + loads).triangleCount() > 0);
    }
    CHECK_THROWS_WITH(loadQuiet(dir + "Compatibility_04.gltf"),
                      Contains("Compatibility_04.gltf") && Contains("minVersion 2.1"));
    CHECK_THROWS_WITH(loadQuiet(dir + "Compatibility_05.gltf"),
                      Contains("Compatibility_05.gltf") && Contains("FAKE_materials_quantumRendering"));
}

TEST_CASE("The Cornell references load with their walls emitter light and camera", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string reference = sharedDir() + "/reference/";
    // Values from ../shared/reference/README.md.
    const vec3 white(0.73f), red(0.63f, 0.065f, 0.05f), green(0.14f, 0.45f, 0.091f);

    const Scene quad = loadQuiet(reference + "cornell_quad.gltf");
    CHECK(quad.warnings.empty());
    const auto albedo = [&](const Scene& scene, const std::string& mesh) {
        return vec3(scene.materialOf(meshNamed(scene, mesh)).baseColorFactor);
    };
    for (const Scene* scene : {&quad}) {
        CHECK_NEAR(albedo(*scene, "Floor/0"), white, 1e-6f);
        CHECK_NEAR(albedo(*scene, "BackWall/0"), white, 1e-6f);
        CHECK_NEAR(albedo(*scene, "Ceiling/0"), white, 1e-6f);
        CHECK_NEAR(albedo(*scene, "RedWall/0"), red, 1e-6f);
        CHECK_NEAR(albedo(*scene, "GreenWall/0"), green, 1e-6f);
        CHECK_NEAR(albedo(*scene, "TallBlock/0"), white, 1e-6f);
    }
    const Mesh& light = meshNamed(quad, "Light/0");
    CHECK_NEAR(quad.materialOf(light).emission(), vec3(17.0f), 1e-5f);
    CHECK_NEAR(emissionAt(quad, light, 0, vec2(0.3f)), vec3(17.0f), 1e-5f);
    // The 130 × 105 mm emitter's area.
    float area = 0.0f;
    for (size_t t = 0; t < light.triangleCount(); ++t) {
        const vec3& a = light.positions[light.indices[3 * t]];
        area += 0.5f * glm::length(glm::cross(light.positions[light.indices[3 * t + 1]] - a,
                                              light.positions[light.indices[3 * t + 2]] - a));
    }
    CHECK(area == Approx(0.130f * 0.105f).epsilon(1e-3));
    CHECK_FALSE(meshNamed(quad, "Floor/0").uv1.empty());
    for (const Mesh& mesh : quad.meshes)  // the walls say "no specular" with ior 1.45; the emitter has none
        if (mesh.name != "Light/0") CHECK(quad.materialOf(mesh).ior == Approx(1.45f));
    REQUIRE(quad.cameras.size() == 1);
    CHECK_NEAR(vl::test::world(quad, quad.cameras[0].position), vec3(0.278f, 0.273f, 0.8f), 1e-6f);
    CHECK_NEAR(quad.cameras[0].forward, vec3(0, 0, -1), 1e-6f);
    CHECK(quad.cameras[0].yfov == Approx(0.686048f));
    CHECK(quad.lights.empty());

    const Scene point = loadQuiet(reference + "cornell_point.gltf");
    CHECK(point.warnings.empty());
    CHECK_NEAR(albedo(point, "RedWall/0"), red, 1e-6f);
    CHECK_NEAR(albedo(point, "GreenWall/0"), green, 1e-6f);
    CHECK_FALSE(point.hasEmitters());
    REQUIRE(point.lights.size() == 1);
    CHECK(point.lights[0].type == LightType::Point);
    CHECK(point.lights[0].intensity == Approx(2.0 / (4.0 * 3.14159265358979)).epsilon(1e-6));
    CHECK_NEAR(vl::test::world(point, point.lights[0].position), vec3(0.278f, 0.5f, -0.2795f), 1e-6f);
}

TEST_CASE("The nvpro Cornell box loads with warnings for its odd bits", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string path = sharedDir() + "/scenes/cornellbox-nvpro/cornellBox.gltf";
    const Scene scene = loadQuiet(path);
    // SOURCE.txt's 16,720 counts each of the 9 meshes once; node cube_instance_3 instances
    // mesh 1 a second time (+12), and the spheres' poles hold zero-area triangles.
    CHECK(scene.triangleCount() + scene.degenerateTrianglesDropped == declared(readJson(path)).triangles);
    CHECK(declared(readJson(path)).triangles == 16720 + 12);
    CHECK(scene.degenerateTrianglesDropped > 0);
    CHECK(anyWarningContains(scene, "degenerate"));
    CHECK(anyWarningContains(scene, "emissiveFactor above 1"));
    CHECK(anyWarningContains(scene, "texture 0 'tex' refers to image 0, which does not exist"));
    bool tenfold = false;
    for (const Material& m : scene.materials) tenfold = tenfold || m.emission() == vec3(10.0f);
    CHECK(tenfold);
    CHECK(scene.lights.empty());
    CHECK_THROWS_AS(loadQuiet(path, /*strict=*/true), InputError);
}

TEST_CASE("Mirrored sample models keep faces and their file normals on the same side", "[scene]") {
    VL_SKIP_WITHOUT_SHARED();
    // Models with vertex normals and negative-determinant nodes: after the winding flip every
    // triangle's CCW normal must agree with the file's normals, transformed by the inverse
    // transpose. Without the flip the mirrored instances would all disagree.
    std::vector<std::string> files{sharedDir() +
                                   "/scenes/khronos-sample-assets/Models/NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb"};
    for (int i = 7; i <= 12; ++i)
        files.push_back(sharedDir() + "/scenes/gltf-asset-generator-2018/Output/Node_NegativeScale/Node_NegativeScale_" +
                        (i < 10 ? "0" : "") + std::to_string(i) + ".gltf");
    for (const std::string& path : files) {
        INFO(path);
        const Scene scene = loadQuiet(path);
        size_t agree = 0, disagree = 0;
        for (const Mesh& mesh : scene.meshes)
            for (size_t t = 0; t < mesh.triangleCount(); ++t) {
                const vec3 n = mesh.normals[mesh.indices[3 * t]] + mesh.normals[mesh.indices[3 * t + 1]] +
                               mesh.normals[mesh.indices[3 * t + 2]];
                (glm::dot(faceNormal(mesh, t), n) > 0.0f ? agree : disagree)++;
            }
        CHECK(agree > 0);
        CHECK(disagree == 0);
    }
}
