#include "bench/scaling.h"

#include "bench/format.h"
#include "bench/process_stats.h"
#include "bench/sphere_room.h"
#include "core/diagnostics.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>

namespace vl {
namespace {

// A work ratio this close to 1 says the axis did not change the stage's work.
constexpr double kSameWorkRatio = 1.1;
// A stage whose work an axis leaves alone but whose time still moves this much depends on
// that axis: worth a line, though it has no exponent.
constexpr double kNotableTimeRatio = 1.5;

// Seconds with three decimals below 0.1 s, two above.
std::string stageSecsText(double seconds) { return fmt(seconds < 0.1 ? "%.3f" : "%.2f", seconds); }

std::string runLabel(int resolution, int lightmapResolution) {
    // 0: the voxel size the bake chooses from the scene (bake/voxel_size.h).
    return "resolution=" + (resolution > 0 ? std::to_string(resolution) : std::string("auto")) +
           " lightmap-res=" + std::to_string(lightmapResolution);
}

// Keeps each stage's fastest time over the bakes.
void keepFastest(std::vector<StageTime>& fastest, const std::vector<StageTime>& stages) {
    if (fastest.empty()) {
        fastest = stages;
        return;
    }
    for (StageTime& f : fastest)
        for (const StageTime& t : stages)
            if (t.stage == f.stage) f.seconds = std::min(f.seconds, t.seconds);
}

// `makeScene` gives the scene of each bake (a copy of the job's, or a generated one): the bake
// takes it whole, so a run's peak memory is the bake's, not that of a scene kept beside it.
StageScalingRun bakeRun(const std::function<Scene()>& makeScene, const BakeJob& base, int resolution,
                        int lightmapResolution, int threads, const StageScalingAxes& axes, bool quiet,
                        const std::string& label = "") {
    StageScalingRun run;
    run.label = label.empty() ? runLabel(resolution, lightmapResolution) : label;
    run.resolution = resolution;
    run.lightmapResolution = lightmapResolution;
    run.threads = threads;
    BakeSettings settings = base.settings;
    settings.voxel.resolution = resolution;
    settings.voxel.voxelSize = 0.0;  // a voxel size would override the axis
    settings.lightmap.width = settings.lightmap.height = lightmapResolution;
    settings.quiet = true;
    if (!quiet) std::fprintf(stderr, "bench: scaling %s, %d thread%s ...\n", run.label.c_str(), threads, threads == 1 ? "" : "s");
    resetPeakMemory();
    try {
        std::optional<tbb::global_control> limit;
        if (threads < tbb::info::default_concurrency())
            limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
        double fastestTotal = 0.0;
        for (int r = 0; r < std::max(1, axes.repeats); ++r) {
            Diagnostics diagnostics(settings.strict, false);
            Scene scene = makeScene();
            run.triangles = scene.triangleCount();
            const double cpu = cpuSeconds(), busy = systemBusySeconds();
            const auto start = std::chrono::steady_clock::now();
            const BakeResult result = bake(std::move(scene), settings, diagnostics);
            const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const double cpuUsed = cpuSeconds() - cpu;
            const double others = wall > 0.0 ? std::max(0.0, systemBusySeconds() - busy - cpuUsed) / wall : 0.0;
            ++run.bakes;
            if (r == 0) {
                run.voxels = result.voxels.size();
                run.gatherPoints = result.gatherPoints;
                for (const BakedLightmap& lightmap : result.lightmaps) run.coveredTexels += lightmap.coveredTexels;
                for (const BakedImage& image : result.images)
                    run.pixels += static_cast<size_t>(image.beauty.width) * image.beauty.height;
            }
            const double total = totalSeconds(result.stages);
            if (r == 0 || total < fastestTotal) {
                fastestTotal = total;
                run.cpuSeconds = cpuUsed;
                run.otherCores = others;
            }
            keepFastest(run.stages, result.stages);
            if (r == 0 && total > axes.repeatLimitSeconds) break;
        }
        run.ok = true;
    } catch (const std::exception& e) {
        run.error = e.what();
        if (!quiet) std::fprintf(stderr, "bench: scaling %s failed: %s\n", run.label.c_str(), e.what());
    }
    run.peakMemoryBytes = peakMemoryBytes();
    return run;
}

// The cores other processes took from the run's threads: those they used beyond the cores
// the run left idle (a one-thread run on two cores shares nothing with one other process).
double contention(const StageScalingRun& run, int threads) {
    return std::max(0.0, run.otherCores - std::max(0, threads - run.threads));
}

double workOf(const StageScalingRun& run, const std::string& work) {
    if (work == "voxels") return static_cast<double>(run.voxels);
    if (work == "covered texels") return static_cast<double>(run.coveredTexels);
    if (work == "pixels") return static_cast<double>(run.pixels);
    return 0.0;
}

// Every stage of the runs, in the bake's order (the first run that has it decides).
std::vector<std::string> stageOrder(const StageScaling& s) {
    std::vector<std::string> order;
    auto add = [&](const StageScalingRun& run) {
        for (const StageTime& t : run.stages)
            if (std::find(order.begin(), order.end(), t.stage) == order.end()) order.push_back(t.stage);
    };
    for (const StageScalingRun& run : s.runs) add(run);
    if (s.oneThread) add(*s.oneThread);
    return order;
}

bool hasStage(const StageScalingRun& run, const std::string& stage) {
    return std::any_of(run.stages.begin(), run.stages.end(), [&](const StageTime& t) { return t.stage == stage; });
}

void analyseAxis(StageScaling& s, const std::vector<size_t>& axis, const std::string& axisName,
                 const std::vector<std::string>& stages, std::set<std::string>& underFloor,
                 std::vector<std::string>& contended) {
    std::vector<const StageScalingRun*> ok;
    for (size_t i : axis)
        if (s.runs[i].ok) ok.push_back(&s.runs[i]);
    const auto axisValue = [&](const StageScalingRun& r) {
        return std::to_string(axisName == "resolution" ? r.resolution : r.lightmapResolution);
    };
    for (const std::string& stage : stages) {
        const std::string work = stageWork(stage);
        if (work.empty()) continue;
        for (size_t k = 0; k + 1 < ok.size(); ++k) {
            const StageScalingRun &a = *ok[k], &b = *ok[k + 1];
            if (!hasStage(a, stage) || !hasStage(b, stage)) continue;
            StageGrowth g = rateStageGrowth(stage, work, a.stageSeconds(stage), b.stageSeconds(stage), workOf(a, work),
                                            workOf(b, work));
            g.from = a.label;
            g.to = b.label;
            const std::string step = axisName + " " + axisValue(a) + " → " + axisValue(b);
            const std::string where = ", " + step;
            const double timeRatio = g.seconds1 > 0.0 ? g.seconds2 / g.seconds1 : 0.0;
            const bool underNoise = g.seconds1 < kScalingNoiseFloorSeconds || g.seconds2 < kScalingNoiseFloorSeconds;
            const double others = std::max(contention(a, s.threads), contention(b, s.threads));
            if (others > kOtherLoadLimitCores) {  // the ratio is as much the other load's as the stage's
                g.rated = g.flagged = false;
                g.text = stage + ": not rated, other processes used " + fmt("%.1f", others) + " cores during a run";
                if (std::find(contended.begin(), contended.end(), step) == contended.end()) contended.push_back(step);
            } else if (g.rated) s.findings.push_back({g.text + where, g.flagged});
            else if (underNoise) underFloor.insert(stage);
            else if (timeRatio > kNotableTimeRatio || (timeRatio > 0.0 && timeRatio < 1.0 / kNotableTimeRatio))
                s.findings.push_back({g.text + where, false});
            s.growth.push_back(std::move(g));
        }
    }
    if (ok.size() >= 2) {
        const StageScalingRun &first = *ok.front(), &last = *ok.back();
        const std::string work = axisName == "resolution" ? "voxels" : "covered texels";
        const double memoryRatio = first.peakMemoryBytes > 0.0 ? last.peakMemoryBytes / first.peakMemoryBytes : 0.0;
        const double workRatio = workOf(first, work) > 0.0 ? workOf(last, work) / workOf(first, work) : 0.0;
        s.findings.push_back({"peak memory: " + fmt("%.0f", first.peakMemoryBytes / 1048576.0) + " → " +
                                  fmt("%.0f", last.peakMemoryBytes / 1048576.0) + " MB (" + fmt("%.2g×", memoryRatio) +
                                  " for " + fmt("%.2g×", workRatio) + " the " + work + "), " + axisName + " " +
                                  axisValue(first) + " → " + axisValue(last),
                              false});
    }
}

// The triangle axis: each stage's time from the fewest triangles to the most, the lightmap's
// time per covered texel against kTexelTimeGrowthLimit, peak memory against its goal.
void analyseTriangleAxis(StageScaling& s, const std::vector<std::string>& stages) {
    s.texelTimeGrowth = 0.0;
    std::vector<const StageScalingRun*> ok;
    for (size_t i : s.triangleAxis)
        if (s.runs[i].ok) ok.push_back(&s.runs[i]);
    if (ok.size() < 2) return;
    const StageScalingRun &first = *ok.front(), &last = *ok.back();
    const std::string span = "triangles " + std::to_string(first.triangles) + " → " + std::to_string(last.triangles);
    const double triangleRatio = double(last.triangles) / double(std::max<size_t>(first.triangles, 1));
    for (const std::string& stage : stages) {
        if (!hasStage(first, stage) || !hasStage(last, stage)) continue;
        const double t1 = first.stageSeconds(stage), t2 = last.stageSeconds(stage);
        if (t1 < kScalingNoiseFloorSeconds || t2 < kScalingNoiseFloorSeconds) continue;
        s.findings.push_back({stage + ": " + stageSecsText(t1) + " → " + stageSecsText(t2) + " s (" + fmt("%.2g×", t2 / t1) +
                                  ") for " + fmt("%.3g×", triangleRatio) + " the triangles, " + span,
                              false});
    }
    const auto perTexel = [](const StageScalingRun& r) {
        return r.coveredTexels > 0 ? r.stageSeconds("lightmaps") / double(r.coveredTexels) : 0.0;
    };
    if (perTexel(first) > 0.0 && perTexel(last) > 0.0) {
        s.texelTimeGrowth = perTexel(last) / perTexel(first);
        const bool over = s.texelTimeGrowth > kTexelTimeGrowthLimit;
        s.findings.push_back({"lightmap time per covered texel: " + fmt("%.2f", 1e6 * perTexel(first)) + " → " +
                                  fmt("%.2f", 1e6 * perTexel(last)) + " µs (" + fmt("%.2f×", s.texelTimeGrowth) + ", goal ≤ " +
                                  fmt("%g×", kTexelTimeGrowthLimit) + "), " + span,
                              over});
    }
    const bool heavy = last.peakMemoryBytes > kTrianglePeakMemoryGoalBytes;
    s.findings.push_back({"peak memory: " + fmt("%.0f", first.peakMemoryBytes / 1048576.0) + " → " +
                              fmt("%.0f", last.peakMemoryBytes / 1048576.0) + " MB (goal under " +
                              fmt("%.0f", kTrianglePeakMemoryGoalBytes / 1048576.0) + " MB at the most), " + span + " at " +
                              std::to_string(last.lightmapResolution) + "²",
                          heavy});
}

void analyseThreads(StageScaling& s, const std::vector<std::string>& stages) {
    if (!s.oneThread) return;
    if (s.threads <= 1) {
        s.notes.push_back("one thread available: no thread speedup");
        return;
    }
    const StageScalingRun& one = *s.oneThread;
    const StageScalingRun* all = nullptr;
    for (const StageScalingRun& r : s.runs)
        if (r.ok && r.resolution == one.resolution && r.lightmapResolution == one.lightmapResolution &&
            r.triangles == one.triangles)
            all = &r;
    if (!one.ok || !all) {
        s.notes.push_back("no thread speedup: the one-thread or the all-threads bake failed");
        return;
    }
    auto add = [&](const std::string& stage, double t1, double tn) {
        if (!(t1 > 0.0) || !(tn > 0.0)) return;
        s.speedups.push_back({stage, t1, tn, t1 / tn});
    };
    for (const std::string& stage : stages)
        if (hasStage(one, stage) && hasStage(*all, stage)) add(stage, one.stageSeconds(stage), all->stageSeconds(stage));
    add("total", one.totalSeconds(), all->totalSeconds());
    const double target = kThreadEfficiencyTarget * s.threads;
    // The threads need the cores: with others' load on them the speedup is the machine's.
    const double others = std::max(contention(one, s.threads), contention(*all, s.threads));
    const bool busy = others > kOtherLoadLimitCores;
    for (const ThreadSpeedup& t : s.speedups) {
        if (t.stage != "bounces" && t.stage != "gather") continue;
        const bool below = t.speedup < target;
        std::string text = "1 → " + std::to_string(s.threads) + " threads: " + t.stage + " " + fmt("%.2f×", t.speedup) +
                           " (target ≥ " + fmt("%.2g×", target) + ")";
        if (busy) text += ": not rated, other processes used " + fmt("%.1f", others) + " cores meanwhile";
        else if (below) text += ": below the target";
        s.findings.push_back({text, below && !busy});
    }
}

}  // namespace

double StageScalingRun::stageSeconds(const std::string& stage) const { return vl::stageSeconds(stages, stage); }

double StageScalingRun::totalSeconds() const { return vl::totalSeconds(stages); }

std::string stageWork(const std::string& stage) {
    if (stage == "voxelize" || stage == "voxel light" || stage == "bounces" || stage == "mips" || stage == "gather")
        return "voxels";
    if (stage == "lightmaps") return "covered texels";
    if (stage == "images") return "pixels";
    return "";
}

StageGrowth rateStageGrowth(const std::string& stage, const std::string& work, double seconds1, double seconds2,
                            double work1, double work2) {
    StageGrowth g;
    g.stage = stage;
    g.work = work;
    g.seconds1 = seconds1;
    g.seconds2 = seconds2;
    g.work1 = work1;
    g.work2 = work2;
    const double timeRatio = seconds1 > 0.0 ? seconds2 / seconds1 : 0.0;
    const double workRatio = work1 > 0.0 ? work2 / work1 : 0.0;
    if (seconds1 < kScalingNoiseFloorSeconds || seconds2 < kScalingNoiseFloorSeconds) {
        g.text = stage + ": not rated (" + fmt("%.3f", seconds1) + " s → " + fmt("%.3f", seconds2) + " s, under the " +
                 fmt("%.0f", 1000.0 * kScalingNoiseFloorSeconds) + " ms noise floor)";
        return g;
    }
    if (!(work1 > 0.0) || !(work2 > 0.0)) {
        g.text = stage + ": not rated (no " + work + ")";
        return g;
    }
    if (workRatio < kSameWorkRatio && workRatio > 1.0 / kSameWorkRatio) {
        g.text = stage + ": " + fmt("%.2g×", timeRatio) + " the time for the same " + work + " (not rated)";
        return g;
    }
    g.rated = true;
    g.exponent = std::log(timeRatio) / std::log(workRatio);
    g.flagged = g.exponent > kGrowthExponentLimit;
    g.text = stage + ": " + fmt("%.2g×", timeRatio) + " the time for " + fmt("%.2g×", workRatio) + " the " + work +
             " (exponent " + fmt("%.2f", g.exponent) + ")";
    if (g.flagged)
        g.text += ": grows faster than its work, " + fmt("%.2g×", timeRatio / workRatio) + " the time per " +
                  (work == "covered texels" ? std::string("texel") : work.substr(0, work.size() - 1));
    return g;
}

void analyseStageScaling(StageScaling& s) {
    s.growth.clear();
    s.findings.clear();
    s.speedups.clear();
    s.notes.clear();
    const std::vector<std::string> stages = stageOrder(s);
    std::set<std::string> underFloor;
    std::vector<std::string> contended;  // steps, in the axes' order
    analyseAxis(s, s.resolutionAxis, "resolution", stages, underFloor, contended);
    analyseAxis(s, s.lightmapAxis, "lightmap-res", stages, underFloor, contended);
    analyseTriangleAxis(s, stages);
    analyseThreads(s, stages);
    if (!underFloor.empty()) {
        std::string names;
        for (const std::string& stage : stages)
            if (underFloor.count(stage)) names += (names.empty() ? "" : ", ") + stage;
        s.notes.push_back("not rated where a time is under " + fmt("%.0f", 1000.0 * kScalingNoiseFloorSeconds) +
                          " ms (timer noise dominates): " + names);
    }
    if (!contended.empty()) {
        std::string steps;
        for (const std::string& step : contended) steps += (steps.empty() ? "" : ", ") + step;
        s.notes.push_back("not rated where other processes took over " + fmt("%.2g", kOtherLoadLimitCores) +
                          " of a run's cores (column others; bake again on a quiet machine): " + steps);
    }
    for (const StageScalingRun& run : s.runs)
        if (!run.ok) s.findings.push_back({run.label + " failed: " + run.error, true});
    if (s.oneThread && !s.oneThread->ok) s.findings.push_back({"one thread failed: " + s.oneThread->error, true});
}

StageScaling runStageScaling(const BakeJob& base, bool quiet, const StageScalingAxes& axes) {
    validateBakeSettings(base.settings);
    StageScaling s;
    s.scenePath = base.scenePath;
    s.axes = axes;
    s.threads = tbb::info::default_concurrency();
    const Scene scene = loadJobScene(base);
    const std::function<Scene()> copyOfJob = [&] { return scene; };
    const int baseResolution = base.settings.voxel.resolution;
    const int baseLightmap = base.settings.lightmap.width;

    auto sortedUnique = [](std::vector<int> v) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
        return v;
    };
    // The job's own settings are on both axes when the axes hold its values: baked once.
    auto runIndex = [&](int resolution, int lightmap) {
        for (size_t i = 0; i < s.runs.size(); ++i)
            if (s.runs[i].resolution == resolution && s.runs[i].lightmapResolution == lightmap) return i;
        s.runs.push_back(bakeRun(copyOfJob, base, resolution, lightmap, s.threads, axes, quiet));
        return s.runs.size() - 1;
    };
    for (int r : sortedUnique(axes.resolutions)) s.resolutionAxis.push_back(runIndex(r, baseLightmap));
    for (int l : sortedUnique(axes.lightmapResolutions)) s.lightmapAxis.push_back(runIndex(baseResolution, l));
    if (axes.threads && s.threads > 1) {
        // The all-threads bake the one-thread one is compared with (an extra run when the
        // job's own values are on neither axis).
        runIndex(baseResolution, baseLightmap);
        s.oneThread = bakeRun(copyOfJob, base, baseResolution, baseLightmap, 1, axes, quiet);
    }
    std::vector<size_t> triangles = axes.triangles;
    std::sort(triangles.begin(), triangles.end());
    triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
    for (size_t t : triangles) {
        const std::string label = "triangles=" + std::to_string(sphereRoom(t).triangleCount()) + " " +
                                  runLabel(axes.triangleResolution, axes.triangleLightmapResolution);
        s.runs.push_back(bakeRun([t] { return sphereRoom(t); }, base, axes.triangleResolution,
                                 axes.triangleLightmapResolution, s.threads, axes, quiet, label));
        s.triangleAxis.push_back(s.runs.size() - 1);
    }
    analyseStageScaling(s);
    if (base.settings.voxel.voxelSize > 0.0)
        s.notes.push_back("the job's voxel-size is left out: the runs set resolution (base " + std::to_string(baseResolution) + ")");
    if (base.settings.lightmap.height != baseLightmap)
        s.notes.push_back("the runs' lightmaps are square: lightmap-res sets width and height");

    if (!quiet) {
        for (const StageScalingRun& run : s.runs)
            if (run.ok)
                std::fprintf(stderr, "bench: scaling %s: %zu voxels, %zu covered texels, %.1f s, %.0f MB peak\n",
                             run.label.c_str(), run.voxels, run.coveredTexels, run.totalSeconds(),
                             run.peakMemoryBytes / 1048576.0);
        for (const ScalingFinding& f : s.findings)
            std::fprintf(stderr, "bench: scaling: %s%s\n", f.flagged ? "FLAGGED " : "", f.text.c_str());
        for (const std::string& note : s.notes) std::fprintf(stderr, "bench: scaling: %s\n", note.c_str());
    }
    return s;
}

}  // namespace vl
