// Every scene.glb a bake writes passes the Khronos glTF validator (tools/gltf-validator, the
// validator's npm package kept in the repository; node from tools/install-deps.sh): a Blender export (the Cycles Cornell box), a .glb
// level with its own textures (zdm2, its lights from the bench's job file) and a .gltf whose
// geometry and texture lie in files beside it (Khronos' BoxTextured).
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <memory>

using namespace vl;
using namespace vl::test;
namespace fs = std::filesystem;

namespace {

// The validator's exit status and what it printed.
int validate(const std::string& glb, std::string& output) {
    const std::string command = "node '" + sourceDir() + "/tools/gltf-validator/validate.js' '" + glb + "' 2>&1";
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
    if (!pipe) return -1;
    std::array<char, 4096> buffer;
    while (std::fgets(buffer.data(), int(buffer.size()), pipe.get())) output += buffer.data();
    const int status = pclose(pipe.release());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST_CASE("Every scene.glb the bake writes passes the Khronos glTF validator with no errors", "[bake]") {
    VL_SKIP_WITHOUT_SHARED();
    if (std::system("node --version >/dev/null 2>&1") != 0)
        VL_SKIP("node is not installed (tools/install-deps.sh installs Debian's nodejs)");
    BakeSettings settings;
    settings.quiet = true;
    settings.voxel.resolution = 32;
    settings.outputs.images = false;
    settings.outputs.grids = false;
    settings.lightmap.subsamplesPerAxis = 1;  // what is checked is the file, not the light: zdm2's grown lightmap in 1/16 the time
    std::vector<BakeJob> jobs = readJobFile(sourceDir() + "/tools/bench/zdm2.json", settings, tempDir("glb-validator"));
    REQUIRE(jobs.size() == 1);
    const std::string khronos = sharedDir() + "/scenes/khronos-sample-assets/Models/";
    for (const std::string& scene : std::vector<std::string>{sharedDir() + "/reference/cornell_quad.gltf",
                                                             khronos + "BoxTextured/glTF/BoxTextured.gltf",
                                                             khronos + "NegativeScaleTest/glTF/NegativeScaleTest.gltf",
                                                             khronos + "SimpleInstancing/glTF/SimpleInstancing.gltf"}) {
        BakeJob job;
        job.scenePath = scene;
        job.settings = settings;
        jobs.push_back(job);
    }
    // A sun the engine draws, added by the job: scene.glb gains a KHR_lights_punctual light
    // with its VOXLIGHT_light_bake mode.
    BakeJob sunlit = jobs.back();
    sunlit.scenePath = sourceDir() + "/scenes/two_rooms.gltf";
    Light sun;
    sun.name = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(vec3(0.3f, -1.0f, 0.2f));
    sun.bake = LightBake::Indirect;
    sunlit.addedLights = {sun};
    jobs.push_back(sunlit);
    // The same sun as a shadowmask light: its channel, and each lightmapped material's
    // VOXLIGHT_shadowmask texture.
    sun.bake = LightBake::Shadowmask;
    sunlit.addedLights = {sun};
    jobs.push_back(sunlit);
    for (size_t j = 0; j < jobs.size(); ++j) {
        jobs[j].outputDir = (fs::path(tempDir("glb-validator")) / ("scene" + std::to_string(j))).string();
        fs::remove_all(jobs[j].outputDir);
        const BakeReport report = runBake(jobs[j]);
        INFO(jobs[j].scenePath << ": " << report.error);
        REQUIRE(report.ok);
        const std::string glb = jobs[j].outputDir + "/scene.glb";
        REQUIRE(fs::exists(glb));
        std::string output;
        const int status = validate(glb, output);
        INFO(output);
        CHECK(status == 0);
        CHECK_THAT(output, Catch::Contains(": 0 errors"));
    }
    // The zdm2 job adds a camera (its image's view): scene.glb carries it as a glTF camera
    // where the job put it, looking at the job's target, so a viewer can show that view.
    const Scene zdm2 = loadGltf(jobs[0].outputDir + "/scene.glb");
    REQUIRE(zdm2.cameras.size() == 1);
    const Camera& start = zdm2.cameras[0];
    CHECK(start.name == "start");
    const vec3 position = vec3(zdm2.origin) + start.position;
    CHECK(glm::length(position - vec3(11.80f, 1.50f, 7.54f)) < 1e-4f);
    const vec3 toTarget = glm::normalize(vec3(11.95f, -1.33f, -7.53f) - vec3(11.80f, 1.50f, 7.54f));
    CHECK(glm::dot(start.forward, toTarget) > 1.0f - 1e-6f);
    CHECK(start.yfov == Approx(1.0f));
}
