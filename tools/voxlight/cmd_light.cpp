// `voxlight light grids.vdb scene.gltf -o lit.vdb`: the voxel direct-lighting pass. Reads the
// attribute grids written by `voxlight voxelize`, lights them with the scene's punctual lights
// and emissive triangles, and writes the same grids plus `radiance` and `occlusion`.
#include "tools/voxlight/commands.h"

#include "core/error.h"
#include "core/progress.h"
#include "cuda/device_choice.h"
#include "cuda/launchers.h"
#include "lighting/lighting.h"
#include "scene/gltf_loader.h"
#include "voxel/vdb_file.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

namespace vl::cli {

namespace {

struct LightOptions {
    std::string grids;
    std::string scene;
    std::string output;
    std::string normalWeights = toString(LightingSettings{}.normalWeights);
    std::string attenuation;
    std::vector<std::string> lightAttenuation;
    std::string device = "cpu";
    int emitterStrata = LightingSettings{}.emitterStrata;
    int threads = 0;
    bool noHdda = false;
    bool strict = false;
    bool quiet = false;
};

AttenuationCoefficients parseCoefficients(const std::string& text, const std::string& option) {
    std::vector<float> values;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        try {
            size_t used = 0;
            values.push_back(std::stof(item, &used));
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw SettingsError("light: " + option + " '" + text + "': '" + item + "' is not a number");
        }
    }
    if (values.size() != 3)
        throw SettingsError("light: " + option + " '" + text + "': expected three numbers K_c,K_l,K_q");
    return {values[0], values[1], values[2]};
}

void runLight(const LightOptions& options) {
    LightingSettings settings;
    settings.normalWeights = parseNormalWeighting(options.normalWeights);
    settings.traversal = options.noHdda ? VisibilityTraversal::Dda : VisibilityTraversal::Hdda;
    settings.emitterStrata = options.emitterStrata;
    settings.threads = options.threads;
    if (!options.attenuation.empty()) settings.attenuation = parseCoefficients(options.attenuation, "--attenuation");
    for (const std::string& entry : options.lightAttenuation) {
        const size_t eq = entry.rfind('=');
        if (eq == std::string::npos || eq == 0)
            throw SettingsError("light: --light-attenuation '" + entry + "': expected NAME=K_c,K_l,K_q");
        settings.lightAttenuation[entry.substr(0, eq)] =
            parseCoefficients(entry.substr(eq + 1), "--light-attenuation " + entry.substr(0, eq));
    }

    const bool onGpu = cuda::resolveDevice(cuda::parseDeviceChoice(options.device), std::cerr);

    const std::string output = options.output.empty()
        ? "output/" + std::filesystem::path(options.scene).stem().string() + "_lit.vdb"
        : options.output;

    LoadOptions load;
    load.strict = options.strict;
    Scene scene = loadGltf(options.scene, load);
    VoxelScene voxels = readVoxelFile(options.grids);
    // Grids voxelized from this scene share its frame; others (another tool's, another
    // version's) are lit in theirs.
    if (voxels.frame != scene.frame) scene.turnFrame(voxels.frame);
    if (voxels.origin != scene.origin) scene.moveOrigin(voxels.origin);
    if (!voxels.sourceScene.empty() &&
        std::filesystem::path(voxels.sourceScene).filename() != std::filesystem::path(options.scene).filename()) {
        const std::string message = options.grids + " was voxelized from '" + voxels.sourceScene + "', not '" +
                                    options.scene + "'";
        if (options.strict) throw InputError(message);
        std::fprintf(stderr, "warning: %s\n", message.c_str());
    }
    if (scene.lights.empty() && !scene.hasEmitters())
        std::fprintf(stderr, "warning: %s has no lights and no emissive triangles: radiance will be zero\n",
                     options.scene.c_str());

    LightingStats stats;
    {
        Progress progress("light", voxels.size(), options.quiet);
        stats = onGpu ? cuda::lightVoxelsCuda(scene, voxels, settings) : lightVoxels(scene, voxels, settings, &progress);
        progress.finish();
    }
    std::ostringstream note;
    note << voxels.settings << (voxels.settings.empty() ? "" : "; ") << "light: normal-weights=" << options.normalWeights
         << " traversal=" << (options.noHdda ? "dda" : "hdda") << " emitter-strata=" << settings.emitterStrata;
    if (settings.attenuation) note << " attenuation=" << options.attenuation;
    voxels.settings = note.str();
    writeVoxelFile(voxels, output);

    std::printf("%s: %zu voxels, %llu lights, %llu emissive triangles (%llu fixed samples)\n", options.grids.c_str(),
                voxels.size(), static_cast<unsigned long long>(stats.lights),
                static_cast<unsigned long long>(stats.emitterTriangles),
                static_cast<unsigned long long>(stats.emitterSamples));
    std::printf("  %llu voxel-light evaluations, %llu visibility steps, %.2f s (%.3g evaluations/s)\n",
                static_cast<unsigned long long>(stats.voxelLightEvaluations),
                static_cast<unsigned long long>(stats.visibilitySteps), stats.seconds,
                stats.seconds > 0.0 ? static_cast<double>(stats.voxelLightEvaluations) / stats.seconds : 0.0);
    std::printf("  wrote %s\n", output.c_str());
}

}  // namespace

void addLightCommand(CLI::App& app) {
    auto options = std::make_shared<LightOptions>();
    auto* cmd = app.add_subcommand("light", "Voxel direct lighting: fill the radiance and occlusion grids of a .vdb");
    cmd->add_option("grids", options->grids, "attribute grids (.vdb from `voxlight voxelize`)")->required();
    cmd->add_option("scene", options->scene, "the glTF scene they were voxelized from (its lights and emitters)")
        ->required();
    cmd->add_option("-o,--output", options->output, "output .vdb (default: output/<scene name>_lit.vdb)");
    cmd->add_option("--normal-weights", options->normalWeights,
                    "lambert | villegas | six-axis (default lambert)");
    cmd->add_option("--attenuation", options->attenuation,
                    "K_c,K_l,K_q: the paper's I/(K_c + K_l r + K_q r^2) for every point and spot light "
                    "(default: glTF inverse square with the range window)");
    cmd->add_option("--light-attenuation", options->lightAttenuation,
                    "NAME=K_c,K_l,K_q for one light (repeatable; overrides --attenuation for that light)");
    cmd->add_option("--emitter-strata", options->emitterStrata,
                    "n: n x n stratified points per emissive triangle (default 3)");
    cmd->add_flag("--no-hdda", options->noHdda, "step one voxel at a time instead of leaping empty nodes (same result)");
    cmd->add_option("--threads", options->threads, "worker threads (default: all cores)");
    cmd->add_option("--device", options->device,
                    "cpu | cuda | auto: auto takes the GPU when one is usable, else says why it runs on the CPU "
                    "(default cpu)");
    cmd->add_flag("--strict", options->strict, "treat every warning as an error");
    cmd->add_flag("-q,--quiet", options->quiet, "no progress output");
    cmd->callback([options] { runLight(*options); });
}

}  // namespace vl::cli
