// The three-scene job the cluster tests bake, locally and split into units, and how their
// outputs are compared.
#pragma once

#include "support/paths.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace vl::test {

// A job of three scenes: the point-lit box, its blocks in an atlas group of their own; the window room under an image sky, turned; the
// classroom (generated lightmap UVs, a sun and a uniform sky, two cameras), as their job files
// and the README light them.
inline std::filesystem::path writeThreeSceneJob(const std::filesystem::path& root) {
    const std::filesystem::path job = root / "job.json";
    std::filesystem::create_directories(root);
    nlohmann::json j;
    j["settings"] = {{"resolution", 32}, {"lightmap-res", 64}, {"width", 48}, {"height", 32},
                     {"images", true},   {"grids", true}};
    j["scenes"] = {{{"path", sourceDir() + "/scenes/cornell_box_point.gltf"},
                    {"atlases", {{{"name", "blocks"}, {"meshes", {"ShortBlock", "TallBlock"}}, {"resolution", 96}}}}},
                   {{"path", sourceDir() + "/scenes/window_room.gltf"},
                    {"sky", {{"image", sourceDir() + "/scenes/skies/afternoon.exr"}, {"rotation", 30}}}},
                   {{"path", sourceDir() + "/scenes/classroom.gltf"},
                    {"sky", {{"radiance", {0.55, 0.7, 1.0}}}},
                    {"lights", {{{"name", "sun"}, {"type", "directional"}, {"direction", {-0.7, -0.55, -0.45}},
                                 {"intensity", 12}, {"angle", 0.53}}}},
                    {"cameras", {{{"name", "corner"}, {"position", {0.6, 1.7, -0.4}}, {"target", {6.5, 1.1, -5.5}},
                                  {"yfov", 0.95}}}}}};
    std::ofstream(job) << j.dump(2);
    return job;
}

inline std::string fileBytes(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// bake.json without what differs from run to run (timings, peak memory).
inline nlohmann::json reportWithoutTimes(const std::filesystem::path& file) {
    nlohmann::json j = nlohmann::json::parse(fileBytes(file));
    for (const char* key : {"stage_seconds", "total_seconds", "peak_memory_bytes"}) j.erase(key);
    if (j.contains("lightmap_uvs")) j["lightmap_uvs"].erase("seconds");
    return j;
}

// Checks that every file of `files` is the same bytes in both folders (bake.json: but its
// timings); returns how many were compared.
inline size_t checkSameOutputs(const std::filesystem::path& expected, const std::filesystem::path& actual,
                               const std::vector<std::string>& files) {
    for (const std::string& file : files) {
        INFO(actual / file);
        if (file == "bake.json")
            CHECK(reportWithoutTimes(actual / file) == reportWithoutTimes(expected / file));
        else
            CHECK(fileBytes(actual / file) == fileBytes(expected / file));
    }
    return files.size();
}

}  // namespace vl::test
