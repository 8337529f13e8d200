// voxlight bake [scene.gltf | job.json …]: the batch bake. Each scene bakes into
// output/<name>/ (or -o); a scene that fails is reported and the batch goes on; the exit
// code is non-zero when any scene failed.
#include "tools/voxlight/commands.h"

#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "core/error.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <utility>

namespace vl::cli {
namespace {

struct BakeOptions {
    std::vector<std::string> inputs;
    std::string output;
    std::vector<std::pair<std::string, std::string>> settings;  // in command-line order
    bool strict = false;
    bool quiet = false;
};

bool isJobFile(const std::string& path) { return std::filesystem::path(path).extension() == ".json"; }

std::vector<BakeJob> planJobs(const BakeOptions& options) {
    BakeSettings settings;
    for (const auto& [name, value] : options.settings) applySetting(bakeSettingsTable(), settings, name, value);
    settings.strict = options.strict;
    settings.quiet = options.quiet;
    validateBakeSettings(settings);

    std::vector<std::string> inputs = options.inputs;
    if (inputs.empty()) inputs.push_back(defaultScenePath());
    const bool single = inputs.size() == 1 && !isJobFile(inputs[0]);
    std::vector<BakeJob> jobs;
    for (const std::string& input : inputs) {
        if (isJobFile(input)) {
            for (BakeJob& job : readJobFile(input, settings, options.output.empty() ? "output" : options.output)) {
                job.settings.strict = job.settings.strict || options.strict;
                job.settings.quiet = options.quiet;
                jobs.push_back(std::move(job));
            }
            continue;
        }
        BakeJob job;
        job.scenePath = input;
        job.settings = settings;
        const std::string name = sceneOutputName(input);
        // -o names the folder itself for one scene, the root folder for several.
        job.outputDir = options.output.empty() ? "output/" + name
                        : single             ? options.output
                                             : options.output + "/" + name;
        jobs.push_back(std::move(job));
    }
    return jobs;
}

void printSummary(const std::vector<BakeReport>& reports) {
    std::fprintf(stderr, "\n%-28s %-6s %9s %10s %10s %9s %8s  %s\n", "scene", "status", "voxels", "texels", "pixels",
                 "seconds", "peak MB", "output");
    for (const BakeReport& r : reports) {
        const std::string name = std::filesystem::path(r.scenePath).filename().string();
        std::fprintf(stderr, "%-28s %-6s %9zu %10zu %10zu %9.2f %8.0f  %s\n", name.c_str(), r.ok ? "ok" : "FAILED",
                     r.voxels, r.coveredTexels, r.pixels, r.totalSeconds(), r.peakMemoryBytes / 1048576.0,
                     r.ok ? r.outputDir.c_str() : r.error.c_str());
    }
}

}  // namespace

void addBakeCommand(CLI::App& app) {
    auto options = std::make_shared<BakeOptions>();
    auto* cmd = app.add_subcommand("bake", "bake lightmaps, images and grids for glTF scenes or job files "
                                           "(default: the Cornell box into output/cornell_box/)");
    cmd->add_option("inputs", options->inputs, "scene files (.gltf, .glb) and job files (.json)");
    cmd->add_option("-o,--output", options->output,
                    "output folder (one scene) or root folder (several); default output/<scene name>");
    cmd->add_flag("--strict", options->strict, "treat every warning as an error");
    cmd->add_flag("-q,--quiet", options->quiet, "no progress on stderr");
    for (const auto& spec : bakeSettingsTable()) {
        const std::string name = spec.name;
        cmd->add_option_function<std::string>(
               "--" + name, [options, name](const std::string& value) { options->settings.emplace_back(name, value); },
               spec.help)
            ->group("Bake settings");
    }
    cmd->callback([options] {
        const std::vector<BakeJob> jobs = planJobs(*options);
        std::vector<BakeReport> reports;
        for (const BakeJob& job : jobs) {
            if (!options->quiet) std::fprintf(stderr, "baking %s -> %s\n", job.scenePath.c_str(), job.outputDir.c_str());
            reports.push_back(runBake(job));
            if (!reports.back().ok) std::fprintf(stderr, "error: %s\n", reports.back().error.c_str());
        }
        printSummary(reports);
        for (const BakeReport& r : reports)
            if (!r.ok) throw Error(std::to_string(reports.size()) + " scene(s) baked, at least one failed");
    });
}

}  // namespace vl::cli
