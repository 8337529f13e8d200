// The names voxlight gives what it writes beside a scene's output folder, and in the output
// folder of a job. A job file's scene is never given one (job_file.cpp): its folder would be
// taken for them, or its bake removed as a dead one's.
#pragma once

namespace vl {

// <folder>.partial-<pid>: a bake of <folder> being written; a dead bake's is removed (bake_job.h).
constexpr const char* kStagingInfix = ".partial-";
// <folder>.lock: held by the one bake that writes <folder>.
constexpr const char* kLockSuffix = ".lock";
// <output folder>/.voxlight-slurm: a cluster bake's plan and units (cluster/plan.h).
constexpr const char* kClusterWorkFolder = ".voxlight-slurm";

}  // namespace vl
