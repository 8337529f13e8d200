// voxlight bench: a tiny run end to end (its CSV has the declared columns and finite values;
// its reports name no file by an absolute path), the path-traced reference's cache key, and
// the time-to-reach interpolation on hand-made fronts. The metrics themselves are tested in
// tests/metrics.
#include "bench/display_path.h"
#include "bench/reference.h"
#include "bench/report.h"
#include "bench/run.h"
#include "core/error.h"
#include "support/paths.h"
#include "tiny_job.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

using namespace vl;
namespace fs = std::filesystem;

namespace {

using test::tinyJob;

BenchReferenceSettings tinyReference(const std::string& cache) {
    BenchReferenceSettings s;
    s.targetNoise = 0.2;
    s.pilotSpp = 4;
    s.maxSpp = 64;
    s.cacheDir = cache;
    s.quiet = true;
    return s;
}

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> fields;
    std::string field;
    std::istringstream in(line);
    while (std::getline(in, field, ',')) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.push_back("");
    return fields;
}

std::string readText(const fs::path& path) {
    std::ifstream in(path);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

// Every string value in a JSON document.
void collectStrings(const nlohmann::json& j, std::vector<std::string>& out) {
    if (j.is_string()) out.push_back(j.get<std::string>());
    else if (j.is_structured())
        for (const auto& item : j) collectStrings(item, out);
}

}  // namespace

TEST_CASE("A tiny bench run writes bench.csv with the declared columns and finite values", "[bench]") {
    const std::string out = test::tempDir("bench_tiny");
    fs::remove_all(out);
    const std::string cache = test::tempDir("bench_tiny_cache");
    fs::remove_all(cache);
    BenchOptions options;
    options.base = tinyJob(out);
    options.points = {{"vct", "default", {}, 0},
                      {"vct", "cones=6", {{"cones", "6"}}, 0},
                      {"vct", "resolution=15", {{"resolution", "15"}}, 0},
                      {"path", "spp=4", {}, 4}};
    options.repeats = 2;
    options.referenceSettings = tinyReference(cache);
    options.blender = "none";
    options.plot = false;
    options.quiet = true;
    const BenchResult result = runBench(options);

    REQUIRE(result.points.size() == 4);
    for (const BenchPointResult& p : result.points) {
        INFO(p.spec.method << " " << p.spec.label << ": " << p.error);
        CHECK(p.ok);
    }
    CHECK(result.reference.hasLightmapIndirect);
    CHECK(result.reference.hasImageIndirect);
    CHECK(result.reference.lightmapSpp >= 4);
    CHECK(result.reference.lightmapSpp % 4 == 0);  // a multiple of the 2 × 2 receiver samples of a texel

    const std::vector<std::string> lines = [&] {
        std::vector<std::string> v;
        std::istringstream in(readText(fs::path(out) / "bench.csv"));
        std::string line;
        while (std::getline(in, line)) v.push_back(line);
        return v;
    }();
    REQUIRE(lines.size() == 5);
    CHECK(split(lines[0]) == benchCsvColumns());
    const auto& columns = benchCsvColumns();
    const auto column = [&](const std::string& name) {
        return static_cast<size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin());
    };
    for (size_t row = 1; row < lines.size(); ++row) {
        const std::vector<std::string> f = split(lines[row]);
        INFO(lines[row]);
        REQUIRE(f.size() == columns.size());
        CHECK(f[column("ok")] == "1");
        // Every number from the times to the last error: present, finite and non-negative.
        for (size_t c = column("lightmap_seconds"); c <= column("image_indirect_smape"); ++c) {
            INFO(columns[c]);
            REQUIRE_FALSE(f[c].empty());
            char* end = nullptr;
            const double v = std::strtod(f[c].c_str(), &end);
            CHECK(*end == '\0');
            CHECK(std::isfinite(v));
            CHECK(v >= 0.0);
        }
        // The lightmap-lit image, VCT and path tracer alike (each lights the camera by its lightmap).
        for (const char* name : {"lightmapped_relrmse", "lightmapped_relmse", "lightmapped_smape"}) {
            INFO(name);
            REQUIRE_FALSE(f[column(name)].empty());
            const double v = std::strtod(f[column(name)].c_str(), nullptr);
            CHECK(std::isfinite(v));
            CHECK(v >= 0.0);
        }
        CHECK(std::strtod(f[column("lightmapped_relrmse")].c_str(), nullptr) < 1.0);
        // SMAPE is bounded by 1 by definition; relative RMSE of these bakes is far below 100%.
        CHECK(std::strtod(f[column("lightmap_smape")].c_str(), nullptr) <= 1.0);
        CHECK(std::strtod(f[column("lightmap_relrmse")].c_str(), nullptr) < 1.0);
        CHECK(std::strtod(f[column("runs")].c_str(), nullptr) == 2.0);
    }
    for (const char* file : {"bench.json", "bench.md", "plot/bench.gp", "heatmaps/vct-default_lightmap.png",
                             "heatmaps/vct-default_lightmapped.png", "points/vct-default/image_lightmapped.exr",
                             "points/path-spp_4/image_lightmapped.exr"}) {
        INFO(file);
        CHECK(fs::exists(fs::path(out) / file));
    }
    const std::string md = readText(fs::path(out) / "bench.md");
    CHECK(md.find("| vct | cones=6 |") != std::string::npos);
    // The headline compares the path tracer with the VCT default on both outputs.
    const nlohmann::json headline = nlohmann::json::parse(readText(fs::path(out) / "bench.json"))["headline"];
    CHECK(headline["vct_default"]["lightmapped_relative_rmse"].get<double>() > 0.0);
    CHECK(md.find("lightmap-lit image relative RMSE") != std::string::npos);
    for (const char* output : {"lightmap", "image"}) {
        INFO(output);
        CHECK(headline["vct_default"][std::string(output) + "_seconds"].get<double>() > 0.0);
        CHECK(headline["path"][output]["seconds_to_reach_vct_error"].get<double>() > 0.0);
        CHECK(md.find(std::string("at equal ") + output + " error") != std::string::npos);
    }
    CHECK(md.find("How the stages scale") == std::string::npos);  // options.scaling is off

    // The default's voxel size against the resolution points, by error² × time: recomputed
    // here from the points' own figures.
    const nlohmann::json json = nlohmann::json::parse(readText(fs::path(out) / "bench.json"));
    const nlohmann::json& voxel = headline["voxel_size"];
    CHECK(voxel["set_by"] == "the resolution setting");  // tinyJob sets one
    CHECK(md.find("- **Voxel size**: the default chose") != std::string::npos);
    for (const char* output : {"lightmap", "image"}) {
        INFO(output);
        double merit[2] = {0.0, 0.0};  // default, resolution=15
        for (const nlohmann::json& p : json["points"]) {
            const std::string label = p["label"];
            if (label != "default" && label != "resolution=15") continue;
            const double e = p[output]["relative_rmse"], t = p[std::string(output) + "_seconds"];
            merit[label == "default" ? 0 : 1] = e * e * t;
            CHECK(p["voxel_size"].get<double>() > 0.0);
        }
        REQUIRE(merit[0] > 0.0);
        REQUIRE(merit[1] > 0.0);
        CHECK(voxel[output]["points"].size() == 2);
        CHECK(voxel[output]["default_over_best"].get<double>() ==
              Approx(merit[0] / std::min(merit[0], merit[1])).epsilon(1e-9));
        CHECK(voxel[output]["best"] == (merit[0] <= merit[1] ? "default" : "resolution=15"));
    }
}

TEST_CASE("Every point of the bench sweeps is a valid bake setting, labelled once", "[bench]") {
    for (bool full : {false, true}) {
        INFO("full " << full);
        const std::vector<BenchPointSpec> sweep = benchSweep(full);
        std::set<std::string> labels;
        for (const BenchPointSpec& p : sweep) {
            INFO(p.method << " " << p.label);
            CHECK(labels.insert(p.method + " " + p.label).second);
            if (p.method != "vct") continue;
            BakeSettings settings;
            for (const auto& [name, value] : p.settings) CHECK_NOTHROW(applySetting(bakeSettingsTable(), settings, name, value));
            CHECK_NOTHROW(validateBakeSettings(settings));
        }
        CHECK(labels.count("vct default"));
        CHECK(labels.count("vct gather-visibility=cones"));
        CHECK(labels.count("vct resolution=48 rays=8"));
        CHECK(labels.count("vct gather-level=-1") == (full ? 1u : 0u));
    }
}

TEST_CASE("Bench reports name a file relative to the repository, ../shared or the bench folder", "[bench]") {
    const std::string repo = test::sourceDir();
    const std::string out = "/nonexistent-voxlight-bench/out";  // outside the repository
    CHECK(displayPath(repo + "/scenes/cornell_box.gltf", out) == "scenes/cornell_box.gltf");
    CHECK(displayPath(repo + "/../shared/reference/cornell_quad.gltf", out) == "../shared/reference/cornell_quad.gltf");
    CHECK(displayPath(out + "/points/cycles-spp=16/blender.log", out) == "points/cycles-spp=16/blender.log");
    CHECK(displayPath(out + "/cache/a/image.exr", out + "/") == "cache/a/image.exr");
    // The repository first: the README's commands run from its root, whatever the bench folder.
    CHECK(displayPath(repo + "/output/bench/plot/gnuplot.log", repo + "/output/bench") == "output/bench/plot/gnuplot.log");
    // Outside all three, or already relative: as given.
    CHECK(displayPath("/nonexistent-voxlight-bench/elsewhere/x.exr", out) == "/nonexistent-voxlight-bench/elsewhere/x.exr");
    CHECK(displayPath(repo + "-other/x.exr", out) == repo + "-other/x.exr");  // a sibling sharing the name's start
    CHECK(displayPath(out + "/x.exr", "") == out + "/x.exr");
    CHECK(displayPath("../elsewhere/x.exr", out) == "../elsewhere/x.exr");
}

TEST_CASE("A bench's reports name no file by this machine's absolute paths", "[bench]") {
    // The bench folder outside the repository (one per build folder), so that what lies in it
    // is named relative to it; the scene is named by its absolute path in the repository.
    const fs::path out = fs::temp_directory_path() /
                         ("voxlight-bench-paths-" + std::to_string(std::hash<std::string>{}(VOXLIGHT_BINARY_DIR)));
    REQUIRE(fs::weakly_canonical(out).lexically_relative(fs::weakly_canonical(test::sourceDir())).string().rfind("..", 0) == 0);
    fs::remove_all(out);
    const BakeJob job = tinyJob(out.string());
    REQUIRE(fs::path(job.scenePath).is_absolute());
    const BenchReferenceSettings settings = tinyReference((out / "cache").string());
    // A user-named reference image (a path-traced one from the cache), and the lightmap
    // reference it leaves to the path tracer cached beforehand: the report names both.
    const BenchReference traced = prepareBenchReference(job, {}, settings);
    BenchReferenceFiles files;
    files.image = traced.cachePath + "/image.exr";
    const BenchReference lightmapOnly = prepareBenchReference(job, files, settings);
    // A Cycles files folder: one lower-spp lightmap, named as ../shared/reference/cycles names them.
    fs::create_directories(out / "cycles");
    fs::copy_file(fs::path(traced.cachePath) / "lightmap.exr", out / "cycles/cornell_box_lightmap_16spp.exr");

    BenchOptions options;
    options.base = job;
    options.points = {{"vct", "default", {}, 0}};
    options.repeats = 1;
    options.reference = files;
    options.referenceSettings = settings;
    options.cyclesFilesDir = (out / "cycles").string();
    options.blender = "none";
    options.plot = false;
    options.quiet = true;
    const BenchResult result = runBench(options);
    REQUIRE(result.reference.fromCache);
    REQUIRE(result.points.size() == 2);

    const std::string json = readText(out / "bench.json"), md = readText(out / "bench.md"), csv = readText(out / "bench.csv");
    const nlohmann::json j = nlohmann::json::parse(json);
    CHECK(j["scene"] == "scenes/cornell_box.gltf");
    const std::string image = "image: cache/" + fs::path(traced.cachePath).filename().string() + "/image.exr";
    const std::string cache = "[cached in cache/" + fs::path(lightmapOnly.cachePath).filename().string() + "]";
    const std::string description = j["reference"]["description"];
    CHECK(description.find(image) != std::string::npos);
    CHECK(description.find(cache) != std::string::npos);
    CHECK(md.find(image) != std::string::npos);
    CHECK(md.find(cache) != std::string::npos);
    std::vector<std::string> outputs;
    for (const auto& p : j["points"]) outputs.push_back(p["outputs"]);
    CHECK(outputs == std::vector<std::string>{"points/vct-default", "cycles"});

    std::vector<std::string> strings;
    collectStrings(j, strings);
    for (const std::string& s : strings) {
        INFO(s);
        CHECK(s.rfind('/', 0) != 0);
    }
    for (const std::string& absolute : {test::sourceDir(), out.string(), fs::weakly_canonical(out).string()}) {
        INFO(absolute);
        CHECK(json.find(absolute) == std::string::npos);
        CHECK(md.find(absolute) == std::string::npos);
        CHECK(csv.find(absolute) == std::string::npos);
    }
}

TEST_CASE("A path-traced bench reference is cached under the content of the scene files", "[bench]") {
    const fs::path dir = test::tempDir("bench_hash");
    fs::remove_all(dir);
    fs::create_directories(dir / "a");
    fs::create_directories(dir / "b");
    for (const char* f : {"cornell_box.gltf", "cornell_box.bin"}) {
        fs::copy_file(test::sourceDir() + "/scenes/" + f, dir / "a" / f);
        fs::copy_file(test::sourceDir() + "/scenes/" + f, dir / "b" / f);
    }
    const uint64_t a = hashSceneFiles((dir / "a/cornell_box.gltf").string());
    CHECK(a == hashSceneFiles((dir / "b/cornell_box.gltf").string()));  // same content elsewhere
    {
        std::fstream bin(dir / "b/cornell_box.bin", std::ios::in | std::ios::out | std::ios::binary);
        bin.seekp(100);
        bin.put('\x7f');
    }
    CHECK(a != hashSceneFiles((dir / "b/cornell_box.gltf").string()));  // a buffer changed
    CHECK_THROWS_AS(hashSceneFiles((dir / "missing.gltf").string()), InputError);

    BakeJob job = tinyJob((dir / "out").string());
    job.scenePath = (dir / "a/cornell_box.gltf").string();
    const BenchReferenceSettings settings = tinyReference((dir / "cache").string());
    const BenchReference first = prepareBenchReference(job, {}, settings);
    CHECK_FALSE(first.fromCache);
    const BenchReference second = prepareBenchReference(job, {}, settings);
    CHECK(second.fromCache);
    CHECK(second.cachePath == first.cachePath);
    CHECK(second.lightmap.pixels == first.lightmap.pixels);
    CHECK(second.image.pixels == first.image.pixels);
    CHECK(second.lightmapSpp == first.lightmapSpp);
    job.settings.imageWidth = 20;  // another image size is another reference
    CHECK_FALSE(prepareBenchReference(job, {}, settings).fromCache);
    job.settings.sky = vec3(0.5f);  // so is another sky
    const BenchReference skyLit = prepareBenchReference(job, {}, settings);
    CHECK_FALSE(skyLit.fromCache);
    Light sun;  // and another sun's disk
    sun.type = LightType::Directional;
    sun.direction = vec3(0, -1, 0);
    job.addedLights = {sun};
    CHECK_FALSE(prepareBenchReference(job, {}, settings).fromCache);
    job.addedLights[0].angularDiameter = 0.01f;
    CHECK_FALSE(prepareBenchReference(job, {}, settings).fromCache);
    CHECK(prepareBenchReference(job, {}, settings).fromCache);
}

TEST_CASE("Bench time to reach an error follows the Pareto front on log-log axes", "[bench]") {
    // (seconds, error); (8, 0.3) is dominated by (4, 0.2).
    const std::vector<std::pair<double, double>> points = {{16, 0.1}, {1, 0.4}, {8, 0.3}, {4, 0.2}};
    CHECK(paretoFront(points) == std::vector<size_t>{1, 3, 0});
    CHECK(timeToReach(points, 0.2).seconds == Approx(4.0));
    // Halfway in log error between (4, 0.2) and (16, 0.1) is halfway in log time: √(4·16) = 8.
    CHECK(timeToReach(points, std::sqrt(0.2 * 0.1)).seconds == Approx(8.0));
    CHECK(timeToReach(points, std::sqrt(0.2 * 0.1)).how == "interpolated");
    // Below its best error: the Monte Carlo rate, 16 s · (0.1 / 0.05)² = 64 s.
    CHECK(timeToReach(points, 0.05).seconds == Approx(64.0));
    // Above its worst: its fastest point already does better.
    CHECK(timeToReach(points, 0.5).seconds == Approx(1.0));
    CHECK(errorAtTime(points, 8.0).seconds == Approx(std::sqrt(0.02)));
    CHECK(errorAtTime(points, 64.0).seconds == Approx(0.05));
    CHECK_FALSE(timeToReach({}, 0.1).found);
}

TEST_CASE("Bench refuses bad repeats and reports a bad VCT setting as a failed point", "[bench]") {
    BenchOptions options;
    options.base = tinyJob(test::tempDir("bench_bad"));
    options.repeats = 0;
    CHECK_THROWS_AS(runBench(options), SettingsError);

    options.repeats = 1;
    options.points = {{"vct", "bad", {{"cones", "0"}}, 0}};
    options.referenceSettings = tinyReference(test::tempDir("bench_bad_cache"));
    options.blender = "none";
    options.plot = false;
    options.quiet = true;
    const BenchResult result = runBench(options);
    REQUIRE(result.points.size() == 1);
    CHECK_FALSE(result.points[0].ok);
    CHECK(result.points[0].error.find("cones") != std::string::npos);
}
