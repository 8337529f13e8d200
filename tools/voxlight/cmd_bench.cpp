// Placeholder until the bench subcommand lands: says so and exits non-zero.
#include "tools/voxlight/commands.h"

#include "core/error.h"

namespace vl::cli {

void addBenchCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("bench", "(not available yet)");
    cmd->allow_extras();
    cmd->callback([] { throw Error("voxlight bench is not implemented yet"); });
}

}  // namespace vl::cli
