// `voxlight reference scene.gltf --spp N`: the path-traced ground truth. Writes a camera
// render (linear EXR beauty/direct/indirect/albedo + sRGB PNG previews), the lightmap atlas
// (E/π per texel: total/direct/indirect EXRs, padding dilated, plus its coverage mask) and
// summary.json with the settings, counts and wall times. --atlases bakes the same atlas
// groups as a job file's "atlases", each into lightmap_<name>.exr.
#include "tools/voxlight/commands.h"

#include "bake/bake_settings.h"
#include "lightmap/dilate.h"
#include "bake/job_file.h"
#include "receivers/receivers.h"
#include "core/atomic_file.h"
#include "core/diagnostics.h"
#include "core/error.h"
#include "core/image_io.h"
#include "cuda/device_choice.h"
#include "cuda/launchers.h"
#include "scene/gltf_loader.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace vl::cli {

namespace {

struct ReferenceOptions {
    std::string scene;
    std::string output;
    int spp = 64;
    int lightmapSpp = 0;  // 0 = --spp
    int width = 0;
    int height = 0;
    int lightmapRes = 256;
    int lightmapSubsamples = LightmapSettings{}.subsamplesPerAxis;
    bool lightmapPerMesh = false;
    std::string atlasFile;
    int maxBounces = PathSettings{}.maxBounces;
    int rouletteStart = PathSettings{}.rouletteStart;
    std::string filter = "tent";
    uint64_t seed = 0;
    int camera = 0;
    bool noRender = false;
    bool noLightmap = false;
    bool strict = false;
    bool quiet = false;
    std::string device = "cpu";
    std::string sky;  // the bake settings' forms: R,G,B or one value; a path; degrees; a scale
    std::string skyImage, skyRotation, skyIntensity;
};

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

nlohmann::json meanRgb(const Image& image, const Image* mask) {
    double sum[3] = {0, 0, 0};
    size_t count = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            if (mask && !(mask->at(x, y) > 0.5f)) continue;
            for (int c = 0; c < 3; ++c) sum[c] += image.at(x, y, c);
            ++count;
        }
    if (count == 0) return {0.0, 0.0, 0.0};
    return {sum[0] / count, sum[1] / count, sum[2] / count};
}

// Linear EXR and its sRGB PNG preview beside it.
void writeWithPreview(const Image& image, const std::filesystem::path& exrPath) {
    writeExr(image, exrPath.string());
    std::filesystem::path png = exrPath;
    png.replace_extension(".png");
    writePngSrgb(image, png.string());
}

std::string fileSafe(std::string name) {
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    return name.empty() ? "mesh" : name;
}

void runReference(const ReferenceOptions& o) {
    const auto totalStart = Clock::now();
    PathTracerSettings settings;
    settings.samplesPerPixel = o.spp;
    settings.path.maxBounces = o.maxBounces;
    settings.path.rouletteStart = o.rouletteStart;
    settings.seed = o.seed;
    settings.quiet = o.quiet;
    if (o.filter == "tent") settings.filter = PixelFilter::Tent;
    else if (o.filter == "box") settings.filter = PixelFilter::Box;
    else throw SettingsError("filter: '" + o.filter + "' is not one of tent, box");
    settings.validate();
    const bool onGpu = cuda::resolveDevice(cuda::parseDeviceChoice(o.device), std::cerr);
    PathTracerSettings lightmapSettings = settings;
    if (o.lightmapSpp < 0) throw SettingsError("lightmap-spp: " + std::to_string(o.lightmapSpp) + " is negative");
    if (o.lightmapSpp > 0) lightmapSettings.samplesPerPixel = o.lightmapSpp;
    LightmapSettings lightmap;
    lightmap.width = lightmap.height = o.lightmapRes;
    lightmap.subsamplesPerAxis = o.lightmapSubsamples;
    lightmap.atlasPerMesh = o.lightmapPerMesh;
    if (!o.atlasFile.empty()) lightmap.atlases = readAtlasFile(o.atlasFile);
    if (!o.noLightmap) lightmap.validate();
    if (o.width < 0 || o.height < 0 || o.width > 16384 || o.height > 16384)
        throw SettingsError("width/height: " + std::to_string(o.width) + " x " + std::to_string(o.height) +
                            " is outside 1..16384");
    if (o.noRender && o.noLightmap) throw SettingsError("reference: --no-render and --no-lightmap leave nothing to do");

    nlohmann::json timings;
    auto t = Clock::now();
    LoadOptions load;
    load.strict = o.strict;
    Scene scene = loadGltf(o.scene, load);
    {
        BakeSettings parsed;  // the one parser of a sky: the bake settings'
        for (const auto& [name, value] : {std::pair<const char*, const std::string&>{"sky", o.sky},
                                          {"sky-image", o.skyImage},
                                          {"sky-rotation", o.skyRotation},
                                          {"sky-intensity", o.skyIntensity}})
            if (!value.empty()) applySetting(bakeSettingsTable(), parsed, name, value);
        applySkySettings(parsed, scene);
    }
    timings["load"] = secondsSince(t);
    if (!o.noLightmap) checkAtlasGroups(scene, lightmap);  // before a render that may take minutes
    Diagnostics diagnostics(o.strict);

    t = Clock::now();
    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = Bvh::build(triangles);
    timings["bvh_build"] = secondsSince(t);
    t = Clock::now();
    const TraceScene traceScene = TraceScene::build(scene, triangles);
    timings["trace_scene"] = secondsSince(t);
    if (traceScene.emitters.empty() && traceScene.lights.empty() && !scene.sky.present())
        diagnostics.warn(o.scene + ": the scene has no lights, no emissive surfaces and no sky: the reference is black");

    const std::filesystem::path outDir =
        o.output.empty() ? std::filesystem::path("output") / scene.name / "reference" : std::filesystem::path(o.output);
    std::filesystem::create_directories(outDir);

    nlohmann::json summary;
    summary["scene"] = o.scene;
    summary["triangles"] = triangles.meshIndex.size();
    summary["punctual_lights"] = traceScene.lights.size();
    summary["emissive_triangles"] = traceScene.emitters.size();
    summary["threads"] = tbb::info::default_concurrency();
    summary["bvh"] = {{"nodes", bvh.nodes.size()}, {"memory_bytes", bvh.memoryBytes()}};
    nlohmann::json s;
    s["spp"] = settings.samplesPerPixel;
    s["lightmap_spp"] = lightmapSettings.samplesPerPixel;
    s["max_bounces"] = settings.path.maxBounces;
    s["roulette_start"] = settings.path.rouletteStart;
    s["filter"] = o.filter;
    s["seed"] = settings.seed;
    s["device"] = onGpu ? "cuda" : "cpu";

    if (!o.noRender) {
        Camera camera;
        if (scene.cameras.empty()) {
            camera = defaultCamera(scene.bounds(), o.width > 0 && o.height > 0 ? float(o.width) / o.height : 1.0f);
        } else {
            if (o.camera < 0 || static_cast<size_t>(o.camera) >= scene.cameras.size())
                throw SettingsError("camera: index " + std::to_string(o.camera) + " but the scene has " +
                                    std::to_string(scene.cameras.size()) + " camera(s)");
            camera = scene.cameras[static_cast<size_t>(o.camera)];
        }
        const float aspect = camera.aspectRatio > 0.0f ? camera.aspectRatio : 1.0f;
        int width = o.width, height = o.height;
        if (width == 0 && height == 0) width = 256;
        if (width == 0) width = std::max(1, static_cast<int>(std::lround(height * aspect)));
        if (height == 0) height = std::max(1, static_cast<int>(std::lround(width / aspect)));
        const CameraModel model = makeCameraModel(camera, width, height);
        const TraceResult r = onGpu ? cuda::renderCameraCuda(traceScene, bvh, model, settings)
                                    : renderCamera(traceScene, bvh, model, settings);
        timings["render"] = r.seconds;
        t = Clock::now();
        writeWithPreview(r.beauty, outDir / "beauty.exr");
        writeWithPreview(r.direct, outDir / "direct.exr");
        writeWithPreview(r.indirect, outDir / "indirect.exr");
        writeWithPreview(r.albedo, outDir / "albedo.exr");
        timings["render_write"] = secondsSince(t);
        s["width"] = width;
        s["height"] = height;
        s["camera"] = camera.name.empty() ? "default" : camera.name;
        summary["render"] = {{"files", {"beauty.exr", "direct.exr", "indirect.exr", "albedo.exr"}},
                             {"paths", r.paths},
                             {"paths_per_second", r.seconds > 0 ? r.paths / r.seconds : 0.0},
                             {"non_finite_samples", r.nonFiniteSamples},
                             {"mean_rgb", meanRgb(r.beauty, nullptr)}};
    }

    if (!o.noLightmap) {
        s["lightmap_res"] = o.lightmapRes;
        s["lightmap_subsamples"] = lightmap.subsamplesPerAxis;
        t = Clock::now();
        const std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, lightmap, diagnostics);
        timings["lightmap_receivers"] = secondsSince(t);
        if (atlases.empty())
            diagnostics.warn(o.scene + ": no mesh has TEXCOORD_1: no lightmap written");
        nlohmann::json maps = nlohmann::json::array();
        double lightmapSeconds = 0.0;
        for (const LightmapAtlas& atlas : atlases) {
            const TraceResult r = onGpu ? cuda::traceIrradianceCuda(traceScene, bvh, atlas.receivers, lightmapSettings)
                                        : traceIrradiance(traceScene, bvh, atlas.receivers, lightmapSettings);
            lightmapSeconds += r.seconds;
            const std::string stem = atlas.name == "lightmap" ? "lightmap" : "lightmap_" + fileSafe(atlas.name);
            const nlohmann::json mean = meanRgb(r.beauty, &atlas.mask);
            const nlohmann::json meanDirect = meanRgb(r.direct, &atlas.mask);
            Image total = r.beauty, direct = r.direct, indirect = r.indirect;
            for (Image* image : {&total, &direct, &indirect}) dilatePadding(*image, atlas.mask);
            writeWithPreview(total, outDir / (stem + ".exr"));
            writeExr(direct, (outDir / (stem + "_direct.exr")).string());
            writeExr(indirect, (outDir / (stem + "_indirect.exr")).string());
            writeExr(atlas.mask, (outDir / (stem + "_mask.exr")).string());
            nlohmann::json meshes = nlohmann::json::array();
            for (uint32_t m : atlas.meshes) meshes.push_back(scene.meshes[m].name);
            maps.push_back({{"name", atlas.name},
                            {"files", {stem + ".exr", stem + "_direct.exr", stem + "_indirect.exr", stem + "_mask.exr"}},
                            {"meshes", meshes},
                            {"resolution", {atlas.mask.width, atlas.mask.height}},
                            {"covered_texels", atlas.coveredTexels},
                            {"coverage", double(atlas.coveredTexels) / (double(atlas.mask.width) * atlas.mask.height)},
                            {"receiver_samples", atlas.receivers.samples.size()},
                            {"overlapping_probes", atlas.overlappingProbes},
                            {"paths", r.paths},
                            {"paths_per_second", r.seconds > 0 ? r.paths / r.seconds : 0.0},
                            {"non_finite_samples", r.nonFiniteSamples},
                            {"seconds", r.seconds},
                            {"mean_rgb_covered", mean},
                            {"mean_direct_rgb_covered", meanDirect}});
        }
        timings["lightmap"] = lightmapSeconds;
        summary["lightmaps"] = maps;
    }

    summary["settings"] = s;
    timings["total"] = secondsSince(totalStart);
    summary["timings_s"] = timings;
    nlohmann::json warnings = scene.warnings;
    for (const std::string& w : diagnostics.warnings()) warnings.push_back(w);
    summary["warnings"] = warnings;
    const std::string summaryPath = (outDir / "summary.json").string();
    writeAtomically(summaryPath, [&](const std::string& temp) {
        std::ofstream out(temp);
        out << summary.dump(2) << '\n';
        if (!out) throw Error("cannot write " + temp);
    });
    if (!o.quiet) std::fprintf(stderr, "reference: wrote %s (%.2f s)\n", outDir.string().c_str(), secondsSince(totalStart));
}

}  // namespace

void addReferenceCommand(CLI::App& app) {
    auto o = std::make_shared<ReferenceOptions>();
    auto* cmd = app.add_subcommand("reference", "Path-traced ground truth: camera render and lightmap with direct/indirect parts");
    cmd->add_option("scene", o->scene, "glTF scene (.gltf or .glb); default: the Cornell box")->default_val(defaultScenePath());
    cmd->add_option("-o,--output", o->output, "output folder (default: output/<scene name>/reference)");
    cmd->add_option("--spp", o->spp, "samples per pixel (default 64)");
    cmd->add_option("--lightmap-spp", o->lightmapSpp, "samples per lightmap texel (default: --spp)");
    cmd->add_option("--width", o->width, "image width (default 256, or from --height and the camera aspect)");
    cmd->add_option("--height", o->height, "image height (default from the width and the camera aspect)");
    cmd->add_option("--lightmap-res", o->lightmapRes, "lightmap atlas width = height in texels (default 256)");
    cmd->add_option("--lightmap-subsamples", o->lightmapSubsamples,
                    "sub-texel probe grid n x n for coverage (1 = texel centres; default 4)");
    cmd->add_flag("--lightmap-per-mesh", o->lightmapPerMesh, "one lightmap image per mesh instead of one shared atlas");
    cmd->add_option("--atlases", o->atlasFile,
                    "JSON file with atlas groups as a job file's \"atlases\" (or a job file): each group its own "
                    "lightmap_<name>.exr, other meshes in lightmap.exr");
    cmd->add_option("--max-bounces", o->maxBounces, "maximum bounces (default 64, as the Cycles references)");
    cmd->add_option("--roulette-start", o->rouletteStart, "bounce where Russian roulette starts (default 5)");
    cmd->add_option("--filter", o->filter, "pixel filter: tent (ERRATA eq. 11, default) or box (Cycles' 1-pixel box)");
    cmd->add_option("--seed", o->seed, "random seed (default 0)");
    cmd->add_option("--camera", o->camera, "index of the glTF camera to render (default 0)");
    cmd->add_flag("--no-render", o->noRender, "skip the camera render");
    cmd->add_flag("--no-lightmap", o->noLightmap, "skip the lightmap");
    cmd->add_flag("--strict", o->strict, "treat every warning as an error");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
    cmd->add_option("--sky", o->sky, "a uniform sky's radiance R,G,B in W/(m²·sr), seen by every path that leaves the scene (default: none)");
    cmd->add_option("--sky-image", o->skyImage, "an equirectangular HDR image of the sky (.hdr, .exr), mapped as Blender maps it (default: none)");
    cmd->add_option("--sky-rotation", o->skyRotation, "degrees the sky image turns about +Y, counterclockwise seen from above (default 0)");
    cmd->add_option("--sky-intensity", o->skyIntensity, "scale of the sky image's radiance (default 1)");
    cmd->add_option("--device", o->device,
                    "cpu | cuda | auto: auto takes the GPU when one is usable, else says why it runs on the CPU "
                    "(default cpu)");
    cmd->callback([o] { runReference(*o); });
}

}  // namespace vl::cli
