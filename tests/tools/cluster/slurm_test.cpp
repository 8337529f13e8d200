// `voxlight bake --slurm` on a real one-node Slurm cluster (tools/cluster/test-cluster.sh: munge,
// slurmctld and slurmd started as root under a temporary folder, stopped afterwards): the
// three-scene job against the local bake, byte for byte; a second submission runs only what
// is not done; a failed voxel unit is reported per unit and by the merge. Skips, saying why,
// where Slurm is not installed (tools/install-deps.sh installs it) or the test is not root.
#include "three_scenes.h"
#include "support/skip.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

const std::string kVoxlight = std::string(VOXLIGHT_BINARY_DIR) + "/voxlight";

struct Run {
    int status = -1;
    std::string output;  // stdout and stderr
};

Run run(const std::string& command) {
    Run r;
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return r;
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) r.output.append(buffer, n);
    const int status = ::pclose(pipe);
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

bool have(const std::string& program) { return run("command -v " + program).status == 0; }

// A cluster for the test's lifetime.
class TestCluster {
public:
    explicit TestCluster(const fs::path& dir) : dir_(dir) {
        const Run started = run(vl::test::sourceDir() + "/tools/cluster/test-cluster.sh start " + dir.string());
        INFO(started.output);
        REQUIRE(started.status == 0);
        const std::string key = "export SLURM_CONF=";
        const size_t at = started.output.find(key);
        REQUIRE(at != std::string::npos);
        const std::string conf = started.output.substr(at + key.size(), started.output.find('\n', at) - at - key.size());
        ::setenv("SLURM_CONF", conf.c_str(), 1);
    }
    ~TestCluster() { run(vl::test::sourceDir() + "/tools/cluster/test-cluster.sh stop " + dir_.string()); }

private:
    fs::path dir_;
};

std::vector<std::string> filesOf(const fs::path& folder) {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(folder))
        if (entry.is_regular_file()) files.push_back(entry.path().filename().string());
    std::sort(files.begin(), files.end());
    return files;
}

}  // namespace

TEST_CASE("A three-scene job baked on a one-node Slurm cluster is the local bake's bytes", "[cluster]") {
    for (const char* program : {"sbatch", "squeue", "scontrol", "slurmctld", "slurmd", "munged"})
        if (!have(program)) VL_SKIP(program << " is not installed (tools/install-deps.sh installs slurm-wlm and munge)");
    if (::geteuid() != 0) VL_SKIP("the test cluster's slurmd runs jobs as their user and must be started as root");
    const fs::path root = vl::test::tempDir("cluster-slurm");
    run(vl::test::sourceDir() + "/tools/cluster/test-cluster.sh stop " + (root / "cluster").string());
    fs::remove_all(root);
    fs::create_directories(root);
    const fs::path job = vl::test::writeThreeSceneJob(root);
    const TestCluster cluster(root / "cluster");

    const std::string submit = kVoxlight + " bake " + job.string() + " -o " + (root / "slurm").string() +
                               " --slurm --lightmap-bands 2 --slurm-wait";
    const Run first = run(submit);
    INFO(first.output);
    REQUIRE(first.status == 0);
    CHECK_THAT(first.output, Catch::Contains("submitted 3 voxel unit(s), 12 receiver unit(s)"));
    CHECK_THAT(first.output, Catch::Contains("merge: done: 3 scene(s) published, 0 failed"));
    const Run local = run(kVoxlight + " bake " + job.string() + " -o " + (root / "local").string() + " -q");
    INFO(local.output);
    REQUIRE(local.status == 0);
    size_t compared = 0;
    for (const char* scene : {"cornell_box_point", "window_room", "classroom"}) {
        const std::vector<std::string> files = filesOf(root / "local" / scene);
        CHECK(filesOf(root / "slurm" / scene) == files);
        compared += vl::test::checkSameOutputs(root / "local" / scene, root / "slurm" / scene, files);
    }
    CHECK(compared >= 3 * 12);

    // Every unit is done: a second submission runs the merge alone, which publishes again.
    const Run second = run(submit);
    INFO(second.output);
    CHECK(second.status == 0);
    CHECK_THAT(second.output, Catch::Contains("submitted 0 voxel unit(s), 0 receiver unit(s)"));
    const Run status = run(kVoxlight + " bake --slurm-status " + (root / "slurm").string());
    INFO(status.output);
    CHECK(status.status == 0);
    size_t done = 0;
    for (size_t at = 0; (at = status.output.find(": done on ", at)) != std::string::npos; ++at) ++done;
    CHECK(done == 15);  // 3 voxel units; 2 bands per atlas (2 + 1 + 1 atlases); cameras 1 + 1 + 2

    // Scenes that fail in their voxel units under --strict (a black scene; the classroom's
    // generated charts under 2 × 2 texels in the 64² atlas, which used to grow for them and
    // warn of that), and one that is missing (it fails to plan, so
    // none of its units runs): their receivers never run, the merge publishes the other scene
    // and names them, and the command fails.
    nlohmann::json j = nlohmann::json::parse(vl::test::fileBytes(job));
    j["scenes"][1].erase("sky");
    j["scenes"].push_back({{"path", (root / "missing.gltf").string()}});
    const fs::path strictJob = root / "strict.json";
    std::ofstream(strictJob) << j.dump(2);
    const Run failed = run(kVoxlight + " bake " + strictJob.string() + " -o " + (root / "strict").string() +
                           " --slurm --slurm-wait --strict --lightmap-bands 1");
    INFO(failed.output);
    CHECK(failed.status != 0);
    CHECK_THAT(failed.output, Catch::Contains("voxel: failed: ") && Catch::Contains("window_room.gltf: the scene has no lights"));
    CHECK_THAT(failed.output, Catch::Contains("not run: its voxel unit failed"));
    CHECK_THAT(failed.output, Catch::Contains("classroom.gltf: ") &&
                                  Catch::Contains("charts are under 2 x 2 texels"));
    CHECK_THAT(failed.output, Catch::Contains("planning failed: ") && Catch::Contains("missing.gltf"));
    CHECK_THAT(failed.output, Catch::Contains("merge: done: 1 scene(s) published, 3 failed"));
    CHECK(fs::exists(root / "strict" / "cornell_box_point" / "bake.json"));
    CHECK_FALSE(fs::exists(root / "strict" / "window_room" / "bake.json"));
}
