// Input the loader must refuse, each with a message naming the file and the element.
#include "gltf_builder.h"
#include "scene_checks.h"

#include <filesystem>
#include <limits>

using namespace vl;
using namespace vl::test;
using Catch::Contains;

namespace {

std::string dir() { return tempDir("scene-loader-bad-input"); }

const std::string kScene = R"("scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}])";

std::string trianglePrimitive(int position, const std::string& extra = "") {
    return R"("meshes": [{"name": "Bad", "primitives": [{"attributes": {"POSITION": )" + std::to_string(position) + "}" +
           extra + "}]}], " + kScene;
}

}  // namespace

TEST_CASE("A file that requires an unsupported extension is refused", "[scene]") {
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::string path =
        b.writeGltf(dir(), "unsupported_extension",
                    trianglePrimitive(position) + R"(, "extensionsUsed": ["KHR_draco_mesh_compression", "KHR_materials_specular"],
                                                      "extensionsRequired": ["KHR_materials_specular", "KHR_draco_mesh_compression"])");
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("requires extension KHR_draco_mesh_compression"));
}

TEST_CASE("A file that needs a newer glTF version is refused and 2.1 without minVersion loads", "[scene]") {
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    b.asset = R"("asset": {"version": "2.1", "minVersion": "2.1"})";
    const std::string newer = b.writeGltf(dir(), "min_version", trianglePrimitive(position));
    CHECK_THROWS_WITH(loadGltf(newer), Contains(newer) && Contains("asset.minVersion 2.1"));
    b.asset = R"("asset": {"version": "3.0"})";
    const std::string major = b.writeGltf(dir(), "major_version", trianglePrimitive(position));
    CHECK_THROWS_WITH(loadGltf(major), Contains(major) && Contains("asset.version 3.0"));
    b.asset = R"("asset": {"version": "2.1"})";
    CHECK(loadQuiet(b.writeGltf(dir(), "compatible_version", trianglePrimitive(position))).triangleCount() == 1);
}

TEST_CASE("An index beyond the vertex count is refused naming the accessor", "[scene]") {
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int indices = b.indices({0, 1, 7});
    const std::string path =
        b.writeGltf(dir(), "index_out_of_range", trianglePrimitive(position, R"(, "indices": )" + std::to_string(indices)));
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("mesh 0 'Bad' primitive 0") &&
                                          Contains("accessor " + std::to_string(indices)) && Contains("index 7") &&
                                          Contains("out of range"));
}

TEST_CASE("A missing accessor is refused naming it", "[scene]") {
    GltfBuilder b;
    b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::string path = b.writeGltf(dir(), "missing_accessor", trianglePrimitive(9));
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("POSITION") && Contains("accessor 9 does not exist"));
}

TEST_CASE("An accessor longer than its buffer view is refused", "[scene]") {
    GltfBuilder b;
    const int view = b.view(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int position = b.accessor(view, kFloat, 4, "VEC3");  // 48 bytes from a 36-byte view
    const std::string path = b.writeGltf(dir(), "accessor_too_long", trianglePrimitive(position));
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("primitive 0 POSITION") &&
                                          Contains("accessor " + std::to_string(position)) &&
                                          Contains("does not fit in bufferView " + std::to_string(view)));
}

TEST_CASE("A buffer view outside its buffer is refused", "[scene]") {
    GltfBuilder b;
    b.view(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int view = b.rawView(R"({"buffer": 0, "byteOffset": 24, "byteLength": 36})");
    const int position = b.accessor(view, kFloat, 3, "VEC3");
    const std::string path = b.writeGltf(dir(), "view_outside_buffer", trianglePrimitive(position));
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("bufferView " + std::to_string(view)) &&
                                          Contains("lies outside buffer 0"));
}

TEST_CASE("A missing buffer file is refused naming it", "[scene]") {
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::string path = b.writeGltf(dir(), "missing_buffer", trianglePrimitive(position));
    std::filesystem::remove(dir() + "/missing_buffer.bin");
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("buffer 0 ('missing_buffer.bin') is missing"));
}

TEST_CASE("NaN and infinite positions are refused naming the vertex", "[scene]") {
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        GltfBuilder b;
        const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, bad, 0});
        const std::string path = b.writeGltf(dir(), "nan_position", trianglePrimitive(position));
        CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("mesh 0 'Bad' primitive 0 POSITION") &&
                                              Contains("accessor " + std::to_string(position)) &&
                                              Contains("non-finite") && Contains("vertex 2"));
    }
}

TEST_CASE("A singular node transform on a mesh node is refused", "[scene]") {
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::string members = R"("meshes": [{"primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
                                R"(}}]}], "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Flat", "mesh": 0, "scale": [1, 0, 1]}])";
    const std::string path = b.writeGltf(dir(), "singular", members);
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("node 0 'Flat'") && Contains("singular transform"));

    // The same scale on a node without a mesh is harmless.
    const std::string members2 = R"("meshes": [{"primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
                                 R"(}}]}], "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "Flat", "scale": [1, 0, 1]}, {"mesh": 0}])";
    CHECK(loadQuiet(b.writeGltf(dir(), "singular_empty_node", members2)).triangleCount() == 1);
}

TEST_CASE("A node cycle is refused instead of recursing forever", "[scene]") {
    GltfBuilder b;
    const std::string path = b.writeGltf(dir(), "cycle", R"("scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1]}, {"name": "Loop", "children": [0]}])");
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("node 0") && Contains("cycle"));
}

TEST_CASE("Truncated and missing files are refused", "[scene]") {
    const std::string missing = dir() + "/does_not_exist.gltf";
    CHECK_THROWS_WITH(loadGltf(missing), Contains(missing) && Contains("no such file"));

    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::string glb = b.writeGlb(dir(), "whole", trianglePrimitive(position));
    std::vector<unsigned char> bytes = readBytes(glb);
    bytes.resize(bytes.size() / 2);
    const std::string truncated = dir() + "/truncated.glb";
    std::ofstream(truncated, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    CHECK_THROWS_WITH(loadGltf(truncated), Contains(truncated) && Contains("cannot be parsed"));

    const std::string notJson = writeText(dir() + "/not_json.gltf", "{\"asset\": {\"version\": \"2.0\"");
    CHECK_THROWS_AS(loadGltf(notJson), InputError);
}

TEST_CASE("An accessor without a bufferView and a huge count is refused before allocating", "[scene]") {
    GltfBuilder b;
    const int position = b.accessor(-1, kFloat, size_t(1) << 40, "VEC3");
    b.vec3({0, 0, 0});  // keeps a buffer in the file
    const std::string path = b.writeGltf(dir(), "huge_count", trianglePrimitive(position));
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("accessor " + std::to_string(position)) &&
                                          Contains("count"));
}

TEST_CASE("Attributes whose counts differ from POSITION are refused", "[scene]") {
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int uv = b.vec2({0, 0, 1, 0});
    const std::string path = b.writeGltf(
        dir(), "count_mismatch",
        R"("meshes": [{"name": "Bad", "primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
            R"(, "TEXCOORD_0": )" + std::to_string(uv) + "}}]}], " + kScene);
    CHECK_THROWS_WITH(loadGltf(path), Contains(path) && Contains("TEXCOORD_0") &&
                                          Contains("accessor " + std::to_string(uv)) && Contains("2 elements"));
}
