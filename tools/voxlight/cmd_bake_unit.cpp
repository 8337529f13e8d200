// voxlight bake-unit WORK --unit voxel|receiver|merge [--scene K] [--index I]: one unit of a
// cluster bake (cluster/units.h), as the batch scripts `voxlight bake --slurm` writes run it.
// Not for people: its empty group keeps it out of `voxlight --help`.
#include "tools/voxlight/commands.h"

#include "cluster/slurm.h"
#include "cluster/units.h"
#include "core/error.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>

namespace vl::cli {
namespace {

struct UnitOptions {
    std::string work;
    std::string unit;
    int scene = -1;
    int index = -1;
};

void runUnitCommand(const UnitOptions& options) {
    // Slurm gives a unit --cpus-per-task CPUs; without an affinity mask TBB would take them all.
    std::optional<tbb::global_control> threads;
    if (const char* cpus = std::getenv("SLURM_CPUS_PER_TASK"); cpus && std::atoi(cpus) > 0)
        threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(std::atoi(cpus)));
    const cluster::ClusterPlan plan = cluster::readPlan(options.work);
    const std::vector<BakeJob> jobs = planJobs(plan.command, true);
    if (jobs.size() != plan.scenes.size())
        throw InputError(options.work + ": the job now plans " + std::to_string(jobs.size()) + " scenes, " +
                         std::to_string(plan.scenes.size()) + " when it was submitted: submit it again");
    if (options.unit == "merge") {
        std::vector<BakeReport> reports;
        std::vector<double> seconds;
        for (size_t k = 0; k < jobs.size(); ++k) {
            const auto start = std::chrono::steady_clock::now();
            reports.push_back(cluster::mergeScene(jobs[k], cluster::sceneWorkFolder(plan.workDir, k), plan.scenes[k].units));
            seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            if (!reports.back().ok) std::fprintf(stderr, "error: %s\n", reports.back().error.c_str());
        }
        printBakeSummary(reports);
        cluster::writeSummary(plan.workDir, reports, seconds);
        for (const BakeReport& r : reports)
            if (!r.ok) throw Error(std::to_string(reports.size()) + " scene(s) merged, at least one failed");
        return;
    }
    if (options.scene < 0 || size_t(options.scene) >= jobs.size())
        throw SettingsError("bake-unit: --scene " + std::to_string(options.scene) + " of a job with " +
                            std::to_string(jobs.size()) + " scenes");
    const size_t k = size_t(options.scene);
    const BakeJob& job = jobs[k];
    if (cluster::fingerprint(job, [&] {
            std::vector<std::string> files;
            for (const std::string& input : plan.command.inputs)
                if (std::filesystem::path(input).extension() == ".json") files.push_back(input);
            return files;
        }()) != plan.scenes[k].fingerprint)
        throw InputError(job.scenePath + ": the scene, its files, its job file or its settings changed since the job "
                         "was submitted: submit it again");
    const std::string work = cluster::sceneWorkFolder(plan.workDir, k);
    cluster::UnitRecord record;
    if (options.unit == "voxel")
        record = cluster::runVoxelUnit(job, work);
    else if (options.unit == "receiver")
        record = cluster::runReceiverUnit(job, work, plan.scenes[k].units, options.index);
    else
        throw SettingsError("bake-unit: --unit must be voxel, receiver or merge, not '" + options.unit + "'");
    if (!record.ok) throw Error(record.error);
    std::fprintf(stderr, "%s: %s unit done on %s in %.2f s\n", job.scenePath.c_str(), options.unit.c_str(),
                 record.host.c_str(), record.seconds);
}

}  // namespace

void addBakeUnitCommand(CLI::App& app) {
    auto options = std::make_shared<UnitOptions>();
    auto* cmd = app.add_subcommand("bake-unit", "the units of voxlight bake --slurm");
    cmd->group("");  // hidden from voxlight --help: the batch scripts call it, not people
    cmd->add_option("work", options->work, "the cluster bake's work folder")->required();
    cmd->add_option("--unit", options->unit, "voxel, receiver or merge")->required();
    cmd->add_option("--scene", options->scene, "the scene's index in the job");
    cmd->add_option("--index", options->index, "the receiver unit's index in its scene");
    cmd->callback([options] { runUnitCommand(*options); });
}

}  // namespace vl::cli
