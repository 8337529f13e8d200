// `voxlight voxelize scene.gltf -o grids.vdb`: glTF → sparse attribute grids in one .vdb.
#include "tools/voxlight/commands.h"

#include "bake/voxel_size.h"
#include "core/error.h"
#include "core/progress.h"
#include "scene/gltf_loader.h"
#include "scene/own_frame.h"
#include "voxel/vdb_file.h"
#include "voxel/voxelize.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace vl::cli {

namespace {

struct VoxelizeOptions {
    std::string scene;
    std::string output;
    double voxelSize = 0.0;
    int resolution = 1;  // read only when --resolution is given
    bool fillInterior = false;
    bool strict = false;
    bool quiet = false;
};

std::string humanBytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 4) {
        bytes /= 1024.0;
        ++u;
    }
    char text[32];
    std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
    return text;
}

void runVoxelize(const VoxelizeOptions& options, bool voxelSizeGiven, bool resolutionGiven) {
    if (voxelSizeGiven && resolutionGiven)
        throw SettingsError("voxelize: give either --voxel-size or --resolution, not both");
    if (voxelSizeGiven && !(options.voxelSize > 0.0 && std::isfinite(options.voxelSize)))
        throw SettingsError("voxelize: --voxel-size must be a positive number of metres");
    if (resolutionGiven && options.resolution <= 0)
        throw SettingsError("voxelize: --resolution must be a positive voxel count");

    const std::string output = options.output.empty()
        ? "output/" + std::filesystem::path(options.scene).stem().string() + ".vdb"
        : options.output;

    const auto start = std::chrono::steady_clock::now();
    LoadOptions load;
    load.strict = options.strict;
    Scene scene = loadGltf(options.scene, load);

    VoxelSettings settings;
    settings.voxelSize = voxelSizeGiven ? options.voxelSize : 0.0;
    settings.resolution = options.resolution;
    settings.fillInterior = options.fillInterior;
    // Into its own frame first, as a bake does (the grid along its walls): a resolution then
    // counts along the grid's axes.
    turnToOwnFrame(scene);
    if (!voxelSizeGiven && !resolutionGiven) {
        // The voxel size a default bake of the scene would choose, so the grids match its.
        const VoxelSizeChoice choice = chooseVoxelSize(scene, BakeSettings{});
        settings.voxelSize = choice.voxelSize;
        if (!options.quiet) std::fprintf(stderr, "%s\n", describeVoxelSize(choice).c_str());
        for (const std::string& warning : choice.warnings) std::fprintf(stderr, "warning: %s\n", warning.c_str());
    }
    VoxelizeStats stats;
    VoxelScene voxels;
    {
        Progress progress("voxelize", scene.triangleCount(), options.quiet);
        settings.voxelSize = voxelSizeFor(scene, settings);
        anchorToVoxelGrid(scene, settings.voxelSize);
        voxels = voxelize(scene, settings, &progress, &stats);
        progress.finish();
    }
    if (voxels.sourceScene.empty()) voxels.sourceScene = options.scene;
    writeVoxelFile(voxels, output);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::printf("%s: %zu triangles -> %zu active voxels of %.6g m", options.scene.c_str(), stats.triangles,
                voxels.size(), voxels.voxelSize);
    if (stats.interiorVoxels) std::printf(" (%zu interior)", stats.interiorVoxels);
    std::printf("\n  channels %s in memory, %s as dense arrays over the active bbox\n",
                humanBytes(stats.channelBytes).c_str(), humanBytes(stats.denseBytes).c_str());
    if (!scene.warnings.empty()) std::printf("  %zu warning(s) while loading, printed above\n", scene.warnings.size());
    std::printf("  wrote %s in %.2f s\n", output.c_str(), seconds);
}

}  // namespace

void addVoxelizeCommand(CLI::App& app) {
    auto options = std::make_shared<VoxelizeOptions>();
    auto* cmd = app.add_subcommand("voxelize", "Voxelize a glTF scene into sparse OpenVDB grids (.vdb)");
    cmd->add_option("scene", options->scene, "glTF scene (.gltf or .glb); default: the Cornell box")
        ->default_val(defaultScenePath());
    cmd->add_option("-o,--output", options->output, "output .vdb (default: output/<scene name>.vdb)");
    auto* voxelSize = cmd->add_option("--voxel-size", options->voxelSize, "voxel size in metres");
    auto* resolution = cmd->add_option("--resolution", options->resolution,
                                       "voxels along the scene's longest axis (default: the voxel size "
                                       "`voxlight bake` would choose for the scene)");
    cmd->add_flag("--fill-interior", options->fillInterior, "also mark voxels inside closed meshes solid");
    cmd->add_flag("--strict", options->strict, "treat every warning as an error");
    cmd->add_flag("-q,--quiet", options->quiet, "no progress output");
    cmd->callback([options, voxelSize, resolution] {
        runVoxelize(*options, voxelSize->count() > 0, resolution->count() > 0);
    });
}

}  // namespace vl::cli
