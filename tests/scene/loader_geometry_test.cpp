// Geometry the loader must get exactly right: node transforms, winding, primitive modes,
// accessor encodings and generated normals, each on a file small enough to check by hand.
#include "gltf_builder.h"
#include "scene_checks.h"

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

const float kHalfSqrt2 = 0.70710678118654752f;

std::string dir() { return tempDir("scene-loader-geometry"); }

std::string singleNodeScene(const std::string& node) {
    return R"("scene": 0, "scenes": [{"nodes": [0]}], "nodes": [)" + node + "]";
}

}  // namespace

TEST_CASE("A node's translation rotation and scale place the quad exactly", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    // T (1,2,3) · R (90° about +Z) · S (2): (x, y, z) → (1 − 2y, 2 + 2x, 3 + 2z).
    const std::string members = R"("meshes": [)" + quadMesh(q) + "], " +
                                singleNodeScene(R"({"mesh": 0, "translation": [1, 2, 3],
                                    "rotation": [0, 0, 0.70710678118654752, 0.70710678118654752], "scale": [2, 2, 2]})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "trs_quad", members));

    REQUIRE(scene.meshes.size() == 1);
    const Mesh& mesh = scene.meshes[0];
    CHECK(mesh.name == "Quad/0");
    REQUIRE(mesh.positions.size() == 4);
    CHECK_NEAR(vl::test::world(scene, mesh.positions[0]), vec3(1, 2, 3), 1e-6f);
    CHECK_NEAR(vl::test::world(scene, mesh.positions[1]), vec3(1, 4, 3), 1e-6f);
    CHECK_NEAR(vl::test::world(scene, mesh.positions[2]), vec3(-1, 4, 3), 1e-6f);
    CHECK_NEAR(vl::test::world(scene, mesh.positions[3]), vec3(-1, 2, 3), 1e-6f);
    CHECK(mesh.indices == std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
    for (const vec3& n : mesh.normals) CHECK_NEAR(n, vec3(0, 0, 1), 1e-6f);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) CHECK_NEAR(faceNormal(mesh, t), vec3(0, 0, 1), 1e-6f);
    CHECK_NEAR(mesh.uv0[0], vec2(0, 1));
    CHECK(mesh.uv1.empty());
    CHECK(mesh.colors.empty());
    CHECK(scene.triangleCount() == 2);
    CHECK(scene.warnings.empty());
    CHECK(scene.name == "trs_quad");
}

TEST_CASE("Parent matrices compose with child transforms", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    // Parent: column-major matrix translating by (10, 0, 0) and scaling y by 3.
    // Child: translation (0, 1, 0). World = parent · child: (x, y, z) → (10 + x, 3(y + 1), z).
    const std::string members = R"("meshes": [)" + quadMesh(q) + R"(],
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "matrix": [1,0,0,0, 0,3,0,0, 0,0,1,0, 10,0,0,1]},
                  {"mesh": 0, "translation": [0, 1, 0]}])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "hierarchy", members));
    REQUIRE(scene.meshes.size() == 1);
    const Mesh& mesh = scene.meshes[0];
    CHECK_NEAR(vl::test::world(scene, mesh.positions[0]), vec3(10, 3, 0));
    CHECK_NEAR(vl::test::world(scene, mesh.positions[2]), vec3(11, 6, 0));
    CHECK_NEAR(vl::test::world(scene, mesh.positions[3]), vec3(10, 6, 0));
}

TEST_CASE("A mirroring node flips the winding so triangles stay counter-clockwise", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    const std::string members =
        R"("meshes": [)" + quadMesh(q) + "], " + singleNodeScene(R"({"mesh": 0, "scale": [-1, 1, 1]})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "mirrored", members));
    REQUIRE(scene.meshes.size() == 1);
    const Mesh& mesh = scene.meshes[0];
    CHECK_NEAR(vl::test::world(scene, mesh.positions[1]), vec3(-1, 0, 0));
    CHECK_NEAR(vl::test::world(scene, mesh.positions[2]), vec3(-1, 1, 0));
    // The mirror keeps the plane's front at +Z (inverse transpose of diag(-1,1,1)); the index
    // order must agree with it.
    CHECK(mesh.indices == std::vector<uint32_t>{0, 2, 1, 0, 3, 2});
    for (size_t t = 0; t < mesh.triangleCount(); ++t) CHECK_NEAR(faceNormal(mesh, t), vec3(0, 0, 1), 1e-6f);
    for (const vec3& n : mesh.normals) CHECK_NEAR(n, vec3(0, 0, 1), 1e-6f);
}

TEST_CASE("Normals go through the inverse transpose under non-uniform scale", "[scene]") {
    GltfBuilder b;
    // A triangle in the plane x + y = 1, facing (1, 1, 0)/√2, scaled by (2, 1, 1): it lies in
    // x/2 + y = 1 afterwards, whose normal is (0.5, 1, 0) normalized.
    const int position = b.vec3({1, 0, 0, 0, 1, 0, 0, 1, 1});
    const int normal = b.vec3({kHalfSqrt2, kHalfSqrt2, 0, kHalfSqrt2, kHalfSqrt2, 0, kHalfSqrt2, kHalfSqrt2, 0});
    const std::string members = R"("meshes": [{"primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
                                R"(, "NORMAL": )" + std::to_string(normal) + "}}]}], " +
                                singleNodeScene(R"({"mesh": 0, "scale": [2, 1, 1]})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "nonuniform", members));
    REQUIRE(scene.meshes.size() == 1);
    const vec3 expected = glm::normalize(vec3(0.5f, 1.0f, 0.0f));
    CHECK_NEAR(scene.meshes[0].normals[0], expected, 1e-6f);
    CHECK_NEAR(faceNormal(scene.meshes[0], 0), expected, 1e-6f);
}

TEST_CASE("Non-indexed triangle strips and fans keep every triangle counter-clockwise", "[scene]") {
    GltfBuilder b;
    // Strip (0,0) (1,0) (0,1) (1,1): triangles {0,1,2} and {1,3,2} (glTF 2.0 §3.7.2.1).
    const int strip = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
    // Fan (0,0) (1,0) (1,1) (0,1): triangles {1,2,0} and {2,3,0}.
    const int fan = b.vec3({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    // Indexed fan over the same vertices in reverse order, faces −Z.
    const int fanIndices = b.indices({3, 2, 1, 0});
    const std::string members = R"("meshes": [{"name": "Modes", "primitives": [
            {"attributes": {"POSITION": )" + std::to_string(strip) + R"(}, "mode": 5},
            {"attributes": {"POSITION": )" + std::to_string(fan) + R"(}, "mode": 6},
            {"attributes": {"POSITION": )" + std::to_string(fan) + R"(}, "indices": )" + std::to_string(fanIndices) +
                                R"(, "mode": 6}]}], )" + singleNodeScene(R"({"mesh": 0})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "strip_fan", members));
    REQUIRE(scene.meshes.size() == 3);
    CHECK(scene.meshes[0].indices == std::vector<uint32_t>{0, 1, 2, 1, 3, 2});
    CHECK(scene.meshes[1].indices == std::vector<uint32_t>{1, 2, 0, 2, 3, 0});
    CHECK(scene.meshes[2].indices == std::vector<uint32_t>{2, 1, 3, 1, 0, 3});
    for (int m = 0; m < 2; ++m)
        for (size_t t = 0; t < 2; ++t) CHECK_NEAR(faceNormal(scene.meshes[m], t), vec3(0, 0, 1), 1e-6f);
    for (size_t t = 0; t < 2; ++t) CHECK_NEAR(faceNormal(scene.meshes[2], t), vec3(0, 0, -1), 1e-6f);
    // Generated normals agree with the faces.
    for (const vec3& n : scene.meshes[0].normals) CHECK_NEAR(n, vec3(0, 0, 1), 1e-6f);
    CHECK(scene.meshes[1].name == "Modes/1");
}

TEST_CASE("Point and line primitives are skipped with one warning", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    const std::string members = R"("meshes": [{"name": "Mixed", "primitives": [
            {"attributes": {"POSITION": )" + std::to_string(q.position) + R"(}, "mode": 0},
            {"attributes": {"POSITION": )" + std::to_string(q.position) + R"(}, "mode": 1},
            {"attributes": {"POSITION": )" + std::to_string(q.position) + R"(}, "indices": )" +
                                std::to_string(q.indices) + "}]}], " + singleNodeScene(R"({"mesh": 0})");
    const std::string path = b.writeGltf(dir(), "points_lines", members);
    const Scene scene = loadQuiet(path);
    REQUIRE(scene.meshes.size() == 1);
    CHECK(scene.meshes[0].name == "Mixed/2");
    REQUIRE(scene.warnings.size() == 1);
    CHECK_THAT(scene.warnings[0], Catch::Contains("skipped 2 point/line") && Catch::Contains("mesh 0 'Mixed' primitive 0") &&
                                      Catch::Contains(path));
    CHECK_THROWS_WITH(loadQuiet(path, /*strict=*/true), Catch::Contains("point/line") && Catch::Contains("--strict"));
}

TEST_CASE("Sparse accessors override the dense values or zeros", "[scene]") {
    GltfBuilder b;
    // Dense quad positions with vertices 1 and 2 replaced: (1,0,0) → (4,0,0), (1,1,0) → (4,2,0).
    const int dense = b.view(std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    const int sparseIndices = b.view(std::vector<uint16_t>{1, 2});
    const int sparseValues = b.view(std::vector<float>{4, 0, 0, 4, 2, 0});
    const std::string sparse = R"("sparse": {"count": 2, "indices": {"bufferView": )" + std::to_string(sparseIndices) +
                               R"(, "componentType": 5123}, "values": {"bufferView": )" + std::to_string(sparseValues) + "}}";
    const int overridden = b.accessor(dense, kFloat, 4, "VEC3", sparse);
    // No bufferView: three zero vectors, two of which the sparse values replace → a triangle
    // (0,0,0) (4,0,0) (4,2,0).
    const int fromZeros = b.accessor(-1, kFloat, 3, "VEC3", sparse);
    const int indices = b.indices({0, 1, 2, 0, 2, 3});
    const std::string members = R"("meshes": [{"primitives": [
            {"attributes": {"POSITION": )" + std::to_string(overridden) + R"(}, "indices": )" + std::to_string(indices) + R"(},
            {"attributes": {"POSITION": )" + std::to_string(fromZeros) + R"(}}]}], )" + singleNodeScene(R"({"mesh": 0})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "sparse", members));
    REQUIRE(scene.meshes.size() == 2);
    const std::vector<vec3> expected{{0, 0, 0}, {4, 0, 0}, {4, 2, 0}, {0, 1, 0}};
    REQUIRE(scene.meshes[0].positions.size() == 4);
    for (size_t i = 0; i < 4; ++i) CHECK_NEAR(vl::test::world(scene, scene.meshes[0].positions[i]), expected[i]);
    REQUIRE(scene.meshes[1].positions.size() == 3);
    for (size_t i = 0; i < 3; ++i) CHECK_NEAR(vl::test::world(scene, scene.meshes[1].positions[i]), expected[i]);
}

TEST_CASE("Normalized integer attributes and interleaved strides decode exactly", "[scene]") {
    GltfBuilder b;
    // POSITION and NORMAL interleaved, 24-byte stride.
    const std::vector<float> interleaved{0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
    const int vertexView = b.view(interleaved, 24);
    const int position = b.accessor(vertexView, kFloat, 3, "VEC3");
    const int normal = b.accessor(vertexView, kFloat, 3, "VEC3", "", 12);
    // TEXCOORD_0: normalized unsigned short; TEXCOORD_1: normalized signed byte (−128 clamps to −1).
    const int uv0 = b.accessor(b.view(std::vector<uint16_t>{0, 65535, 32768, 0, 65535, 65535}), kUnsignedShort, 3, "VEC2",
                               R"("normalized": true)");
    const int uv1 = b.accessor(b.view(std::vector<int8_t>{-128, 127, -127, 0, 64, 0, 0, 0}), kByte, 3, "VEC2",
                               R"("normalized": true)");
    // COLOR_0: normalized unsigned byte VEC3 with a 4-byte stride (alpha defaults to 1).
    const int color = b.accessor(b.view(std::vector<uint8_t>{255, 51, 0, 9, 0, 255, 102, 9, 0, 0, 0, 9}, 4),
                                 kUnsignedByte, 3, "VEC3", R"("normalized": true)");
    const std::string members = R"("meshes": [{"primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
                                R"(, "NORMAL": )" + std::to_string(normal) + R"(, "TEXCOORD_0": )" + std::to_string(uv0) +
                                R"(, "TEXCOORD_1": )" + std::to_string(uv1) + R"(, "COLOR_0": )" + std::to_string(color) +
                                "}}]}], " + singleNodeScene(R"({"mesh": 0})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "normalized", members));
    REQUIRE(scene.meshes.size() == 1);
    const Mesh& mesh = scene.meshes[0];
    CHECK_NEAR(vl::test::world(scene, mesh.positions[1]), vec3(1, 0, 0));
    CHECK_NEAR(vl::test::world(scene, mesh.positions[2]), vec3(0, 1, 0));
    CHECK_NEAR(mesh.normals[1], vec3(0, 0, 1));
    REQUIRE(mesh.uv0.size() == 3);
    CHECK_NEAR(mesh.uv0[0], vec2(0, 1));
    CHECK_NEAR(mesh.uv0[1], vec2(32768.0f / 65535.0f, 0));
    CHECK_NEAR(mesh.uv0[2], vec2(1, 1));
    CHECK_NEAR(mesh.uv1[0], vec2(-1, 1));
    CHECK_NEAR(mesh.uv1[1], vec2(-1, 0));
    CHECK_NEAR(mesh.uv1[2], vec2(64.0f / 127.0f, 0));
    REQUIRE(mesh.colors.size() == 3);
    CHECK_NEAR(mesh.colors[0], vec4(1, 0.2f, 0, 1));
    CHECK_NEAR(mesh.colors[1], vec4(0, 1, 0.4f, 1));
}

TEST_CASE("Missing normals are the area-weighted average of the adjacent faces", "[scene]") {
    GltfBuilder b;
    // Vertex 0 is shared by a triangle of area 2 facing +Z and one of area 0.5 facing +X:
    // its normal is (2·(0,0,1) + 0.5·(1,0,0)) normalized = (1, 0, 4)/√17.
    const int position = b.vec3({0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 1, 0, 0, 0, 1});
    const int indices = b.indices({0, 1, 2, 0, 3, 4});
    const std::string members = R"("meshes": [{"primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
                                R"(}, "indices": )" + std::to_string(indices) + "}]}], " +
                                singleNodeScene(R"({"mesh": 0})");
    const Scene scene = loadQuiet(b.writeGltf(dir(), "area_weighted", members));
    REQUIRE(scene.meshes.size() == 1);
    const Mesh& mesh = scene.meshes[0];
    REQUIRE(mesh.normals.size() == 5);
    CHECK_NEAR(mesh.normals[0], vec3(1, 0, 4) / std::sqrt(17.0f), 1e-6f);
    CHECK_NEAR(mesh.normals[1], vec3(0, 0, 1), 1e-6f);
    CHECK_NEAR(mesh.normals[3], vec3(1, 0, 0), 1e-6f);
}

TEST_CASE("Zero-area triangles are dropped and counted", "[scene]") {
    GltfBuilder b;
    // Good quad (2 triangles), a triangle with a repeated index and one with collinear corners.
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0});
    const int indices = b.indices({0, 1, 2, 0, 0, 1, 0, 2, 3, 0, 1, 4});
    const std::string members = R"("meshes": [{"primitives": [{"attributes": {"POSITION": )" + std::to_string(position) +
                                R"(}, "indices": )" + std::to_string(indices) + "}]}], " +
                                singleNodeScene(R"({"mesh": 0})");
    const std::string path = b.writeGltf(dir(), "degenerate", members);
    const Scene scene = loadQuiet(path);
    CHECK(scene.degenerateTrianglesDropped == 2);
    REQUIRE(scene.meshes.size() == 1);
    CHECK(scene.meshes[0].indices == std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
    REQUIRE(scene.warnings.size() == 1);
    CHECK_THAT(scene.warnings[0], Catch::Contains("dropped 2 degenerate"));
}

TEST_CASE("The default scene is loaded and other scenes are not", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    const std::string members = R"("meshes": [)" + quadMesh(q) + R"(], "scene": 1,
        "scenes": [{"nodes": [0]}, {"nodes": [1]}],
        "nodes": [{"mesh": 0, "translation": [5, 0, 0]}, {"mesh": 0, "translation": [0, 7, 0]}])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "two_scenes", members));
    REQUIRE(scene.meshes.size() == 1);
    CHECK_NEAR(vl::test::world(scene, scene.meshes[0].positions[0]), vec3(0, 7, 0));
}

TEST_CASE("A mesh used by two nodes becomes two world-space meshes", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    const std::string members = R"("meshes": [)" + quadMesh(q) + R"(], "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [0, 0, -2]}])";
    const Scene scene = loadQuiet(b.writeGltf(dir(), "instanced", members));
    REQUIRE(scene.meshes.size() == 2);
    CHECK_NEAR(vl::test::world(scene, scene.meshes[1].positions[2]), vec3(1, 1, -2));
    CHECK(scene.triangleCount() == 4);
    CHECK_NEAR(vl::test::world(scene, scene.bounds().lower), vec3(0, 0, -2));
    CHECK_NEAR(vl::test::world(scene, scene.bounds().upper), vec3(1, 1, 0));
    // The local frame is centred on the geometry's box (scene.h).
    CHECK_NEAR(scene.bounds().lower, -scene.bounds().upper);
}

TEST_CASE("GLB files and embedded data URIs load the same geometry as .gltf with a .bin", "[scene]") {
    GltfBuilder b;
    const QuadAccessors q = addQuad(b);
    const std::string members =
        R"("meshes": [)" + quadMesh(q) + "], " + singleNodeScene(R"({"mesh": 0, "translation": [0, 0, 1]})");
    const std::vector<std::string> paths{b.writeGlb(dir(), "quad", members),
                                         b.writeGltf(dir(), "quad_embedded", members, /*embedBuffer=*/true)};
    for (const std::string& path : paths) {
        INFO(path);
        const Scene scene = loadQuiet(path);
        REQUIRE(scene.meshes.size() == 1);
        CHECK_NEAR(vl::test::world(scene, scene.meshes[0].positions[2]), vec3(1, 1, 1));
        CHECK(scene.meshes[0].indices == std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
        CHECK_NEAR(scene.meshes[0].uv0[3], vec2(0, 0));
    }
}
