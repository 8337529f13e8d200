// voxlight bench: speed against error. For one scene it sweeps the bake's settings (VCT)
// and the path tracer's spp (and Cycles' spp when Blender is on the PATH), times every
// point in this one process (median of repeats), measures its peak memory and its error
// against one reference (reference.h) on the lightmap's covered texels and on the
// image, total and indirect, and of the image the lightmap lights (the view a user sees,
// lightmap/lightmap_image.h) against the reference image, and writes bench.csv, bench.json, a time-against-error plot,
// error heat maps and a Markdown report (report.h).
//
// Times: a VCT point runs the whole bake (load, voxelize, voxel light, bounces, mips, BVH,
// receivers, shading, EXR writes; no grids file); its lightmap time is the bake without the
// image stage and its image time the bake without the lightmap stage (neither counts the
// lightmap-lit image's render). A path-tracer point times load + BVH + receivers + tracing
// the same way; its lightmap-lit image is made from its shared atlas after the timing.
//
// With options.scaling it then times how each stage scales with voxel and lightmap
// resolution and threads (scaling.h), reported with the rest.
#pragma once

#include "bake/bake_job.h"
#include "bench/reference.h"
#include "bench/scaling.h"
#include "metrics/metrics.h"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vl {

struct BenchPointSpec {
    std::string method;  // "vct", "path", "cycles"
    std::string label;   // unique within its method: "default", "resolution=64", "spp=64"
    std::vector<std::pair<std::string, std::string>> settings;  // vct: bake settings over the base job's
    int spp = 0;                                                 // path, cycles
};

struct BenchError {
    bool available = false;
    ErrorMetrics metrics;
};

struct BenchPointResult {
    BenchPointSpec spec;
    bool ok = false;
    std::string error;                      // why the point failed, when !ok
    std::vector<double> lightmapRuns;       // seconds, one per repeat
    std::vector<double> imageRuns;
    double lightmapSeconds = 0.0;           // medians; 0 when not measured
    double imageSeconds = 0.0;
    std::vector<double> cpuRuns;            // process CPU seconds (all threads) of everything the point made
    double cpuSeconds = 0.0;                // median; the shared machine is oversubscribed, so wall ≥ CPU / threads
    double peakMemoryBytes = 0.0;           // the process's resident high-water mark during the point
    BenchError lightmap, lightmapIndirect, image, imageIndirect;
    // The camera lit by the point's lightmap as it ships (lightmap/lightmap_image.h), against the
    // reference image; its time is the lightmap's, what making the lightmap cost.
    BenchError lightmapped;
    std::optional<LightmapSeamReport> seams;  // vct: the lightmap's chart seams (lightmap/lightmap_seams.h)
    double voxelSize = 0.0;                 // vct: the bake's voxel size (m) and what set it
    std::string voxelSizeSetBy;
    std::string outputDir;                  // its outputs, relative to the bench folder
    std::string note;                       // e.g. where a time came from
};

struct BenchOptions {
    BakeJob base;                       // scene, base settings, added lights; outputDir = the bench folder
    std::vector<BenchPointSpec> points; // empty: benchSweep(full), unless pointsGiven
    bool pointsGiven = false;           // points is the whole list even when empty (a Cycles-only run)
    bool full = false;
    int repeats = 3;
    double repeatLimitSeconds = 30.0;   // a point whose first run takes longer is timed once
    BenchReferenceFiles reference;      // user-named; what is missing is path-traced
    BenchReferenceSettings referenceSettings;
    float imageExcludeAbove = 5.0f;     // image pixels whose reference exceeds this (the emitter) are left out
    std::string blender;                // "" = look on the PATH; "none" = no Cycles peer
    std::string cyclesScript;           // tools/bench/cycles_bake.py
    std::vector<int> cyclesSpp = {16, 64, 256};
    // Precomputed Cycles results (lower-spp files of ../shared/reference with their timings),
    // added as method "cycles-files" points.
    std::string cyclesFilesDir;
    // After the points: how the stages scale with voxel and lightmap resolution and threads
    // (scaling.h), baked from `base`.
    bool scaling = false;
    StageScalingAxes scalingAxes;
    bool plot = true;
    bool quiet = false;
    std::string commandLine;  // how to regenerate the run, quoted in the report
};

struct BenchResult {
    std::string scenePath;
    std::string outputDir;
    BenchReference reference;  // images dropped after the run; description and noise kept
    std::vector<BenchPointResult> points;
    std::vector<std::string> notes;  // what was skipped and why (no Blender, no gnuplot, …)
    std::vector<std::string> files;  // written, relative to outputDir
    std::optional<StageScaling> scaling;  // when options.scaling and the scene loaded
    int threads = 0;
    int repeats = 0;
};

// The default sweep (VCT default, one setting varied at a time, one fast point; path tracer
// 16..256 spp), or the full one (more settings and values, path tracer to 1024 spp).
std::vector<BenchPointSpec> benchSweep(bool full);

BenchResult runBench(const BenchOptions& options);

}  // namespace vl
