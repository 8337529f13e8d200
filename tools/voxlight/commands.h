// Each subcommand lives in its own file and registers itself with the app here.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace vl {
struct BakeJob;
namespace cluster {
struct PlannedCommand;
}
}  // namespace vl

namespace vl::cli {

void addVoxelizeCommand(CLI::App& app);
void addInspectCommand(CLI::App& app);
void addReferenceCommand(CLI::App& app);
void addLightCommand(CLI::App& app);
void addBakeCommand(CLI::App& app);
void addBakeUnitCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addViewCommand(CLI::App& app);

// The jobs of a bake command line (its inputs, -o, settings in order and --strict); cmd_bake.cpp.
std::vector<BakeJob> planJobs(const cluster::PlannedCommand& command, bool quiet);

// The project's default scene (scenes/cornell_box.gltf in the source tree).
std::string defaultScenePath();

}  // namespace vl::cli
