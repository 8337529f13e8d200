// Placeholder until the light subcommand lands: says so and exits non-zero.
#include "tools/voxlight/commands.h"

#include "core/error.h"

namespace vl::cli {

void addLightCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("light", "(not available yet)");
    cmd->allow_extras();
    cmd->callback([] { throw Error("voxlight light is not implemented yet"); });
}

}  // namespace vl::cli
