// Placeholder until the voxelize subcommand lands: says so and exits non-zero.
#include "tools/voxlight/commands.h"

#include "core/error.h"

namespace vl::cli {

void addVoxelizeCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("voxelize", "(not available yet)");
    cmd->allow_extras();
    cmd->callback([] { throw Error("voxlight voxelize is not implemented yet"); });
}

}  // namespace vl::cli
