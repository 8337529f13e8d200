// `voxlight bake --slurm`: a bake job submitted to a Slurm cluster as units (cluster/units.h),
// and the state of a submitted job. Per job, in sbatch's terms:
//   one array of voxel units, task K = scene K;
//   per scene an array of its receiver units (bands of its atlases, then its cameras),
//     --dependency=afterok:<voxel array>_K, --kill-on-invalid-dep=yes: cancelled, not left
//     pending, when its voxel unit fails;
//   one merge job, --dependency=afterany on all of them: it runs after failures too, and
//     reports them.
// What the cluster must provide and what a bake on it guarantees: docs/cluster.md.
#pragma once

#include "cluster/plan.h"

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

// Submits what is not done of `plan` (whose command, scenes and binary are set) and writes
// plan.json with the job ids; dry-run prints instead. Returns the lines to print. Every node
// must see the output folder at the same path (a shared file system with close-to-open
// consistency, as NFS gives): units hand their results over in <output root>/.voxlight-slurm/,
// and the merge publishes each scene's folder as a local bake does. A second submission of the
// same job (same inputs, settings and voxlight) runs only the units without a successful
// result; a changed job starts over.
std::vector<std::string> submit(ClusterPlan& plan, const SlurmOptions& options);

// Per scene and unit: done, failed and why, queued and why, running, or gone without a result.
std::vector<std::string> slurmStatus(const std::string& outputRoot);

// Waits until the plan's merge job has left the queue; false if it never was submitted. Error
// when squeue keeps failing.
bool waitForMerge(const ClusterPlan& plan, double pollSeconds = 1.0);

}  // namespace vl::cluster
