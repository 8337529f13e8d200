// `voxlight bake --slurm`: a bake job submitted to a Slurm cluster as units (cluster/units.h),
// and the state of a submitted job. Per job, in sbatch's terms:
//   one array of voxel units, task K = scene K;
//   per scene an array of its receiver units (bands of its atlases, then its cameras),
//     --dependency=afterok:<voxel array>_K, --kill-on-invalid-dep=yes: cancelled, not left
//     pending, when its voxel unit fails;
//   one merge job, --dependency=afterany on all of them: it runs after failures too, and
//     reports them.
// Every node must see the output folder at the same path (a shared file system with
// close-to-open consistency, as NFS gives): units hand their results over in
// <output root>/.voxlight-slurm/, and the merge publishes each scene's folder as a local bake
// does. A second submission of the same job (same inputs, settings and voxlight) runs only the
// units without a successful result; a changed job starts over.
#pragma once

#include "bake/bake_job.h"
#include "cluster/units.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace vl::cluster {

struct SlurmOptions {
    std::string partition;  // sbatch --partition; empty: the cluster's default
    std::string time;       // sbatch --time per unit; empty: the partition's default
    int maxParallel = 0;    // array tasks running at once (--array=…%N); 0: no limit
    int cpusPerTask = 0;    // sbatch --cpus-per-task; 0: Slurm's default
    int bands = 0;          // lightmap bands per scene; 0: one per kTexelsPerBand texels
    bool dryRun = false;    // print the batch scripts and sbatch commands, submit nothing
};

// The job as every unit re-reads it: the command line that planned it.
struct PlannedCommand {
    std::vector<std::string> inputs;  // absolute
    std::string output;               // absolute; empty: ./output at submission
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

// Submits what is not done of `plan` (whose command, scenes and binary are set) and writes
// plan.json with the job ids; dry-run prints instead. Returns the lines to print.
std::vector<std::string> submit(ClusterPlan& plan, const SlurmOptions& options);

// Per scene and unit: done, failed and why, queued and why, running, or gone without a result.
std::vector<std::string> slurmStatus(const std::string& outputRoot);

// Waits until the plan's merge job has left the queue; false if it never was submitted. Error
// when squeue keeps failing.
bool waitForMerge(const ClusterPlan& plan, double pollSeconds = 1.0);

// The merge's summary (written by the merge unit): per scene, ok or the error.
constexpr const char* kSummaryFile = "summary.json";
nlohmann::json readSummary(const std::string& workDir);
// `mergeSeconds`: per scene, the merge's wall time for it.
void writeSummary(const std::string& workDir, const std::vector<BakeReport>& reports,
                  const std::vector<double>& mergeSeconds);

}  // namespace vl::cluster
