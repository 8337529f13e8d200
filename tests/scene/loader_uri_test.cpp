// Files a scene points at (issue 15, part 4): a glTF uri that leaves the scene's folder is
// refused unless LoadOptions::filesOutsideScene allows it, so a downloaded scene cannot read
// other files of the machine into a texture; data: URIs and files beside the scene load.
#include "core/error.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

using namespace vl;
namespace fs = std::filesystem;

namespace {

// One triangle whose positions lie in a buffer at `bufferUri`, and an image at `imageUri`
// ("" none), written as `folder`/scene.gltf.
std::string scene(const fs::path& folder, const std::string& bufferUri, const std::string& imageUri = "") {
    fs::create_directories(folder);
    std::string json = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"uri": ")" + bufferUri + R"(", "byteLength": 36}])";
    if (!imageUri.empty()) json += R"(, "images": [{"uri": ")" + imageUri + R"("}])";
    json += "}";
    const fs::path path = folder / "scene.gltf";
    std::ofstream(path) << json;
    return path.string();
}

void writeTriangle(const fs::path& file) {
    fs::create_directories(file.parent_path());
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(positions), sizeof positions);
}

}  // namespace

TEST_CASE("A glTF uri that leaves the scene's folder is refused, naming the element and the uri", "[scene]") {
    const fs::path root = test::tempDir("uri-confinement");
    fs::remove_all(root);
    writeTriangle(root / "outside.bin");  // beside the scene's folder, not in it
    writeTriangle(root / "scene" / "inside.bin");
    writeTriangle(root / "scene" / "textures" / "below.bin");
    fs::create_directories(root / "scene");
    fs::create_symlink(root / "outside.bin", root / "scene" / "link.bin");
    const fs::path folder = root / "scene";

    // Files in the folder and below it load as before.
    CHECK(loadGltf(scene(folder, "inside.bin")).meshes.size() == 1);
    CHECK(loadGltf(scene(folder, "textures/below.bin")).meshes.size() == 1);
    CHECK(loadGltf(scene(folder, "textures/../inside.bin")).meshes.size() == 1);  // stays inside

    const std::string absolute = (root / "outside.bin").string();
    for (const std::string& uri : {std::string("../outside.bin"), std::string("%2E%2E/outside.bin"),
                                   std::string("textures/../../outside.bin"), std::string("link.bin")}) {
        INFO(uri);
        const std::string path = scene(folder, uri);
        CHECK_THROWS_WITH(loadGltf(path), Catch::Contains(path) && Catch::Contains("buffer 0 ('" + uri + "')") &&
                                              Catch::Contains("outside the scene's folder") &&
                                              Catch::Contains("files-outside-scene=true"));
        LoadOptions allowed;
        allowed.filesOutsideScene = true;
        CHECK(loadGltf(path, allowed).meshes.size() == 1);
    }
    // An absolute path is not read, allowed or not (uris are relative to the file's folder).
    for (const bool allow : {false, true}) {
        LoadOptions options;
        options.filesOutsideScene = allow;
        CHECK_THROWS_WITH(loadGltf(scene(folder, absolute), options),
                          Catch::Contains("buffer 0 ('" + absolute + "') is an absolute path, which is not read"));
    }
    // An image's uri is held to the same; so is a scheme, allowed or not.
    CHECK_THROWS_WITH(loadGltf(scene(folder, "inside.bin", "../../../../etc/passwd")),
                      Catch::Contains("image 0 ('../../../../etc/passwd')") && Catch::Contains("outside the scene's folder"));
    for (const std::string& uri : {"file://" + absolute, std::string("http://example.com/x.bin")}) {
        INFO(uri);
        LoadOptions allowed;
        allowed.filesOutsideScene = true;
        CHECK_THROWS_WITH(loadGltf(scene(folder, uri), allowed),
                          Catch::Contains("buffer 0") && Catch::Contains(":' URI: only data: URIs and files beside the scene"));
    }
    // data: URIs load.
    const std::string data = "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    CHECK(loadGltf(scene(folder, data)).meshes.size() == 1);
}
