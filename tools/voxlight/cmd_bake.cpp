// Placeholder until the bake subcommand lands: says so and exits non-zero.
#include "tools/voxlight/commands.h"

#include "core/error.h"

namespace vl::cli {

void addBakeCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("bake", "(not available yet)");
    cmd->allow_extras();
    cmd->callback([] { throw Error("voxlight bake is not implemented yet"); });
}

}  // namespace vl::cli
