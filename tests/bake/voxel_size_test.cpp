// The voxel size a bake chooses from its scene (bake/voxel_size.h): the free paths against
// Cauchy's mean chord, the rules, each light's clearance against analytic distances, the
// user's settings winning, and what the clearance rule is for: a light close to a ceiling
// keeps its bounce light.
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/voxel_size.h"
#include "quad_scene.h"

#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace vl;
using namespace vl::test;
namespace fs = std::filesystem;

namespace {

// A white room [0, size.x] × [0, size.y] × [0, size.z] with one point light.
Scene roomWithLight(vec3 size, vec3 light) {
    Scene scene;
    scene.sourcePath = "room (test)";
    const int white = addLambert(scene, vec3(0.6f));
    addRoom(scene, "room/", white, vec3(0.0f), size);
    scene.lights.push_back(pointLightAt(light, 1.0f));
    return scene;
}

}  // namespace

TEST_CASE("The free paths between a closed room's surfaces average 4V/S, Cauchy's mean chord", "[bake]") {
    // Cosine-distributed rays from points uniform over a convex room's inside have the mean
    // chord 4V/S: 2/3 of a cube's side. 4096 rays: the mean's own spread is about 0.8%.
    struct Case {
        vec3 size;
    };
    for (const Case& c : {Case{vec3(1.0f)}, Case{vec3(2.0f, 1.0f, 0.8f)}, Case{vec3(3.0f, 0.5f, 0.5f)}}) {
        Scene scene;
        addRoom(scene, "room/", addLambert(scene, vec3(0.6f)), vec3(0.0f), c.size);
        const double volume = double(c.size.x) * c.size.y * c.size.z;
        const double area = 2.0 * (double(c.size.x) * c.size.y + double(c.size.y) * c.size.z + double(c.size.z) * c.size.x);
        const FreePaths paths = surfaceFreePaths(scene);
        INFO("room " << c.size.x << " × " << c.size.y << " × " << c.size.z << ": mean " << paths.mean << ", 4V/S "
                     << 4.0 * volume / area);
        CHECK(paths.rays == 4096);
        CHECK(paths.hits == paths.rays);  // closed: nothing leaves
        CHECK(paths.singleSidedBacks == 0);
        CHECK(paths.mean == Approx(4.0 * volume / area).epsilon(0.025));
        CHECK(paths.median < paths.mean * 1.2);
    }
}

TEST_CASE("The default voxel size puts kVoxelsPerFreePath voxels along the mean free path", "[bake]") {
    // The light is 0.4 m from every wall: farther than a voxel, so the free path alone decides.
    const Scene scene = roomWithLight(vec3(2.0f, 1.0f, 0.8f), vec3(1.0f, 0.5f, 0.4f));
    const VoxelSizeChoice choice = chooseVoxelSize(scene, quietSettings());
    // The count along the longest side (2 m) is the 8k − 1 nearest 2 m / (mean / 31): the
    // gather cells' 4 voxels fit twice between the walls' outermost voxels.
    const double wanted = 2.0 / (choice.freePaths.mean / kVoxelsPerFreePath);
    const int count = choice.voxelsAlongLongest;
    CHECK((count + 1) % 8 == 0);
    CHECK(std::abs(count - wanted) <= 4.0);
    CHECK(choice.voxelSize == Approx(2.0 / count).epsilon(1e-9));
    CHECK_THAT(choice.setBy, Catch::Contains("the mean free path between its surfaces"));
    CHECK(choice.warnings.empty());
}

TEST_CASE("A room turned at an angle to the world axes gets the voxel size of the room unturned", "[bake]") {
    const glm::mat3 turn = glm::mat3(glm::rotate(glm::mat4(1.0f), 0.5f, glm::normalize(vec3(1.0f, 2.0f, 0.5f))));
    const auto turned = [&](Scene scene) {
        for (Mesh& mesh : scene.meshes) {
            for (vec3& p : mesh.positions) p = turn * p;
            for (vec3& n : mesh.normals) n = turn * n;
        }
        for (Light& light : scene.lights) light.position = turn * light.position;
        return scene;
    };
    SECTION("closed: the free paths do not turn") {
        const Scene scene = roomWithLight(vec3(2.0f, 1.0f, 0.8f), vec3(1.0f, 0.5f, 0.4f));
        const VoxelSizeChoice unturnedChoice = chooseVoxelSize(scene, quietSettings());
        const double unturned = unturnedChoice.voxelSize;
        const VoxelSizeChoice choice = chooseVoxelSize(turned(scene), quietSettings());
        // The rays' directions about each point turn with the room only up to its basis: the
        // same mean within the probe's spread, and the count along the room's own longest side
        // (in its own frame) the same 8k − 1 or the next.
        CHECK(choice.freePaths.mean == Approx(unturnedChoice.freePaths.mean).epsilon(0.02));
        CHECK(std::abs(2.0 / choice.voxelSize - 2.0 / unturned) <= 8.0 + 1e-6);
        CHECK_THAT(choice.setBy, Catch::Contains("the mean free path") && Catch::Contains("in its own frame"));
    }
    SECTION("open: the size rule counts along the scene's own longest side") {
        // A 2 m × 1 m floor with a wall 0.2 m high along one long side: most rays leave.
        Scene scene;
        const int white = addLambert(scene, vec3(0.6f));
        addQuad(scene, "floor", white, vec3(0.0f), vec3(0.0f, 0.0f, 1.0f), vec3(2.0f, 0.0f, 1.0f), vec3(2.0f, 0.0f, 0.0f));
        addQuad(scene, "wall", white, vec3(0.0f), vec3(2.0f, 0.0f, 0.0f), vec3(2.0f, 0.2f, 0.0f), vec3(0.0f, 0.2f, 0.0f));
        const VoxelSizeChoice choice = chooseVoxelSize(turned(scene), quietSettings());
        const vec3 bounds = turned(scene).bounds().extent();
        INFO("turned bounds " << bounds.x << " × " << bounds.y << " × " << bounds.z << "; " << choice.setBy);
        REQUIRE(maxComponent(bounds) > 2.1f);
        CHECK(2 * choice.freePaths.hits < choice.freePaths.rays);
        CHECK(choice.voxelSize <= 2.0 / kSceneVoxels * (1.0 + 1e-6));
        CHECK(choice.voxelSize > 2.0 / kSceneVoxels * (1.0 - 2.0 / choice.voxelsAlongLongest));
        CHECK_THAT(choice.setBy, Catch::Contains("in its own frame") && Catch::Contains("an open scene"));
    }
}

TEST_CASE("Surfaces a few millimetres apart cap the free-path rule, with a warning", "[bake]") {
    // Two 1 m plates facing each other 2 mm apart: a mean free path of millimetres would ask
    // for thousands of voxels along the plates.
    Scene scene;
    scene.sourcePath = "plates (test)";
    const int white = addLambert(scene, vec3(0.6f));
    addQuad(scene, "lower", white, vec3(0.0f), vec3(0.0f, 0.0f, 1.0f), vec3(1.0f, 0.0f, 1.0f), vec3(1.0f, 0.0f, 0.0f));
    addQuad(scene, "upper", white, vec3(0.0f, 0.002f, 0.0f), vec3(1.0f, 0.002f, 0.0f), vec3(1.0f, 0.002f, 1.0f),
            vec3(0.0f, 0.002f, 1.0f));
    const VoxelSizeChoice choice = chooseVoxelSize(scene, quietSettings());
    INFO(choice.setBy);
    CHECK(choice.freePaths.mean < 0.01);
    CHECK(choice.voxelsAlongLongest <= kMaxFreePathVoxels);
    REQUIRE(choice.warnings.size() == 1);
    CHECK_THAT(choice.warnings[0], Catch::Contains("plates (test)") && Catch::Contains("free paths") &&
                                       Catch::Contains("voxel-size"));
}

TEST_CASE("A light's clearance is its distance to the nearest triangle", "[bake]") {
    // Outside a unit room: nearest is a wall's inside (distance to the plane), an edge (two
    // coordinates out) or a corner (all three out), each an analytic distance.
    struct Case {
        vec3 light;
        double distance;
    };
    for (const Case& c : {Case{vec3(0.5f, 0.25f, 0.5f), 0.25}, Case{vec3(2.0f, 0.5f, 0.5f), 1.0},
                          Case{vec3(2.0f, 2.0f, 0.5f), std::sqrt(2.0)}, Case{vec3(2.0f, 2.0f, 2.0f), std::sqrt(3.0)},
                          Case{vec3(0.3f, 0.999f, 0.6f), 0.001}}) {
        INFO("light at " << c.light.x << ", " << c.light.y << ", " << c.light.z);
        const VoxelSizeChoice choice = chooseVoxelSize(roomWithLight(vec3(1.0f), c.light), quietSettings());
        REQUIRE(choice.clearances.size() == 1);
        CHECK(choice.clearances[0].light == "lamp");
        CHECK(choice.clearances[0].metres == Approx(c.distance).epsilon(1e-4));  // float positions
    }
}

TEST_CASE("A light close to a surface makes the voxels fine enough to clear it by one voxel", "[bake]") {
    // 5 mm under the ceiling of a 1 m room: 200 voxels along the side would put the light
    // exactly one voxel off; the next odd count is 201.
    const Scene scene = roomWithLight(vec3(1.0f), vec3(0.37f, 0.995f, 0.41f));
    const VoxelSizeChoice choice = chooseVoxelSize(scene, quietSettings());
    CHECK(choice.voxelsAlongLongest == 201);
    CHECK(choice.voxelSize == Approx(1.0 / 201.0).epsilon(1e-5));
    CHECK(choice.voxelSize <= choice.clearances[0].metres);
    CHECK_THAT(choice.setBy, Catch::Contains("light 'lamp'") && Catch::Contains("5 mm"));
    CHECK(choice.warnings.empty());

    SECTION("but at most kMaxRefinement times finer than the free-path rule, with a warning") {
        const int rule = chooseVoxelSize(roomWithLight(vec3(1.0f), vec3(0.5f)), quietSettings()).voxelsAlongLongest;
        const Scene onFloor = roomWithLight(vec3(1.0f), vec3(0.5f, 0.0f, 0.5f));
        const VoxelSizeChoice capped = chooseVoxelSize(onFloor, quietSettings());
        CHECK(capped.voxelsAlongLongest == kMaxRefinement * (rule + 1) - 1);
        CHECK_THAT(capped.setBy, Catch::Contains("lies on a surface"));
        REQUIRE(capped.warnings.size() == 1);
        CHECK_THAT(capped.warnings[0], Catch::Contains("room (test)") && Catch::Contains("light 'lamp'") &&
                                           Catch::Contains("less than one voxel"));
    }
}

TEST_CASE("A voxel size or resolution the user gives wins over the scene's", "[bake]") {
    const Scene scene = roomWithLight(vec3(1.0f), vec3(0.37f, 0.995f, 0.41f));
    BakeSettings settings = quietSettings();
    settings.voxel.resolution = 31;
    const VoxelSizeChoice byResolution = chooseVoxelSize(scene, settings);
    CHECK(byResolution.voxelSize == Approx(1.0 / 31.0).epsilon(1e-6));
    CHECK(byResolution.setBy == "the resolution setting");
    // The light then sits inside the ceiling's voxel layer, and the user is told.
    REQUIRE(byResolution.warnings.size() == 1);
    CHECK_THAT(byResolution.warnings[0], Catch::Contains("light 'lamp' is 5 mm from the nearest surface"));

    settings.voxel.voxelSize = 0.002;
    const VoxelSizeChoice bySize = chooseVoxelSize(scene, settings);
    CHECK(bySize.voxelSize == 0.002);
    CHECK(bySize.setBy == "the voxel-size setting");
    CHECK(bySize.warnings.empty());
}

TEST_CASE("The voxel size does not depend on where the scene sits or how big it is", "[bake]") {
    const Scene scene = roomWithLight(vec3(1.0f), vec3(0.37f, 0.995f, 0.41f));
    const VoxelSizeChoice original = chooseVoxelSize(scene, quietSettings());
    Scene moved = scene, scaled = scene;
    for (Mesh& mesh : moved.meshes)
        for (vec3& p : mesh.positions) p += vec3(100.0f, -50.0f, 20.0f);
    moved.lights[0].position += vec3(100.0f, -50.0f, 20.0f);
    for (Mesh& mesh : scaled.meshes)
        for (vec3& p : mesh.positions) p *= 1000.0f;
    scaled.lights[0].position *= 1000.0f;
    CHECK(chooseVoxelSize(moved, quietSettings()).voxelsAlongLongest == original.voxelsAlongLongest);
    const VoxelSizeChoice big = chooseVoxelSize(scaled, quietSettings());
    CHECK(big.voxelsAlongLongest == original.voxelsAlongLongest);
    CHECK(big.voxelSize == Approx(1000.0 * original.voxelSize).epsilon(1e-5));
}

TEST_CASE("Voxels chosen around a light 5 mm under a ceiling keep the bounce light it gives", "[bake]") {
    // The first bounce alone (no voxel bounces): the room's mean indirect lightmap value. The
    // reference is 255 voxels (1.3 voxels of clearance), which the coarse grid's own bias puts
    // within 2% of the finest grids measured. By stepping through the voxels (the paper's
    // visibility) at 63 voxels the light lies a third of a voxel under the ceiling, inside its
    // voxel layer, and the ceiling's light is lost to the bounce (measured −21% of the room's
    // first bounce); the chosen size clears it by a voxel. By rays from the voxels' surface
    // points (the default) the ceiling's points see the light at any size.
    const Scene scene = roomWithLight(vec3(1.0f), vec3(0.37f, 0.995f, 0.41f));
    auto firstBounce = [&](int resolution, VoxelVisibility visibility) {
        BakeSettings settings = quietSettings();
        settings.voxel.resolution = resolution;
        settings.lighting.visibilityBy = visibility;
        settings.gather.bounces = 0;
        settings.gather.bounceTail = false;
        settings.lightmap.atlasPerMesh = true;
        settings.lightmap.width = settings.lightmap.height = 16;
        Diagnostics diagnostics(false, false);
        const BakeResult result = bake(scene, settings, diagnostics);
        double sum = 0.0;
        for (const BakedLightmap& l : result.lightmaps)
            for (int y = 0; y < l.mask.height; ++y)
                for (int x = 0; x < l.mask.width; ++x)
                    if (l.mask.at(x, y) > 0.5f) sum += l.indirect.at(x, y, 0);
        return sum;
    };
    for (const VoxelVisibility visibility : {VoxelVisibility::Stepping, VoxelVisibility::Rays}) {
        const bool stepping = visibility == VoxelVisibility::Stepping;
        const double chosen = firstBounce(0, visibility), coarse = firstBounce(63, visibility),
                     reference = firstBounce(255, visibility);
        INFO((stepping ? "stepping" : "rays") << ": first bounce: chosen " << chosen << ", 63 voxels " << coarse
                                              << ", 255 voxels " << reference);
        CHECK(chosen == Approx(reference).epsilon(0.04));
        if (stepping)
            CHECK(coarse < 0.85 * reference);
        else
            CHECK(coarse == Approx(reference).epsilon(0.04));
    }
}

TEST_CASE("bake.json says what set the voxel size and how far each light is from a surface", "[bake]") {
    const fs::path out = fs::temp_directory_path() / "voxlight_voxel_size_test";
    fs::remove_all(out);
    BakeJob job;
    job.scenePath = std::string(VOXLIGHT_SOURCE_DIR) + "/scenes/cornell_box_point.gltf";
    job.outputDir = out.string();
    job.settings = quietSettings();
    job.settings.lightmap.width = job.settings.lightmap.height = 32;
    const BakeReport report = runBake(job);
    INFO(report.error);
    REQUIRE(report.ok);
    std::ifstream file(out / "bake.json");
    const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    CHECK_THAT(text, Catch::Contains("\"voxel_size_set_by\": \"the mean free path between its surfaces (" +
                                         std::to_string(int(kVoxelsPerFreePath)) + " voxels along") &&
                         Catch::Contains("\"voxels_along_longest_side\": ") && Catch::Contains("\"free_paths\"") &&
                         Catch::Contains("\"light_clearances\"") && Catch::Contains("\"settings\": \"resolution=auto"));
    fs::remove_all(out);
}
