#include "tools/voxlight/commands.h"

#include "core/error.h"

#include <iostream>

namespace vl::cli {

std::string defaultScenePath() { return std::string(VOXLIGHT_SOURCE_DIR) + "/scenes/cornell_box.gltf"; }

}  // namespace vl::cli

int main(int argc, char** argv) {
    CLI::App app{"voxlight: global illumination baking for glTF scenes (voxel cone tracing)"};
    app.set_version_flag("--version", std::string("voxlight ") + VOXLIGHT_VERSION);
    app.require_subcommand(1);
    vl::cli::addVoxelizeCommand(app);
    vl::cli::addInspectCommand(app);
    vl::cli::addReferenceCommand(app);
    vl::cli::addLightCommand(app);
    vl::cli::addBakeCommand(app);
    vl::cli::addBakeUnitCommand(app);
    vl::cli::addBenchCommand(app);
    vl::cli::addViewCommand(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const vl::Error& e) {
        std::cerr << "error: " << e.what() << '\n';
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "internal error: " << e.what() << '\n';
        return 2;
    }
    return 0;
}
