#include "bench/run.h"

#include "lightmap/dilate.h"
#include "lightmap/lightmap_image.h"
#include "bench/cycles_peer.h"
#include "bench/process_stats.h"
#include "bench/report.h"
#include "bench/traced_scene.h"
#include "core/error.h"
#include "core/image_io.h"

#include <tbb/info.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace vl {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fileSafe(const std::string& text) {
    std::string out;
    for (char c : text) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.') ? c : '_';
    return out;
}

// The mask of image pixels compared: those whose total reference stays at or below `limit`
// in every channel (the emitter seen directly is left out, as the Cycles README does).
Image imageMask(const Image& reference, float limit) {
    Image mask(reference.width, reference.height, 1, 1.0f);
    if (limit <= 0.0f) return mask;
    for (int y = 0; y < reference.height; ++y)
        for (int x = 0; x < reference.width; ++x)
            for (int c = 0; c < std::min(3, reference.channels); ++c)
                if (reference.at(x, y, c) > limit) mask.at(x, y) = 0.0f;
    return mask;
}

BenchError compare(const Image& test, const Image& reference, const Image& mask, const std::string& testName,
                   const Image* testMask = nullptr) {
    BenchError e;
    MetricOptions options;
    options.mask = &mask;
    options.testMask = testMask;
    options.testName = testName;
    e.metrics = compareImages(test, reference, options);
    e.available = true;
    return e;
}

struct Comparer {
    const BenchReference& ref;
    Image imageMask;

    // Fills the point's errors from whichever of its outputs exist on disk.
    void fromFiles(BenchPointResult& p, const fs::path& dir, const std::string& lightmapStem, const std::string& imageStem) const {
        // A lightmap is rated over the texels it holds its own light in (its _mask.exr): not those
        // inside closed geometry, which it fills from their neighbours and a reference bake
        // holds black.
        const fs::path ownMaskFile = dir / (lightmapStem + "_mask.exr");
        const Image ownMask = !lightmapStem.empty() && fs::exists(ownMaskFile) ? readImage(ownMaskFile.string()) : Image();
        auto check = [&](const std::string& stem, const std::string& suffix, const Image& reference, const Image& mask,
                         BenchError& out) {
            const fs::path file = dir / (stem + suffix);
            if (stem.empty() || !fs::exists(file)) return;
            const bool lightmap = stem == lightmapStem && !ownMask.empty();
            out = compare(readImage(file.string()), reference, mask, file.string(), lightmap ? &ownMask : nullptr);
        };
        if (ref.hasLightmap) check(lightmapStem, ".exr", ref.lightmap, ref.mask, p.lightmap);
        if (ref.hasLightmapIndirect) check(lightmapStem, "_indirect.exr", ref.lightmapIndirect, ref.mask, p.lightmapIndirect);
        if (ref.hasImage) check(imageStem, ".exr", ref.image, imageMask, p.image);
        if (ref.hasImageIndirect) check(imageStem, "_indirect.exr", ref.imageIndirect, imageMask, p.imageIndirect);
        if (ref.hasImage) check(imageStem, "_lightmapped.exr", ref.image, imageMask, p.lightmapped);
    }
};

// The image the bake wrote for the first camera: "image" with one camera, else "image_0_<name>".
std::string imageStemOf(const BakeReport& report) {
    for (const std::string& f : report.files)
        if (f.rfind("image", 0) == 0 && f.size() > 13 && f.compare(f.size() - 13, 13, "_indirect.exr") == 0)
            return f.substr(0, f.size() - 13);
    return "";
}

void runVctPoint(const BenchOptions& options, const Comparer& comparer, BenchPointResult& p) {
    BakeJob job = options.base;
    for (const auto& [name, value] : p.spec.settings) applySetting(bakeSettingsTable(), job.settings, name, value);
    job.settings.outputs.grids = false;  // files that package the bake, not the bake
    job.settings.outputs.gltf = false;
    // Only what the reference can rate: the lightmap when it has one, and the image with the
    // lightmap-lit image beside it (which needs a lightmap: zdm2 has no TEXCOORD_1, so its
    // reference has no lightmap, and the bake generates UVs for one).
    if (!comparer.ref.hasImage) job.settings.outputs.images = false;
    if (!comparer.ref.hasLightmap && !makesLightmapImages(job.settings)) job.settings.outputs.lightmaps = false;
    job.settings.quiet = true;
    validateBakeSettings(job.settings);
    p.outputDir = "points/vct-" + fileSafe(p.spec.label);
    job.outputDir = (fs::path(options.base.outputDir) / p.outputDir).string();
    BakeReport report;
    for (int r = 0; r < options.repeats; ++r) {
        const double cpu = cpuSeconds();
        report = runBake(job);
        p.cpuRuns.push_back(cpuSeconds() - cpu);
        if (!report.ok) throw Error(report.error);
        const double total = report.totalSeconds();
        // Each output's time leaves out the other's stages and the lightmap-lit image's render
        // (a measurement, not part of either): generated lightmap UVs are the lightmap's.
        const double measuring = stageSeconds(report.stages, "lightmap image");
        if (job.settings.outputs.lightmaps)
            p.lightmapRuns.push_back(total - stageSeconds(report.stages, "images") - measuring);
        if (job.settings.outputs.images)
            p.imageRuns.push_back(total - stageSeconds(report.stages, "lightmaps") -
                                  stageSeconds(report.stages, "lightmap uvs") - measuring);
        if (r == 0 && total > options.repeatLimitSeconds) break;
    }
    p.voxelSize = report.voxelSize;
    p.voxelSizeSetBy = report.voxelSizeChoice.setBy;
    p.seams = report.lightmapSeams;
    comparer.fromFiles(p, job.outputDir, "lightmap", imageStemOf(report));
}

void runPathPoint(const BenchOptions& options, const Comparer& comparer, BenchPointResult& p) {
    p.outputDir = "points/path-" + fileSafe(p.spec.label);
    const fs::path dir = fs::path(options.base.outputDir) / p.outputDir;
    fs::create_directories(dir);
    const PathTracerSettings settings = benchPathSettings(p.spec.spp, 0);
    TraceResult lightmap, image;
    std::optional<BenchTraceScene> traced;
    for (int r = 0; r < options.repeats; ++r) {
        traced.reset();
        const auto start = Clock::now();
        const double cpu = cpuSeconds();
        traced.emplace(loadBenchTraceScene(options.base));
        const double setup = secondsSince(start);
        double total = setup;
        if (traced->atlas) {
            lightmap = traceIrradiance(traced->trace, traced->bvh, traced->atlas->receivers, settings);
            p.lightmapRuns.push_back(setup + lightmap.seconds);
            total += lightmap.seconds;
        }
        if (traced->camera) {
            image = renderCamera(traced->trace, traced->bvh, *traced->camera, settings);
            p.imageRuns.push_back(setup + image.seconds);
            total += image.seconds;
        }
        p.cpuRuns.push_back(cpuSeconds() - cpu);
        if (r == 0 && total > options.repeatLimitSeconds) break;
    }
    if (!lightmap.beauty.empty()) {
        writeExr(lightmap.beauty, (dir / "lightmap.exr").string());
        writeExr(lightmap.indirect, (dir / "lightmap_indirect.exr").string());
    }
    if (!image.beauty.empty()) {
        writeExr(image.beauty, (dir / "image.exr").string());
        writeExr(image.indirect, (dir / "image_indirect.exr").string());
    }
    // The path-traced lightmap as the bake's would ship (dilated, RGBM), lighting the camera:
    // what this lightmap resolution and its bilinear reading allow, whatever the light. Only
    // the shared atlas is traced; meshes of other atlases show the unlit level.
    if (traced && traced->atlas && traced->camera && !lightmap.beauty.empty() && !image.beauty.empty() &&
        options.base.settings.outputs.lightmapImage) {
        Image texels = lightmap.beauty;
        dilatePadding(texels, traced->atlas->mask);
        const Image lit = bakeLightmapImage(traced->trace, traced->bvh, *traced->camera, traced->scene, traced->triangles,
                                            options.base.settings, {{traced->atlas->meshes, shippedLightmapTexels(texels)}});
        writeExr(lit, (dir / "image_lightmapped.exr").string());
    }
    comparer.fromFiles(p, dir, "lightmap", "image");
}

std::string percentOrDash(const BenchError& e) {
    if (!e.available) return "-";
    char text[32];
    std::snprintf(text, sizeof text, "%.1f%%", 100.0 * e.metrics.relativeRmse);
    return text;
}

}  // namespace

std::vector<BenchPointSpec> benchSweep(bool full) {
    std::vector<BenchPointSpec> points;
    auto vct = [&](const std::string& label, std::vector<std::pair<std::string, std::string>> settings) {
        points.push_back({"vct", label, std::move(settings), 0});
    };
    auto each = [&](const std::string& name, const std::vector<std::string>& values) {
        for (const std::string& v : values) vct(name + "=" + v, {{name, v}});
    };
    vct("default", {});
    // The settings that move the default's time or error most: voxel resolution (around the
    // default's own choice, so the report can rate it: bake/voxel_size.h), what decides the
    // gathers' visibility (cones, the method before rays), the rays per gather, where the
    // final gather runs, and the bounces.
    if (full) {
        each("resolution", {"32", "48", "64", "96", "160", "224"});
        each("gather-visibility", {"cones"});
        each("gather-rays", {"8", "24"});
        each("bounce-rays", {"4", "12"});
        each("cones", {"6", "16"});
        each("normal-weights", {"lambert", "villegas"});
        each("bounces", {"0", "2", "4"});
        each("gather-level", {"-1", "3"});  // -1: every receiver sample gathers its own cones (slower)
        each("bounce-gather-level", {"3"});
        each("voxel-emitter-strata", {"2"});
    } else {
        each("resolution", {"80", "96", "160"});
        each("gather-visibility", {"cones"});
        vct("rays=12", {{"bounce-rays", "12"}, {"gather-rays", "12"}});  // 12 x 12 rays at every gather
        // The default before the voxel size followed the free paths (bake/voxel_size.h).
        vct("resolution=112 gather-level=3", {{"resolution", "112"}, {"gather-level", "3"}, {"bounce-gather-level", "3"}});
        each("bounces", {"2"});
    }
    // The fast end.
    vct("resolution=48 rays=8", {{"resolution", "48"}, {"bounce-rays", "8"}, {"gather-rays", "8"}});
    const std::vector<int> spp = full ? std::vector<int>{4, 16, 64, 256, 1024} : std::vector<int>{16, 64, 256};
    for (int s : spp) points.push_back({"path", "spp=" + std::to_string(s), {}, s});
    return points;
}

BenchResult runBench(const BenchOptions& options) {
    if (options.repeats < 1 || options.repeats > 100)
        throw SettingsError("repeats: " + std::to_string(options.repeats) + " is outside 1..100");
    if (options.base.outputDir.empty()) throw SettingsError("bench: no output folder");
    validateBakeSettings(options.base.settings);
    BenchResult result;
    result.scenePath = options.base.scenePath;
    result.outputDir = options.base.outputDir;
    result.threads = tbb::info::default_concurrency();
    result.repeats = options.repeats;
    fs::create_directories(options.base.outputDir);

    BenchReferenceSettings refSettings = options.referenceSettings;
    refSettings.quiet = options.quiet;
    const auto refStart = Clock::now();
    result.reference = prepareBenchReference(options.base, options.reference, refSettings);
    if (!options.quiet)
        std::fprintf(stderr, "bench: reference ready in %.1f s: %s\n", secondsSince(refStart), result.reference.description.c_str());
    const Comparer comparer{result.reference, result.reference.hasImage ? imageMask(result.reference.image, options.imageExcludeAbove) : Image()};

    std::vector<BenchPointSpec> specs = options.points.empty() && !options.pointsGiven ? benchSweep(options.full) : options.points;
    const CyclesPeer peer = findCyclesPeer(options);
    if (!peer.available) result.notes.push_back(peer.why);
    else
        for (int spp : options.cyclesSpp) specs.push_back({"cycles", "spp=" + std::to_string(spp), {}, spp});

    const bool peakResets = resetPeakMemory();
    if (!peakResets) result.notes.push_back("peak memory is the process's since it started (/proc/self/clear_refs not writable)");

    for (const BenchPointSpec& spec : specs) {
        BenchPointResult p;
        p.spec = spec;
        if (!options.quiet) std::fprintf(stderr, "bench: %s %s ...\n", spec.method.c_str(), spec.label.c_str());
        resetPeakMemory();
        try {
            if (spec.method == "vct") runVctPoint(options, comparer, p);
            else if (spec.method == "path") runPathPoint(options, comparer, p);
            else if (spec.method == "cycles") runCyclesPoint(options, peer, p, [&](BenchPointResult& q, const fs::path& dir) {
                comparer.fromFiles(q, dir, "lightmap", "image");
            });
            else throw SettingsError("bench: unknown method '" + spec.method + "' (vct, path, cycles)");
            p.ok = true;
        } catch (const std::exception& e) {
            p.error = e.what();
            if (!options.quiet) std::fprintf(stderr, "bench: %s %s failed: %s\n", spec.method.c_str(), spec.label.c_str(), e.what());
        }
        if (p.peakMemoryBytes == 0.0) p.peakMemoryBytes = peakMemoryBytes();  // a Cycles point reports its own process's
        p.lightmapSeconds = median(p.lightmapRuns);
        p.imageSeconds = median(p.imageRuns);
        p.cpuSeconds = median(p.cpuRuns);
        if (!options.quiet && p.ok)
            std::fprintf(stderr, "bench: %s %s: lightmap %.2f s %s (indirect %s), image %.2f s %s, lightmap-lit %s\n",
                         spec.method.c_str(), spec.label.c_str(), p.lightmapSeconds, percentOrDash(p.lightmap).c_str(),
                         percentOrDash(p.lightmapIndirect).c_str(), p.imageSeconds, percentOrDash(p.image).c_str(),
                         percentOrDash(p.lightmapped).c_str());
        if (!options.quiet && p.ok && p.seams)
            std::fprintf(stderr,
                         "bench: %s %s: %zu lightmap seams, mean jump on the edge %.2f%% (%.2f%% before stitching), "
                         "half a texel in %.2f%% (%.2f%%)\n",
                         spec.method.c_str(), spec.label.c_str(), p.seams->after.edges,
                         100.0 * p.seams->afterAtEdge.meanRelative, 100.0 * p.seams->beforeAtEdge.meanRelative,
                         100.0 * p.seams->after.meanRelative, 100.0 * p.seams->before.meanRelative);
        result.points.push_back(std::move(p));
    }
    if (!options.cyclesFilesDir.empty()) {
        std::vector<BenchPointResult> files = cyclesFilePoints(options.cyclesFilesDir, options.base.scenePath, options.reference,
                                                               [&](BenchPointResult& q, const fs::path& dir, const std::string& lm,
                                                                   const std::string& im) { comparer.fromFiles(q, dir, lm, im); });
        for (BenchPointResult& p : files) result.points.push_back(std::move(p));
    }
    if (options.scaling) {
        try {
            StageScalingAxes axes = options.scalingAxes;
            axes.repeatLimitSeconds = options.repeatLimitSeconds;
            result.scaling = runStageScaling(options.base, options.quiet, axes);
        } catch (const std::exception& e) {
            result.notes.push_back(std::string("no stage scaling: ") + e.what());
        }
    }
    writeBenchOutputs(result, options);
    return result;
}

}  // namespace vl
