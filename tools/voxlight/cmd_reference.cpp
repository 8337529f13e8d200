// Placeholder until the reference subcommand lands: says so and exits non-zero.
#include "tools/voxlight/commands.h"

#include "core/error.h"

namespace vl::cli {

void addReferenceCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("reference", "(not available yet)");
    cmd->allow_extras();
    cmd->callback([] { throw Error("voxlight reference is not implemented yet"); });
}

}  // namespace vl::cli
