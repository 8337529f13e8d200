// How the bake's stages scale (voxlight bench's "How the stages scale"). Takes a bake job;
// loads its scene once and bakes it in memory (bake.h, no files) along two axes: voxel
// resolution at the job's lightmap size, and lightmap resolution at the job's voxel
// resolution (the job's own settings are one run of both); and, when asked, a third: generated
// rooms of spheres of more and more triangles at one voxel and lightmap resolution
// (bench/sphere_room.h), the same covered texels in each. Gives every run's per-stage wall
// time, work (voxels, gather points, covered texels, pixels) and peak memory; each stage's
// growth exponent against its work between consecutive runs, flagged above
// kGrowthExponentLimit; and the speedup of the job's bake from one thread to all of them.
#pragma once

#include "bake/bake_job.h"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace vl {

// A stage whose time grows as work^e with e above this grows faster than its work (a
// cost per voxel or per texel that rises with the size).
constexpr double kGrowthExponentLimit = 1.25;
// Stage times under this are timer noise and scheduling on a shared machine: not rated.
constexpr double kScalingNoiseFloorSeconds = 0.005;
// Parallel efficiency expected of the stages that carry the bake (bounces, gather): the
// issue's 1 → 2 threads ≥ 1.8×.
constexpr double kThreadEfficiencyTarget = 0.9;
// The triangle axis's goals (issue 35): the lightmap's time per covered texel grows by no more
// than this from the fewest triangles to the most, and the most triangles bake in under
// kTrianglePeakMemoryGoalBytes.
constexpr double kTexelTimeGrowthLimit = 2.0;
constexpr double kTrianglePeakMemoryGoalBytes = 2.0 * 1024.0 * 1024.0 * 1024.0;
// Other processes using more than this many cores during a run take cores its threads need:
// its times carry their load, and a thread speedup measured then is not rated.
constexpr double kOtherLoadLimitCores = 0.25;

struct StageScalingAxes {
    std::vector<int> resolutions = {64, 128, 256};              // voxels along the longest axis
    std::vector<int> lightmapResolutions = {256, 512, 1024};    // atlas width and height
    bool threads = true;  // also bake the job's settings on one thread
    // The triangle axis: a sphere room of each of these many triangles (none: no axis), baked
    // at triangleResolution voxels and a triangleLightmapResolution² atlas, the job's other
    // settings.
    std::vector<size_t> triangles;
    int triangleResolution = 128;
    int triangleLightmapResolution = 2048;
    // Bakes per run; a stage's time is its fastest: the ratios of small stage times are what
    // is measured, and other load on the machine only ever adds time.
    int repeats = 3;
    double repeatLimitSeconds = 30.0;  // a run whose first bake takes longer is baked once
};

struct StageScalingRun {
    std::string label;  // "resolution=64 lightmap-res=256"
    size_t triangles = 0;  // of the scene baked
    int resolution = 0;
    int lightmapResolution = 0;
    int threads = 0;  // TBB's parallelism during the run
    int bakes = 0;    // how many times it was baked (stages: the fastest of them)
    bool ok = false;
    std::string error;  // why the bake failed, when !ok
    size_t voxels = 0;
    size_t gatherPoints = 0;
    size_t coveredTexels = 0;  // summed over the atlases
    size_t pixels = 0;         // summed over the cameras
    std::vector<StageTime> stages;
    double cpuSeconds = 0.0;       // of the bake with the fastest total
    double otherCores = 0.0;       // cores other processes used during that bake, on average
    double peakMemoryBytes = 0.0;  // over its bakes

    double stageSeconds(const std::string& stage) const;  // 0 when the run lacks it
    double totalSeconds() const;
};

// One stage between two runs along one axis.
struct StageGrowth {
    std::string stage;
    std::string work;  // what it grows with: "voxels", "covered texels", "pixels"
    std::string from, to;  // the runs' labels
    double seconds1 = 0.0, seconds2 = 0.0;
    double work1 = 0.0, work2 = 0.0;
    bool rated = false;     // both times over the noise floor and the work changed
    double exponent = 0.0;  // log(t2/t1) / log(w2/w1), when rated
    bool flagged = false;   // rated and exponent > kGrowthExponentLimit
    std::string text;       // "bounces: 2.3× the time for 3.9× the voxels (exponent 0.61)"
};

// The pure rating of one pair: exponent, flag and text. The work did not change (ratio within
// 10%) or a time is under the noise floor: not rated, and the text says why.
StageGrowth rateStageGrowth(const std::string& stage, const std::string& work, double seconds1, double seconds2,
                            double work1, double work2);

// What a stage's time should grow with: "voxels" for the voxel stages (their cones per voxel
// or gather point are fixed by the settings), "covered texels" for lightmaps, "pixels" for
// images; "" for a stage whose work no axis changes (bvh: the triangles).
std::string stageWork(const std::string& stage);

struct ThreadSpeedup {
    std::string stage;  // a stage, or "total"
    double oneThreadSeconds = 0.0;
    double allThreadsSeconds = 0.0;
    double speedup = 0.0;  // one / all
};

struct ScalingFinding {
    std::string text;
    bool flagged = false;
};

struct StageScaling {
    std::string scenePath;
    StageScalingAxes axes;                    // what was run
    int threads = 0;                          // all threads
    std::vector<StageScalingRun> runs;        // resolution axis ascending, then the lightmap axis's other runs
    std::vector<size_t> resolutionAxis;       // indices into runs, by resolution
    std::vector<size_t> lightmapAxis;         // by lightmap resolution
    std::vector<size_t> triangleAxis;         // by triangles (the generated scenes)
    std::optional<StageScalingRun> oneThread; // the job's settings on one thread
    std::vector<ThreadSpeedup> speedups;      // in stage order, then "total"
    std::vector<StageGrowth> growth;          // resolution axis, then lightmap axis; stages in bake order
    // The triangle axis's lightmap time per covered texel, fewest triangles to most (0: no axis).
    double texelTimeGrowth = 0.0;
    std::vector<ScalingFinding> findings;     // growth lines, flags, thread speedups
    std::vector<std::string> notes;           // what was not rated and why
};

// Growth, speedups, findings and notes (each replaced) from runs, axes and oneThread (no
// timing: testable with hand-made runs).
void analyseStageScaling(StageScaling& scaling);

// Bakes every run (a failed run records its error and the others go on); prints progress and
// a summary on stderr unless quiet. Throws only when the scene cannot be loaded.
StageScaling runStageScaling(const BakeJob& base, bool quiet, const StageScalingAxes& axes = StageScalingAxes());

}  // namespace vl
