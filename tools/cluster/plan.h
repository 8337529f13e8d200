// A cluster bake's plan and the files beside it in its work folder (<output>/.voxlight-slurm):
// plan.json (the command every unit re-reads, the scenes, their units and fingerprints, the
// Slurm job ids) and the merge's summary.json.
#pragma once

#include "bake/bake_job.h"
#include "cluster/units.h"

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace vl::cluster {

constexpr const char* kPlanFile = "plan.json";

// The job as every unit re-reads it: the command line that planned it.
struct PlannedCommand {
    std::vector<std::string> inputs;  // absolute
    std::string output;               // absolute; empty: no -o (scenes go to output/<name> in `chdir`)
    std::vector<std::pair<std::string, std::string>> settings;
    bool strict = false;
};

// plan.json in the job's work folder.
struct ClusterPlan {
    PlannedCommand command;
    std::string workDir;   // absolute: <output root>/.voxlight-slurm
    std::string voxlight;  // absolute path of the voxlight binary the units run
    std::string chdir;     // the folder the job was submitted from
    struct Scene {
        std::string scenePath, outputDir, fingerprint;
        SceneUnits units;
        std::string planError;  // why planning failed (the scene did not load): nothing runs, the merge reports it
    };
    std::vector<Scene> scenes;
    // Slurm job ids, once submitted ("" where nothing was submitted).
    std::string voxelJob;
    std::vector<int> voxelTasks;  // the scenes the voxel array ran
    std::vector<std::string> receiverJobs;  // per scene
    std::vector<std::vector<int>> receiverTasks;  // per scene, the receivers submitted
    std::string mergeJob;
};

std::string workFolder(const std::string& outputRoot);
std::string sceneWorkFolder(const std::string& workDir, size_t scene);
void writePlan(const ClusterPlan& plan);
// InputError naming the file when it is missing or not a plan.
ClusterPlan readPlan(const std::string& workDir);

// A scene's fingerprint: voxlight's version, the job's settings, and the names, sizes and
// modification times of the scene file, the files it points at, the sky image and `jobFiles`.
std::string fingerprint(const BakeJob& job, const std::vector<std::string>& jobFiles);

// The merge's summary (written by the merge unit): per scene, ok or the error.
constexpr const char* kSummaryFile = "summary.json";
nlohmann::json readSummary(const std::string& workDir);
// `mergeSeconds`: per scene, the merge's wall time for it.
void writeSummary(const std::string& workDir, const std::vector<BakeReport>& reports,
                  const std::vector<double>& mergeSeconds);

}  // namespace vl::cluster
