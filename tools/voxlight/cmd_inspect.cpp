// Placeholder until the inspect subcommand lands: says so and exits non-zero.
#include "tools/voxlight/commands.h"

#include "core/error.h"

namespace vl::cli {

void addInspectCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("inspect", "(not available yet)");
    cmd->allow_extras();
    cmd->callback([] { throw Error("voxlight inspect is not implemented yet"); });
}

}  // namespace vl::cli
