// voxlight bake-unit WORK --unit voxel|receiver|merge [--scene K] [--index I]: one unit of a
// cluster bake (cluster/units.h), as the batch scripts `voxlight bake --slurm` writes run it.
// Not for people: its empty group keeps it out of `voxlight --help`.
#include "tools/voxlight/commands.h"

#include "cluster/slurm.h"
#include "cluster/units.h"
#include "core/error.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
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

std::vector<std::string> jobFilesOf(const cluster::ClusterPlan& plan) {
    std::vector<std::string> files;
    for (const std::string& input : plan.command.inputs)
        if (std::filesystem::path(input).extension() == ".json") files.push_back(input);
    return files;
}

// Why scene k of the plan must not be baked or merged now: it failed to plan, or its job,
// files or settings changed since submission (empty: nothing stops it).
std::string sceneRefusal(const cluster::ClusterPlan& plan, const std::vector<BakeJob>& jobs, size_t k) {
    const cluster::ClusterPlan::Scene& planned = plan.scenes[k];
    if (!planned.planError.empty()) return planned.planError;
    if (jobs[k].scenePath != planned.scenePath || jobs[k].outputDir != planned.outputDir ||
        cluster::fingerprint(jobs[k], jobFilesOf(plan)) != planned.fingerprint)
        return jobs[k].scenePath + ": the scene, its files, its job file or its settings changed since the job was "
                                   "submitted: submit it again";
    return "";
}

void mergeAll(const cluster::ClusterPlan& plan, const std::vector<BakeJob>& jobs) {
    std::vector<BakeReport> reports;
    std::vector<double> seconds;
    for (size_t k = 0; k < jobs.size(); ++k) {
        const auto start = std::chrono::steady_clock::now();
        const std::string refusal = sceneRefusal(plan, jobs, k);
        if (refusal.empty()) {
            reports.push_back(cluster::mergeScene(jobs[k], cluster::sceneWorkFolder(plan.workDir, k), plan.scenes[k].units));
        } else {
            BakeReport failed;
            failed.scenePath = jobs[k].scenePath;
            failed.outputDir = jobs[k].outputDir;
            failed.error = refusal;
            reports.push_back(failed);
        }
        seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        if (!reports.back().ok) std::fprintf(stderr, "error: %s\n", reports.back().error.c_str());
    }
    printBakeSummary(reports);
    cluster::writeSummary(plan.workDir, reports, seconds);
    for (const BakeReport& r : reports)
        if (!r.ok) throw Error(std::to_string(reports.size()) + " scene(s) merged, at least one failed");
}

void runUnitCommand(const UnitOptions& options) {
    // Slurm gives a unit --cpus-per-task CPUs; without an affinity mask TBB would take them all.
    std::optional<tbb::global_control> threads;
    if (const char* cpus = std::getenv("SLURM_CPUS_PER_TASK"); cpus && std::atoi(cpus) > 0)
        threads.emplace(tbb::global_control::max_allowed_parallelism, size_t(std::atoi(cpus)));
    if (options.unit != "voxel" && options.unit != "receiver" && options.unit != "merge")
        throw SettingsError("bake-unit: --unit must be voxel, receiver or merge, not '" + options.unit + "'");
    // Whatever stops a voxel or receiver unit before it runs is recorded in its folder, where
    // --slurm-status and the merge read why; without a plan the folder is not known.
    const cluster::ClusterPlan plan = cluster::readPlan(options.work);
    if (plan.scenes.empty()) throw InputError(options.work + ": its plan holds no scene");
    const bool isMerge = options.unit == "merge";
    if (!isMerge && (options.scene < 0 || size_t(options.scene) >= plan.scenes.size()))
        throw SettingsError("bake-unit: --scene " + std::to_string(options.scene) + " of a job with " +
                            std::to_string(plan.scenes.size()) + " scenes");
    const size_t k = size_t(std::max(options.scene, 0));
    const std::string work = cluster::sceneWorkFolder(plan.workDir, k);
    const cluster::SceneUnits& units = plan.scenes[isMerge ? 0 : k].units;
    const std::string folder = options.unit == "voxel" ? cluster::kVoxelFolder
                               : options.index >= 0 && options.index < units.receiverCount()
                                   ? cluster::receiverFolder(units, options.index)
                                   : "receiver-" + std::to_string(options.index);
    std::vector<BakeJob> jobs;
    try {
        jobs = planJobs(plan.command, true);
        if (jobs.size() != plan.scenes.size())
            throw InputError(options.work + ": the job now plans " + std::to_string(jobs.size()) + " scenes, " +
                             std::to_string(plan.scenes.size()) + " when it was submitted: submit it again");
        if (!isMerge) {
            const std::string refusal = sceneRefusal(plan, jobs, k);
            if (!refusal.empty()) throw InputError(refusal);
        }
    } catch (const std::exception& e) {
        if (!isMerge) cluster::recordUnitFailure(work, folder, e.what());
        throw;
    }
    if (isMerge) return mergeAll(plan, jobs);
    const BakeJob& job = jobs[k];
    const cluster::UnitRecord record = options.unit == "voxel"
                                           ? cluster::runVoxelUnit(job, work)
                                           : cluster::runReceiverUnit(job, work, units, options.index);
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
