// voxlight bake [scene.gltf | job.json …]: the batch bake. Each scene bakes into
// output/<name>/ (or -o); a scene that fails is reported and the batch goes on; the exit
// code is non-zero when any scene failed. With --slurm the job goes to a Slurm cluster as
// units (cluster/slurm.h) and the command returns once it is submitted.
#include "tools/voxlight/commands.h"

#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "cluster/slurm.h"
#include "core/error.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <unistd.h>
#include <utility>

namespace vl::cli {
namespace {

namespace fs = std::filesystem;

bool isJobFile(const std::string& path) { return fs::path(path).extension() == ".json"; }

struct BakeOptions {
    cluster::PlannedCommand command;
    bool quiet = false;
    bool slurm = false;
    bool wait = false;
    std::string status;  // --slurm-status <output root>
    cluster::SlurmOptions slurmOptions;
};

// The command as the units see it: inputs and the output root absolute (they run elsewhere),
// the default scene named.
cluster::PlannedCommand absoluteCommand(cluster::PlannedCommand command) {
    if (command.inputs.empty()) command.inputs.push_back(defaultScenePath());
    for (std::string& input : command.inputs) input = fs::absolute(input).lexically_normal().string();
    // No -o: the scenes go where a local bake puts them (output/<name>, relative to the folder
    // the units run in, which is this one).
    if (!command.output.empty()) command.output = fs::absolute(command.output).lexically_normal().string();
    return command;
}

void submitToSlurm(const BakeOptions& options) {
    cluster::ClusterPlan plan;
    plan.command = absoluteCommand(options.command);
    plan.workDir = cluster::workFolder(plan.command.output.empty() ? "output" : plan.command.output);
    plan.voxlight = fs::read_symlink("/proc/self/exe").string();
    plan.chdir = fs::current_path().string();
    std::vector<std::string> jobFiles;
    for (const std::string& input : plan.command.inputs)
        if (isJobFile(input)) jobFiles.push_back(input);
    for (const BakeJob& job : planJobs(plan.command, true)) {
        cluster::ClusterPlan::Scene scene;
        scene.scenePath = job.scenePath;
        scene.outputDir = job.outputDir;
        scene.fingerprint = cluster::fingerprint(job, jobFiles);
        try {
            scene.units = cluster::planSceneUnits(job, options.slurmOptions.bands);
        } catch (const std::exception& e) {
            // A scene that does not plan (its file is missing or broken) runs no unit; the merge
            // reports it, with the error a local bake gives, and the other scenes go on.
            scene.planError = e.what();
            std::fprintf(stderr, "error: %s\n", e.what());
        }
        plan.scenes.push_back(scene);
    }
    for (const std::string& line : cluster::submit(plan, options.slurmOptions)) std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    if (!options.wait || options.slurmOptions.dryRun) return;
    cluster::waitForMerge(plan);
    for (const std::string& line : cluster::slurmStatus(fs::path(plan.workDir).parent_path().string()))
        std::printf("%s\n", line.c_str());
    const nlohmann::json summary = cluster::readSummary(plan.workDir);
    if (summary.is_null()) throw Error("the merge job ended without a summary: see " + plan.workDir + "/logs/merge.out");
    for (const auto& scene : summary.at("scenes"))
        if (!scene.at("ok").get<bool>()) throw Error("at least one scene of the cluster bake failed");
}

}  // namespace

std::vector<BakeJob> planJobs(const cluster::PlannedCommand& command, bool quiet) {
    BakeSettings settings;
    for (const auto& [name, value] : command.settings) applySetting(bakeSettingsTable(), settings, name, value);
    settings.strict = command.strict;
    settings.quiet = quiet;
    validateBakeSettings(settings);

    std::vector<std::string> inputs = command.inputs;
    if (inputs.empty()) inputs.push_back(defaultScenePath());
    const bool single = inputs.size() == 1 && !isJobFile(inputs[0]);
    std::vector<BakeJob> jobs;
    for (const std::string& input : inputs) {
        if (isJobFile(input)) {
            for (BakeJob& job : readJobFile(input, settings, "output", command.settings, command.output)) {
                job.settings.strict = job.settings.strict || command.strict;
                job.settings.quiet = quiet;
                jobs.push_back(std::move(job));
            }
            continue;
        }
        BakeJob job;
        job.scenePath = input;
        job.settings = settings;
        const std::string name = sceneOutputName(input);
        // -o names the folder itself for one scene, the root folder for several.
        job.outputDir = command.output.empty() ? "output/" + name
                        : single             ? command.output
                                             : command.output + "/" + name;
        jobs.push_back(std::move(job));
    }
    return jobs;
}

void addBakeCommand(CLI::App& app) {
    auto options = std::make_shared<BakeOptions>();
    auto* cmd = app.add_subcommand("bake", "bake lightmaps, images and grids for glTF scenes or job files "
                                           "(default: the Cornell box into output/cornell_box/)");
    cmd->add_option("inputs", options->command.inputs, "scene files (.gltf, .glb) and job files (.json)");
    cmd->add_option("-o,--output", options->command.output,
                    "output folder (one scene) or root folder (several); default output/<scene name>");
    cmd->add_flag("--strict", options->command.strict, "treat every warning as an error");
    cmd->add_flag("-q,--quiet", options->quiet, "no progress on stderr");
    cmd->add_flag("--slurm", options->slurm,
                  "submit the bake to a Slurm cluster as units (voxel stages, lightmap bands, cameras, merge) and "
                  "return; the output folder must be on a file system every node sees at the same path")
        ->group("Cluster");
    cmd->add_option("--partition", options->slurmOptions.partition, "Slurm partition for every unit")->group("Cluster");
    cmd->add_option("--time", options->slurmOptions.time, "Slurm time limit per unit (sbatch --time)")->group("Cluster");
    cmd->add_option("--max-parallel", options->slurmOptions.maxParallel, "array tasks running at once (0: no limit)")
        ->check(CLI::NonNegativeNumber)
        ->group("Cluster");
    cmd->add_option("--cpus-per-task", options->slurmOptions.cpusPerTask,
                    "CPUs per unit (sbatch --cpus-per-task; the unit uses that many threads)")
        ->check(CLI::NonNegativeNumber)
        ->group("Cluster");
    cmd->add_option("--lightmap-bands", options->slurmOptions.bands,
                    "units per lightmap atlas, each a band of its rows (0: one per 512 x 512 texels of the atlas)")
        ->check(CLI::Range(0, 4096))
        ->group("Cluster");
    cmd->add_flag("--slurm-dry-run", options->slurmOptions.dryRun, "print the batch scripts and sbatch commands only")
        ->group("Cluster");
    cmd->add_flag("--slurm-wait", options->wait,
                  "after submitting, wait for the merge and exit non-zero if a scene failed")
        ->group("Cluster");
    cmd->add_option("--slurm-status", options->status,
                    "the state of the cluster bake submitted into this output folder, per unit")
        ->group("Cluster");
    for (const auto& spec : bakeSettingsTable()) {
        const std::string name = spec.name;
        cmd->add_option_function<std::string>(
               "--" + name,
               [options, name](const std::string& value) { options->command.settings.emplace_back(name, value); },
               spec.help)
            ->group("Bake settings");
    }
    cmd->callback([options] {
        if (!options->status.empty()) {
            for (const std::string& line : cluster::slurmStatus(options->status)) std::printf("%s\n", line.c_str());
            return;
        }
        if (options->slurm || options->slurmOptions.dryRun) {
            submitToSlurm(*options);
            return;
        }
        const std::vector<BakeJob> jobs = planJobs(options->command, options->quiet);
        std::vector<BakeReport> reports;
        for (const BakeJob& job : jobs) {
            if (!options->quiet) std::fprintf(stderr, "baking %s -> %s\n", job.scenePath.c_str(), job.outputDir.c_str());
            reports.push_back(runBake(job));
            if (!reports.back().ok) std::fprintf(stderr, "error: %s\n", reports.back().error.c_str());
        }
        printBakeSummary(reports);
        for (const BakeReport& r : reports)
            if (!r.ok) throw Error(std::to_string(reports.size()) + " scene(s) baked, at least one failed");
    });
}

}  // namespace vl::cli
