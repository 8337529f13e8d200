// A bake split into units (cluster/units.h) and run unit by unit in this process writes the
// same bytes as the local bake of the same job; a failed unit fails its scene with its error.
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "cluster/slurm.h"
#include "cluster/units.h"
#include "cluster/voxel_state.h"
#include "core/error.h"
#include "core/image_io.h"
#include "support/paths.h"
#include "three_scenes.h"
#include "scene/gltf_builder.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace vl;
using namespace vl::cluster;
namespace fs = std::filesystem;

namespace {

// The default Cornell box at 16 voxels and a 16² lightmap, into root/out.
BakeJob tinyBoxJob(const fs::path& root) {
    BakeJob job;
    job.scenePath = test::sourceDir() + "/scenes/cornell_box.gltf";
    job.outputDir = (root / "out").string();
    job.settings.quiet = true;
    job.settings.voxel.resolution = 16;
    job.settings.lightmap.width = job.settings.lightmap.height = 16;
    return job;
}

// Runs the voxel unit and every receiver unit of `units` in this process, then the merge; its report.
BakeReport runUnitsAndMerge(const BakeJob& job, const std::string& work, const SceneUnits& units) {
    REQUIRE(runVoxelUnit(job, work).ok);
    for (int r = 0; r < units.receiverCount(); ++r) REQUIRE(runReceiverUnit(job, work, units, r).ok);
    const BakeReport merged = mergeScene(job, work, units);
    INFO(merged.error);
    REQUIRE(merged.ok);
    return merged;
}

}  // namespace


TEST_CASE("A bake run unit by unit writes the same bytes as the local bake", "[cluster]") {
    const fs::path root = test::tempDir("cluster-units");
    fs::remove_all(root);
    BakeSettings defaults;
    defaults.quiet = true;
    std::vector<BakeJob> jobs = readJobFile(test::writeThreeSceneJob(root).string(), defaults, (root / "out").string());
    REQUIRE(jobs.size() == 3);
    size_t compared = 0;
    for (size_t k = 0; k < jobs.size(); ++k) {
        BakeJob local = jobs[k];
        local.outputDir = (root / "local" / std::to_string(k)).string();
        const BakeReport expected = runBake(local);
        INFO(jobs[k].scenePath << ": " << expected.error);
        REQUIRE(expected.ok);

        BakeJob split = jobs[k];
        split.outputDir = (root / "split" / std::to_string(k)).string();
        const std::string work = (root / "work" / std::to_string(k)).string();
        // Three bands an atlas: rows that do not divide evenly.
        const SceneUnits units = planSceneUnits(split, 3);
        REQUIRE(units.atlases.size() == (k == 0 ? 2 : 1));
        CHECK(units.atlases[0].name == "lightmap");
        if (k == 0) CHECK(units.atlases[1].name == "blocks");
        for (const SceneUnits::Atlas& atlas : units.atlases) CHECK(atlas.bands == 3);
        CHECK(units.cameras == (k == 2 ? 2 : 1));
        REQUIRE(runVoxelUnit(split, work).ok);
        for (int r = units.receiverCount() - 1; r >= 0; --r) {
            const UnitRecord record = runReceiverUnit(split, work, units, r);
            INFO(receiverName(units, r) << ": " << record.error);
            REQUIRE(record.ok);
        }
        const BakeReport merged = mergeScene(split, work, units);
        INFO(merged.error);
        REQUIRE(merged.ok);
        CHECK(merged.files == expected.files);
        compared += test::checkSameOutputs(local.outputDir, split.outputDir, expected.files);
    }
    CHECK(compared >= 3 * 12);
}

TEST_CASE("A scene whose lightmaps have no mesh to bake merges as its local bake", "[cluster]") {
    // Khronos' MultiUVTest: its only mesh has a TEXCOORD_1 of its own use, and no atlas is baked.
    VL_SKIP_WITHOUT_SHARED();
    const fs::path root = test::tempDir("cluster-no-atlas");
    fs::remove_all(root);
    BakeJob job;
    job.scenePath = test::sharedDir() + "/scenes/khronos-sample-assets/Models/MultiUVTest/glTF/MultiUVTest.gltf";
    job.settings.quiet = true;
    job.settings.voxel.resolution = 16;
    job.settings.sky = vec3(0.5f);
    job.outputDir = (root / "local").string();
    const BakeReport local = runBake(job);
    INFO(local.error);
    REQUIRE(local.ok);
    job.outputDir = (root / "split").string();
    const std::string work = (root / "work").string();
    const BakeReport merged = runUnitsAndMerge(job, work, planSceneUnits(job, 2));
    CHECK(merged.files == local.files);
    test::checkSameOutputs(root / "local", root / "split", local.files);
}

TEST_CASE("A lightmap whose seams are stitched merges as its local bake, its shadowmask too", "[cluster]") {
    // A 2 × 2 m floor split at x = 1 into two charts of a 32² lightmap, the second turned a
    // quarter and coarser (as bake/lightmap_seams_test.cpp's), under a point light: its seam is
    // stitched after the bands are put together, as the local bake stitches it. A plate without
    // a lightmap, 0.6 m up, casts a shadow across the seam (x 0.8–1.4).
    const fs::path root = test::tempDir("cluster-seams");
    fs::remove_all(root);
    fs::create_directories(root);
    test::GltfBuilder b;
    const int positions = b.vec3({0, 0, 0, 0, 0, 2, 1, 0, 2, 1, 0, 0, 1, 0, 0, 1, 0, 2, 2, 0, 2, 2, 0, 0});
    const int normals = b.vec3({0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0});
    std::vector<float> uv1 = {2, 2, 2, 18, 10, 18, 10, 2, 2, 20, 14, 20, 14, 26, 2, 26};
    for (float& v : uv1) v /= 32.0f;
    const int texcoords = b.vec2(uv1);
    const int indices = b.indices({0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7});
    const int plate = b.vec3({0.75f, 0.6f, 0.7f, 0.75f, 0.6f, 1.1f, 1.05f, 0.6f, 1.1f, 1.05f, 0.6f, 0.7f});
    const int plateIndices = b.indices({0, 1, 2, 0, 2, 3});
    const std::string members =
        R"("meshes": [{"name": "Floor", "primitives": [{"attributes": {"POSITION": )" + std::to_string(positions) +
        R"(, "NORMAL": )" + std::to_string(normals) + R"(, "TEXCOORD_1": )" + std::to_string(texcoords) +
        R"(}, "indices": )" + std::to_string(indices) + R"(}]},
        {"name": "Plate", "primitives": [{"attributes": {"POSITION": )" + std::to_string(plate) +
        R"(}, "indices": )" + std::to_string(plateIndices) + R"(}]}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 30}]}},
        "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.7, 1.2, 0.9]},
                  {"mesh": 1}])";
    const std::string scene = b.writeGltf(root.string(), "split_floor", members);
    // Baked whole, and with the light in shadowmask mode: its mask's bands are put together,
    // dilated and stitched as the local bake's.
    for (const LightBake mode : {LightBake::All, LightBake::Shadowmask}) {
        const fs::path dir = root / lightBakeName(mode);
        BakeJob job;
        job.scenePath = scene;
        job.settings.quiet = true;
        job.settings.voxel.resolution = 16;
        job.settings.lightmap.width = job.settings.lightmap.height = 32;
        job.settings.lightBake = mode;
        job.settings.generateLightmapUvs = false;  // the plate only casts its shadow
        job.outputDir = (dir / "local").string();
        const BakeReport local = runBake(job);
        INFO(lightBakeName(mode) << ": " << local.error);
        REQUIRE(local.ok);
        REQUIRE(local.lightmapSeams);
        CHECK(local.lightmapSeams->after.edges == 1);
        CHECK(local.lightmapSeams->stitched);
        CHECK(local.lightmapSeams->texelsMoved > 0);
        if (mode == LightBake::All)
            CHECK(local.lightmapSeams->afterAtEdge.meanRelative < local.lightmapSeams->beforeAtEdge.meanRelative);
        const bool masked = std::count(local.files.begin(), local.files.end(), "lightmap_shadowmask.png") == 1;
        CHECK(masked == (mode == LightBake::Shadowmask));
        if (masked) {  // the plate's shadow is in it: seen and hidden texels both
            int width = 0, height = 0, channels = 0;
            const std::vector<uint8_t> mask = readImage8((dir / "local" / "lightmap_shadowmask.png").string(), width, height, channels);
            REQUIRE(channels == 4);
            int hidden = 0, seen = 0;
            for (size_t t = 0; t < mask.size(); t += 4) {
                if (mask[t] < 64) ++hidden;
                else if (mask[t] > 192) ++seen;
            }
            CHECK(hidden > 4);
            CHECK(seen > 4);
        }

        job.outputDir = (dir / "split").string();
        const std::string work = (dir / "work").string();
        const SceneUnits units = planSceneUnits(job, 3);
        REQUIRE(units.atlases.size() == 1);
        const BakeReport merged = runUnitsAndMerge(job, work, units);
        CHECK(merged.files == local.files);
        test::checkSameOutputs(dir / "local", dir / "split", local.files);
    }
}

TEST_CASE("A failed unit fails its scene's merge with its error, and the output folder is left alone", "[cluster]") {
    const fs::path root = test::tempDir("cluster-failed-unit");
    fs::remove_all(root);
    const BakeJob job = tinyBoxJob(root);
    const std::string work = (root / "work").string();
    const SceneUnits units = planSceneUnits(job, 2);
    REQUIRE(runVoxelUnit(job, work).ok);
    REQUIRE(runReceiverUnit(job, work, units, 0).ok);

    // Receiver 1 never ran: the merge names it and publishes nothing.
    BakeReport report = mergeScene(job, work, units);
    CHECK_FALSE(report.ok);
    CHECK_THAT(report.error, Catch::Contains("atlas 'lightmap' rows 1 of 2") && Catch::Contains("left no result"));
    CHECK_FALSE(fs::exists(job.outputDir + "/bake.json"));

    // A voxel unit whose scene is missing: its own error, as a local bake gives it.
    BakeJob missing = job;
    missing.scenePath = (root / "missing.gltf").string();
    const UnitRecord failed = runVoxelUnit(missing, (root / "work-missing").string());
    CHECK_FALSE(failed.ok);
    const BakeReport local = runBake(missing);
    CHECK(failed.error == local.error);
    report = mergeScene(missing, (root / "work-missing").string(), units);
    CHECK_FALSE(report.ok);
    CHECK(report.error == local.error);
    // The receivers of a failed voxel unit fail with its error too, and record it.
    const UnitRecord receiver = runReceiverUnit(missing, (root / "work-missing").string(), units, 0);
    CHECK_FALSE(receiver.ok);
    CHECK(receiver.error == local.error);
    REQUIRE(readUnitRecord((root / "work-missing" / "atlas-0-band-0-of-2").string()));
}

TEST_CASE("A damaged voxel state is refused, naming the file", "[cluster]") {
    const fs::path root = test::tempDir("cluster-damaged");
    fs::remove_all(root);
    const BakeJob job = tinyBoxJob(root);
    const std::string work = (root / "work").string();
    REQUIRE(runVoxelUnit(job, work).ok);
    const fs::path state = fs::path(work) / "voxel" / "voxel-state.vxu";
    std::string data = test::fileBytes(state);
    REQUIRE(data.size() > 1000);
    data[data.size() / 2] ^= 0x20;
    std::ofstream(state, std::ios::binary) << data;
    CHECK_THROWS_WITH(readVoxelState(state.string()), Catch::Contains(state.string()) && Catch::Contains("damaged"));
    const UnitRecord receiver = runReceiverUnit(job, work, planSceneUnits(job, 1), 0);
    CHECK_FALSE(receiver.ok);
    CHECK_THAT(receiver.error, Catch::Contains("damaged"));
    std::ofstream(state, std::ios::binary) << data.substr(0, 100);
    CHECK_THROWS_WITH(readVoxelState(state.string()), Catch::Contains(state.string()));
}

TEST_CASE("A voxel state refuses a scene that lies otherwise than the one it was made from", "[cluster]") {
    // The receiver units turn and anchor the scene as the voxel unit did (the state keeps its
    // frame and origin); a scene that moved since gives another origin, and its receivers would
    // read the wrong voxels.
    const fs::path root = test::tempDir("cluster-moved");
    fs::remove_all(root);
    const BakeJob job = tinyBoxJob(root);
    const std::string work = (root / "work").string();
    REQUIRE(runVoxelUnit(job, work).ok);
    const VoxelState state = readVoxelState((fs::path(work) / "voxel" / "voxel-state.vxu").string());
    CHECK_NOTHROW(receiverScene(loadJobScene(job), state));
    Scene moved = loadJobScene(job);
    for (Mesh& mesh : moved.meshes)
        for (vec3& p : mesh.positions) p += vec3(0.25f, 0.0f, 0.0f);
    CHECK_THROWS_WITH(receiverScene(moved, state),
                      Catch::Contains("cornell_box.gltf") && Catch::Contains("lies otherwise") &&
                          Catch::Contains("the scene changed"));
}

TEST_CASE("A unit whose scene changed since submission records why and does not run", "[cluster]") {
    // The plan's fingerprint is not the scene's any more (as after an edit): `voxlight
    // bake-unit` refuses to bake it and leaves the reason in the unit's folder, where
    // --slurm-status and the merge read it.
    const fs::path root = test::tempDir("cluster-changed");
    fs::remove_all(root);
    ClusterPlan plan;
    plan.command.inputs = {test::sourceDir() + "/scenes/cornell_box.gltf"};
    plan.command.output = (root / "out").string();
    plan.command.settings = {{"resolution", "16"}};
    plan.workDir = workFolder(plan.command.output);
    plan.voxlight = std::string(VOXLIGHT_BINARY_DIR) + "/voxlight";
    plan.chdir = root.string();
    ClusterPlan::Scene scene;
    scene.scenePath = plan.command.inputs[0];
    scene.outputDir = plan.command.output;
    scene.fingerprint = "0000000000000000";
    plan.scenes.push_back(scene);
    plan.receiverTasks.assign(1, {});
    plan.receiverJobs.assign(1, "");
    writePlan(plan);
    const std::string command = plan.voxlight + " bake-unit " + plan.workDir + " --unit voxel --scene 0 2>/dev/null";
    CHECK(std::system(command.c_str()) != 0);
    const std::optional<UnitRecord> record = readUnitRecord(sceneWorkFolder(plan.workDir, 0) + "/voxel");
    REQUIRE(record);
    CHECK_FALSE(record->ok);
    CHECK_THAT(record->error, Catch::Contains("cornell_box.gltf") && Catch::Contains("changed since the job was submitted"));
    CHECK_FALSE(fs::exists(sceneWorkFolder(plan.workDir, 0) + "/voxel/voxel-state.vxu"));
}
