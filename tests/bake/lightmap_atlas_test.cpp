// The atlas a bake makes (issue 34): lightmap-res N is an N × N atlas, growing it is the
// user's choice (lightmap-res auto, lightmap-texel), and charts under 2 × 2 texels that no
// neighbour takes are reported by mesh.
#include "bake/bake_job.h"
#include "bake/bake_settings.h"
#include "bake/job_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "scene/gltf_builder.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

using namespace vl;
using namespace vl::test;
namespace fs = std::filesystem;

namespace {

BakeJob atlasJob(const std::string& scene, const fs::path& out) {
    fs::remove_all(out);
    BakeJob job;
    job.scenePath = scene;
    job.outputDir = out.string();
    job.settings = quietSettings();
    job.settings.voxel.resolution = 32;
    job.settings.outputs.gltf = false;
    return job;
}

nlohmann::json bakeJson(const fs::path& out) { return nlohmann::json::parse(std::ifstream(out / "bake.json")); }

bool warned(const BakeReport& report, const std::string& text) {
    return std::any_of(report.warnings.begin(), report.warnings.end(),
                       [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

// A 2 m floor without TEXCOORD_1, and a 5 mm speck floating above it in a mesh of its own,
// lit by a point light.
std::string floorAndSpeck(const fs::path& dir) {
    GltfBuilder b;
    const int floorPositions = b.vec3({-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1});
    const int floorIndices = b.indices({0, 1, 2, 0, 2, 3});
    const int speckPositions = b.vec3({0, 0.5f, 0, 0.005f, 0.5f, 0, 0, 0.5f, -0.005f});
    const int speckIndices = b.indices({0, 1, 2});
    const std::string members =
        R"("meshes": [{"name": "Floor", "primitives": [{"attributes": {"POSITION": )" + std::to_string(floorPositions) +
        R"(}, "indices": )" + std::to_string(floorIndices) + R"(}]},
                      {"name": "Speck", "primitives": [{"attributes": {"POSITION": )" + std::to_string(speckPositions) +
        R"(}, "indices": )" + std::to_string(speckIndices) + R"(}]}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 200}]}},
        "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"mesh": 1}, {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 1.5, 0]}])";
    fs::create_directories(dir);
    return b.writeGltf(dir.string(), "floor_and_speck", members);
}

}  // namespace

TEST_CASE("lightmap-res takes a size or auto, lightmap-texel metres; bad values are refused by name", "[bake]") {
    const SettingsTable<BakeSettings>& table = bakeSettingsTable();
    BakeSettings s;
    applySetting(table, s, "lightmap-res", "auto");
    CHECK(s.lightmap.autoResolution);
    CHECK(s.lightmap.width == 256);
    CHECK_THAT(describeBakeSettings(s), Catch::Contains("lightmap-res=auto"));
    applySetting(table, s, "lightmap-res", "512");
    CHECK_FALSE(s.lightmap.autoResolution);
    CHECK(s.lightmap.width == 512);
    CHECK(s.lightmap.height == 512);
    applySetting(table, s, "lightmap-texel", "0.02");
    CHECK(s.lightmap.texelSize == 0.02);
    CHECK_THAT(describeBakeSettings(s), Catch::Contains("lightmap-texel=0.02"));
    applySetting(table, s, "lightmap-texel", "0");
    CHECK(s.lightmap.texelSize == 0.0);
    CHECK_THAT(describeBakeSettings(s), !Catch::Contains("lightmap-texel"));

    for (const char* bad : {"", "big", "0", "-4", "16385", "1e3", "512px", "Auto", "auto "}) {
        INFO("lightmap-res '" << bad << "'");
        BakeSettings settings;
        CHECK_THROWS_WITH(applySetting(table, settings, "lightmap-res", bad), Catch::Contains("lightmap-res"));
        CHECK(settings.lightmap.width == 256);
        CHECK_FALSE(settings.lightmap.autoResolution);
    }
    for (const char* bad : {"", "2cm", "-0.01", "1e-9", "nan", "inf", "1e7"}) {
        INFO("lightmap-texel '" << bad << "'");
        BakeSettings settings;
        CHECK_THROWS_WITH(applySetting(table, settings, "lightmap-texel", bad), Catch::Contains("lightmap-texel"));
        CHECK(settings.lightmap.texelSize == 0.0);
    }
    // In a job file: the file, the scene and the setting.
    const fs::path dir = tempDir("atlas-settings");
    std::ofstream(dir / "job.json") << R"({"scenes": [{"path": "a.gltf", "settings": {"lightmap-texel": "2 cm"}}]})";
    CHECK_THROWS_AS(readJobFile((dir / "job.json").string(), BakeSettings{}, "output"), SettingsError);
    CHECK_THROWS_WITH(readJobFile((dir / "job.json").string(), BakeSettings{}, "output"),
                      Catch::Contains("job.json") && Catch::Contains("lightmap-texel") && Catch::Contains("2 cm"));
    std::ofstream(dir / "job.json") << R"({"settings": {"lightmap-res": "auto"},
        "scenes": [{"path": "a.gltf"}, {"path": "b.gltf", "settings": {"lightmap-res": 128}}]})";
    const std::vector<BakeJob> jobs = readJobFile((dir / "job.json").string(), BakeSettings{}, "output");
    REQUIRE(jobs.size() == 2);
    CHECK(jobs[0].settings.lightmap.autoResolution);
    CHECK_FALSE(jobs[1].settings.lightmap.autoResolution);  // the scene's own size replaces auto
    CHECK(jobs[1].settings.lightmap.width == 128);
}

TEST_CASE("A bake keeps the atlas size asked and lists its charts under 2 x 2 texels by mesh in bake.json", "[bake]") {
    // At 64² the floor's texel is about 3 cm: the 5 mm speck is one chart under 2 × 2 texels
    // with no neighbour to join, named in bake.json and in a warning. The atlas stays 64²,
    // where the floor alone could have packed at a finer texel in a larger one.
    const fs::path dir = tempDir("atlas-small-charts");
    const fs::path out = dir / "bake";
    BakeJob job = atlasJob(floorAndSpeck(dir), out);
    job.settings.lightmap.width = job.settings.lightmap.height = 64;
    const BakeReport report = runBake(job);
    INFO(report.error);
    REQUIRE(report.ok);
    REQUIRE(report.lightmapUvs);
    CHECK(report.lightmapUvs->width == 64);
    CHECK(report.lightmapUvs->charts == 2);
    const Image lightmap = readImage((out / "lightmap.exr").string());
    CHECK(lightmap.width == 64);
    CHECK(lightmap.height == 64);
    const nlohmann::json uvs = bakeJson(out).at("lightmap_uvs");
    INFO(uvs.dump());
    CHECK(uvs.at("width") == 64);
    CHECK(uvs.at("charts") == 2);
    REQUIRE(uvs.at("small_charts").size() == 1);
    CHECK(uvs.at("small_charts")[0].at("mesh") == "Speck/0");
    CHECK(uvs.at("small_charts")[0].at("charts") == 1);
    CHECK(warned(report, "Speck/0 (1)"));
    CHECK_FALSE(warned(report, "Floor"));
}

TEST_CASE("lightmap-res auto and lightmap-texel give the density asked, in the atlas that holds it", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string box = sharedDir() + "/scenes/cornellbox-nvpro/cornellBox.gltf";  // no TEXCOORD_1
    const fs::path dir = tempDir("atlas-density");
    {
        // auto: at least half a voxel per texel, in the smallest power-of-two square.
        BakeJob job = atlasJob(box, dir / "auto");
        job.settings.lightmap.autoResolution = true;
        const BakeReport report = runBake(job);
        INFO(report.error);
        REQUIRE(report.ok);
        REQUIRE(report.lightmapUvs);
        const LightmapUvReport& uvs = *report.lightmapUvs;
        INFO(describeLightmapUvs(uvs) << ", voxel size " << report.voxelSize);
        CHECK(uvs.askedTexelSize == Approx(kAutoTexelPerVoxel * report.voxelSize).epsilon(1e-12));
        CHECK(uvs.texelSize <= uvs.askedTexelSize);
        CHECK(uvs.width == uvs.height);
        CHECK((uvs.width & (uvs.width - 1)) == 0);
        CHECK(readImage((dir / "auto" / "lightmap.exr").string()).width == uvs.width);
        CHECK(bakeJson(dir / "auto").at("lightmap_uvs").at("texel_size_asked") == uvs.askedTexelSize);
    }
    {
        // A texel size: exactly it, in a square a multiple of 4 texels a side.
        BakeJob job = atlasJob(box, dir / "texel");
        job.settings.lightmap.texelSize = 0.1;
        const BakeReport report = runBake(job);
        INFO(report.error);
        REQUIRE(report.ok);
        REQUIRE(report.lightmapUvs);
        const LightmapUvReport& uvs = *report.lightmapUvs;
        CHECK(uvs.texelSize == 0.1);
        CHECK(uvs.width == uvs.height);
        CHECK(uvs.width % 4 == 0);
        const Image lightmap = readImage((dir / "texel" / "lightmap.exr").string());
        CHECK(lightmap.width == uvs.width);
        CHECK(lightmap.height == uvs.height);
    }
    {
        // The meshes' own TEXCOORD_1: the atlas whose texels are that size on average.
        const std::string quad = sharedDir() + "/reference/cornell_quad.gltf";
        BakeJob job = atlasJob(quad, dir / "authored");
        job.settings.lightmap.texelSize = 0.02;
        const BakeReport report = runBake(job);
        INFO(report.error);
        REQUIRE(report.ok);
        CHECK_FALSE(report.lightmapUvs);
        const Scene scene = loadGltf(quad);
        double surface = 0.0, uv = 0.0;
        for (const Mesh& mesh : scene.meshes) {
            if (mesh.uv1.empty() || scene.materialOf(mesh).emissive()) continue;
            for (size_t t = 0; t < mesh.triangleCount(); ++t) {
                const uint32_t* i = &mesh.indices[3 * t];
                surface += 0.5 * double(glm::length(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]],
                                                              mesh.positions[i[2]] - mesh.positions[i[0]])));
                const vec2 a = mesh.uv1[i[0]], b = mesh.uv1[i[1]], c = mesh.uv1[i[2]];
                uv += 0.5 * std::abs(double(b.x - a.x) * (c.y - a.y) - double(b.y - a.y) * (c.x - a.x));
            }
        }
        const Image lightmap = readImage((dir / "authored" / "lightmap.exr").string());
        CHECK(lightmap.width == lightmap.height);
        CHECK(lightmap.width % 4 == 0);
        const double texel = std::sqrt(surface / uv) / lightmap.width;  // metres per texel, on average
        CHECK(texel <= 0.02);
        CHECK(texel > 0.02 * (lightmap.width - 4) / lightmap.width);
    }
}
