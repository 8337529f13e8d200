#include "bake/bake_job.h"

#include "bake/dilate.h"
#include "bake/receivers.h"
#include "bake/shade_receivers.h"
#include "cone/bounces.h"
#include "cone/radiance_mips.h"
#include "core/atomic_file.h"
#include "core/diagnostics.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "lighting/lighting.h"
#include "scene/gltf_loader.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/trace_scene.h"
#include "voxel/vdb_file.h"
#include "voxel/voxelize.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sys/resource.h>
#include <unistd.h>

namespace vl {
namespace fs = std::filesystem;

double BakeReport::totalSeconds() const {
    double total = 0.0;
    for (const StageTime& s : stages) total += s.seconds;
    return total;
}

namespace {

long peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss * 1024L;
}

double availableMemoryBytes() {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    double kib = 0.0;
    std::string unit;
    while (meminfo >> key >> kib >> unit)
        if (key == "MemAvailable:") return kib * 1024.0;
    return static_cast<double>(sysconf(_SC_AVPHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

double surfaceArea(const Scene& scene) {
    double area = 0.0;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const vec3& a = mesh.positions[mesh.indices[3 * t]];
            const vec3& b = mesh.positions[mesh.indices[3 * t + 1]];
            const vec3& c = mesh.positions[mesh.indices[3 * t + 2]];
            area += 0.5 * glm::length(glm::cross(b - a, c - a));
        }
    return area;
}

std::string gib(double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f GiB", bytes / (1024.0 * 1024.0 * 1024.0));
    return text;
}

// Times a stage and records it in the report.
template <typename F>
auto stage(BakeReport& report, const std::string& name, F&& work) {
    const auto start = std::chrono::steady_clock::now();
    struct Record {
        BakeReport& report;
        const std::string& name;
        std::chrono::steady_clock::time_point start;
        ~Record() {
            report.stages.push_back(
                {name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
        }
    } record{report, name, start};
    return work();
}

Image sumRgb(const Image& a, const Image& b) {
    Image out = a;
    for (size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] += b.pixels[i];
    return out;
}

// Writes a linear EXR and records its name.
void writeLinear(const Image& image, const fs::path& dir, const std::string& file, BakeReport& report) {
    writeExr(image, (dir / file).string());
    report.files.push_back(file);
}

void writePreview(const Image& image, const fs::path& dir, const std::string& file, BakeReport& report) {
    writePngSrgb(image, (dir / file).string());
    report.files.push_back(file);
}

std::string safeName(const std::string& name) {
    std::string out;
    for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
    return out.empty() ? "unnamed" : out;
}

nlohmann::json reportJson(const BakeReport& report, const BakeSettings& settings) {
    nlohmann::json json;
    json["scene"] = report.scenePath;
    json["tool_version"] = VOXLIGHT_VERSION;
    json["settings"] = describeBakeSettings(settings);
    json["triangles"] = report.triangles;
    json["voxel_size"] = report.voxelSize;
    json["voxels"] = report.voxels;
    json["mip_levels"] = report.mipLevels;
    json["lightmap_texels"] = report.lightmapTexels;
    json["covered_texels"] = report.coveredTexels;
    json["pixels"] = report.pixels;
    json["peak_memory_bytes"] = peakResidentBytes();
    for (const StageTime& s : report.stages) json["stage_seconds"][s.stage] = s.seconds;
    json["total_seconds"] = report.totalSeconds();
    json["warnings"] = report.warnings;
    json["files"] = report.files;
    return json;
}

// Moves every file of the staging folder into the output folder (each rename atomic) and
// removes the staging folder.
void publish(const fs::path& staging, const fs::path& target) {
    fs::create_directories(target);
    for (const auto& entry : fs::directory_iterator(staging)) fs::rename(entry.path(), target / entry.path().filename());
    fs::remove(staging);
}

void bakeScene(const BakeJob& job, BakeReport& report, const fs::path& staging) {
    const BakeSettings& settings = job.settings;
    validateBakeSettings(settings);
    Diagnostics diagnostics(settings.strict);

    Scene scene = stage(report, "load", [&] {
        LoadOptions options;
        options.strict = settings.strict;
        return loadGltf(job.scenePath, options);
    });
    for (const std::string& w : scene.warnings) report.warnings.push_back(w);
    for (const Light& light : job.addedLights) scene.lights.push_back(light);
    report.triangles = scene.triangleCount();
    if (scene.lights.empty() && !scene.hasEmitters()) {
        const std::string message = job.scenePath + ": the scene has no lights and no emissive materials: the bake is black";
        diagnostics.warn(message);
        report.warnings.push_back(message);
    }

    // Everything that can be refused is refused here, before the first expensive stage.
    const double voxelSize = voxelSizeFor(scene, settings.voxel);
    checkMemoryBudget(scene, settings, voxelSize);
    for (const auto& [name, k] : settings.lighting.lightAttenuation) {
        (void)k;
        bool found = false;
        for (const Light& light : scene.lights) found = found || light.name == name;
        if (!found) throw SettingsError(job.scenePath + ": attenuation is set for light '" + name + "', which the scene lacks");
    }

    VoxelScene voxels = stage(report, "voxelize", [&] {
        Progress progress("voxelize", scene.triangleCount(), settings.quiet);
        return voxelize(scene, settings.voxel, &progress);
    });
    report.voxels = voxels.size();
    report.voxelSize = voxels.voxelSize;

    stage(report, "voxel light", [&] {
        Progress progress("voxel light", voxels.size(), settings.quiet);
        lightVoxels(scene, voxels, settings.lighting, &progress);
        return 0;
    });
    stage(report, "bounces", [&] {
        propagateBounces(voxels, settings.cone, settings.bounces);
        return 0;
    });
    const RadianceMips mips = stage(report, "mips", [&] { return buildRadianceMips(voxels); });
    report.mipLevels = static_cast<size_t>(mips.levelCount());
    const MipView mipView = mips.view();

    const SceneTriangles triangles = gatherTriangles(scene);
    const Bvh bvh = stage(report, "bvh", [&] { return Bvh::build(triangles); });
    const TraceScene traceScene = TraceScene::build(scene, triangles);
    const TraceSceneView sceneView = traceScene.view();
    const BvhView bvhView = bvh.view();

    if (settings.outputs.lightmaps) {
        stage(report, "lightmaps", [&] {
            std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, settings.lightmap, diagnostics);
            for (LightmapAtlas& atlas : atlases) {
                report.lightmapTexels += atlas.receivers.elementCount();
                report.coveredTexels += atlas.coveredTexels;
                Progress progress("lightmap " + atlas.name, atlas.receivers.elementCount(), settings.quiet);
                ReceiverLighting lit = shadeReceivers(atlas.receivers, sceneView, bvhView, &mipView, settings.cone,
                                                      settings.direct, &progress);
                progress.finish();
                Image total = sumRgb(lit.direct, lit.indirect);
                for (Image* image : {&total, &lit.direct, &lit.indirect}) dilatePadding(*image, atlas.mask);
                const std::string stem = safeName(atlas.name);
                writeLinear(total, staging, stem + ".exr", report);
                writeLinear(lit.direct, staging, stem + "_direct.exr", report);
                writeLinear(lit.indirect, staging, stem + "_indirect.exr", report);
                writeLinear(atlas.mask, staging, stem + "_mask.exr", report);
                writePreview(total, staging, stem + ".png", report);
            }
            return 0;
        });
    }

    if (settings.outputs.images) {
        stage(report, "images", [&] {
            std::vector<Camera> cameras = scene.cameras;
            const float aspect = static_cast<float>(settings.imageWidth) / static_cast<float>(settings.imageHeight);
            if (cameras.empty()) cameras.push_back(defaultCamera(scene.bounds(), aspect));
            for (size_t c = 0; c < cameras.size(); ++c) {
                const CameraModel model = makeCameraModel(cameras[c], settings.imageWidth, settings.imageHeight);
                const CameraReceivers receivers = buildCameraReceivers(traceScene, bvh, model, settings.imageSubsamples);
                report.pixels += receivers.receivers.elementCount();
                Progress progress("image", receivers.receivers.elementCount(), settings.quiet);
                const ReceiverLighting lit = shadeReceivers(receivers.receivers, sceneView, bvhView, &mipView,
                                                            settings.cone, settings.direct, &progress);
                progress.finish();
                const Image beauty = sumRgb(sumRgb(receivers.emission, lit.directRadiance), lit.indirectRadiance);
                const std::string stem = cameras.size() == 1 ? "image" : "image_" + std::to_string(c) + "_" + safeName(cameras[c].name);
                writeLinear(beauty, staging, stem + ".exr", report);
                writeLinear(lit.directRadiance, staging, stem + "_direct.exr", report);
                writeLinear(lit.indirectRadiance, staging, stem + "_indirect.exr", report);
                writeLinear(receivers.albedo, staging, stem + "_albedo.exr", report);
                writePreview(beauty, staging, stem + ".png", report);
            }
            return 0;
        });
    }

    if (settings.outputs.grids) {
        stage(report, "write grids", [&] {
            voxels.sourceScene = job.scenePath;
            voxels.settings = describeBakeSettings(settings);
            writeVoxelFile(voxels, (staging / "grids.vdb").string(), mipGridsForFile(mips));
            report.files.push_back("grids.vdb");
            return 0;
        });
    }
    for (const std::string& w : diagnostics.warnings())
        if (std::find(report.warnings.begin(), report.warnings.end(), w) == report.warnings.end())
            report.warnings.push_back(w);
    report.peakMemoryBytes = peakResidentBytes();
    report.files.push_back("bake.json");
    writeAtomically((staging / "bake.json").string(), [&](const std::string& temp) {
        std::ofstream out(temp);
        out << reportJson(report, settings).dump(2) << '\n';
        if (!out) throw Error("cannot write " + temp);
    });
}

}  // namespace

void checkMemoryBudget(const Scene& scene, const BakeSettings& settings, double voxelSize) {
    // A surface crosses about 1 to √3 voxels per h² of area; a voxel costs ~100 bytes of
    // channels, as much again in voxelization fragments, and ~50 in mips. A receiver sample
    // costs ~48 bytes, a texel or pixel ~64 in images.
    const double voxels = 2.0 * surfaceArea(scene) / (voxelSize * voxelSize);
    const double texels = settings.outputs.lightmaps
        ? static_cast<double>(settings.lightmap.width) * settings.lightmap.height *
              (48.0 * settings.lightmap.subsamplesPerAxis * settings.lightmap.subsamplesPerAxis + 64.0)
        : 0.0;
    const double pixels = settings.outputs.images
        ? static_cast<double>(settings.imageWidth) * settings.imageHeight *
              (48.0 * settings.imageSubsamples * settings.imageSubsamples + 64.0 * 8)
        : 0.0;
    const double estimate = voxels * 250.0 + texels + pixels;
    const double available = availableMemoryBytes();
    if (estimate > available)
        throw SettingsError(scene.sourcePath + ": this bake would need about " + gib(estimate) + " of memory (" +
                            std::to_string(static_cast<long long>(voxels)) + " voxels at voxel size " +
                            std::to_string(voxelSize) + " m) but " + gib(available) +
                            " is available: lower resolution, lightmap-res or the image size");
}

BakeReport runBake(const BakeJob& job) {
    BakeReport report;
    report.scenePath = job.scenePath;
    report.outputDir = job.outputDir;
    const fs::path target(job.outputDir);
    const fs::path staging = target.parent_path() / (target.filename().string() + ".partial-" + std::to_string(getpid()));
    try {
        fs::remove_all(staging);
        fs::create_directories(staging);
        bakeScene(job, report, staging);
        publish(staging, target);
        report.ok = true;
    } catch (const std::exception& e) {
        report.error = e.what();
        std::error_code ignored;
        fs::remove_all(staging, ignored);
    }
    return report;
}

}  // namespace vl
