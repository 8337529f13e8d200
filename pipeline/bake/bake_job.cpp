#include "bake/bake_job.h"

#include "bake/output_names.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "export/gltf_export.h"
#include "scene/gltf_loader.h"
#include "voxel/vdb_file.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/resource.h>
#include <unistd.h>

namespace vl {
namespace fs = std::filesystem;

double BakeReport::totalSeconds() const { return vl::totalSeconds(stages); }

namespace {

long peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss * 1024L;
}

std::string safeName(const std::string& name) {
    std::string out;
    for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
    return out.empty() ? "unnamed" : out;
}

// The bake's files, written side by side once all are listed (EXR compression takes a core
// per file; the same bytes as one by one: docs/decisions.md, "Files written side by side").
// Listed in the report in the order they were added.
class StagedFiles {
public:
    StagedFiles(const fs::path& dir, BakeReport& report) : dir_(dir), report_(report) {}
    void exr(const Image& image, const std::string& file) { add(file, [&image](const std::string& p) { writeExr(image, p); }); }
    void png(const Image& image, const std::string& file) {
        add(file, [&image](const std::string& p) { writePngSrgb(image, p); });
    }
    // 8-bit linear RGBA, as stored (a shadowmask).
    void png8(int width, int height, const std::vector<uint8_t>& rgba, const std::string& file) {
        add(file, [width, height, &rgba](const std::string& p) {
            const std::vector<uint8_t> png = encodePng8(width, height, 4, rgba);
            std::ofstream out(p, std::ios::binary);
            out.write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
            if (!out) throw Error("cannot write " + p);
        });
    }
    void add(const std::string& file, std::function<void(const std::string&)> write) {
        writes_.push_back({(dir_ / file).string(), std::move(write)});
        report_.files.push_back(file);
    }
    // Throws the first error any write throws (the caller removes the staging folder).
    void writeAll() {
        tbb::parallel_for(size_t(0), writes_.size(), [&](size_t k) { writes_[k].second(writes_[k].first); });
        writes_.clear();
    }

private:
    fs::path dir_;
    BakeReport& report_;
    std::vector<std::pair<std::string, std::function<void(const std::string&)>>> writes_;
};

// A scene read from a glTF file (not one made in code): what glTF out can write back.
bool isGltfFile(const std::string& path) {
    std::string extension = fs::path(path).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    std::error_code ec;
    return (extension == ".gltf" || extension == ".glb") && fs::is_regular_file(path, ec);
}

nlohmann::json reportJson(const BakeReport& report, const BakeSettings& settings) {
    nlohmann::json json;
    json["scene"] = report.scenePath;
    json["tool_version"] = VOXLIGHT_VERSION;
    json["settings"] = describeBakeSettings(settings);
    json["triangles"] = report.triangles;
    json["voxel_size"] = report.voxelSize;
    json["voxel_size_set_by"] = report.voxelSizeChoice.setBy;
    json["voxels_along_longest_side"] = report.voxelSizeChoice.voxelsAlongLongest;
    if (const FreePaths& f = report.voxelSizeChoice.freePaths; f.rays > 0)
        json["free_paths"] = {{"rays", f.rays}, {"hits", f.hits}, {"mean_metres", f.mean}, {"median_metres", f.median},
                              {"single_sided_backs", f.singleSidedBacks}};
    for (const LightClearance& c : report.voxelSizeChoice.clearances)
        json["light_clearances"].push_back({{"light", c.light}, {"metres", c.metres}});
    json["voxels"] = report.voxels;
    json["mip_levels"] = report.mipLevels;
    json["gather_points"] = report.gatherPoints;
    json["bright_patches"] = report.brightPatches;
    if (report.volumeProbes.x > 0)
        json["irradiance_volume"] = {{"probes", {report.volumeProbes.x, report.volumeProbes.y, report.volumeProbes.z}},
                                     {"spacing_metres", report.volumeSpacing},
                                     {"valid_probes", report.volumeValidProbes}};
    json["gather_visibility"] = toString(report.gatherVisibility.visibility);
    json["gather_visibility_set_by"] = report.gatherVisibility.setBy;
    if (report.lightmapUvs) {
        const LightmapUvReport& uvs = *report.lightmapUvs;
        json["lightmap_uvs"] = {{"meshes", uvs.meshes},          {"charts", uvs.charts},
                                {"charts_grown", uvs.grownCharts}, {"width", uvs.width},
                                {"height", uvs.height},          {"texel_size", uvs.texelSize},
                                {"chart_area_share", uvs.occupancy}, {"max_stretch", uvs.maxStretch},
                                {"mean_stretch", uvs.meanStretch}, {"small_charts", nlohmann::json::array()}};
        if (uvs.askedTexelSize > 0.0) json["lightmap_uvs"]["texel_size_asked"] = uvs.askedTexelSize;
        json["lightmap_uvs"]["merged_across_creases"] = uvs.mergedAcrossCreases;
        // Charts under kSmallChartTexels a side that no neighbour could take, per mesh.
        for (const SmallCharts& small : uvs.smallCharts)
            json["lightmap_uvs"]["small_charts"].push_back({{"mesh", small.mesh}, {"charts", small.charts}});
    }
    if (report.lightmapSeams) {
        // Measured on the total as scene.glb carries it, half a texel inside each chart and on
        // the edge itself (lightmap/lightmap_seams.h).
        const LightmapSeamReport& seams = *report.lightmapSeams;
        json["lightmap_seams"] = {{"edges", seams.after.edges},
                                  {"length_metres", seams.after.length},
                                  {"stitched", seams.stitched},
                                  {"texels_moved", seams.texelsMoved},
                                  {"mean_relative_jump", seams.after.meanRelative},
                                  {"pooled_relative_jump", seams.after.pooledRelative},
                                  {"before_stitching", seams.before.meanRelative},
                                  {"before_stitching_pooled", seams.before.pooledRelative},
                                  {"mean_relative_jump_at_edge", seams.afterAtEdge.meanRelative},
                                  {"before_stitching_at_edge", seams.beforeAtEdge.meanRelative}};
    }
    json["lightmap_texels"] = report.lightmapTexels;
    json["covered_texels"] = report.coveredTexels;
    json["buried_texels"] = report.buriedTexels;
    json["pixels"] = report.pixels;
    json["peak_memory_bytes"] = report.peakMemoryBytes;
    for (const StageTime& s : report.stages) json["stage_seconds"][s.stage] = s.seconds;
    json["total_seconds"] = report.totalSeconds();
    json["warnings"] = report.warnings;
    json["files"] = report.files;
    return json;
}

// Moves every staged file into the output folder (each rename atomic), bake.json last, then
// drops the staging folder: a process killed meanwhile leaves finished files only, and a
// bake.json only beside a whole bake's files.
void publish(const fs::path& staging, const fs::path& target) {
    fs::create_directories(target);
    for (const auto& entry : fs::directory_iterator(staging))
        if (entry.path().filename() != "bake.json") fs::rename(entry.path(), target / entry.path().filename());
    if (fs::exists(staging / "bake.json")) {
        fs::remove(target / "bake.json");  // the old report goes first: it would describe files no longer there
        fs::rename(staging / "bake.json", target / "bake.json");
    }
    fs::remove(staging);
}

// One bake at a time writes an output folder: an exclusive lock on <folder>.lock, which the
// system drops when its holder exits, however it exits (kill -9 included). A second bake of
// the same folder is refused, naming the first's process.
class OutputLock {
public:
    explicit OutputLock(const fs::path& target) : path_(target.string() + kLockSuffix) {
        if (!target.parent_path().empty()) fs::create_directories(target.parent_path());
        // The holder removes the file when it ends: a lock taken on a file already removed
        // (opened just before) is taken again on the file now there.
        for (int attempt = 0;; ++attempt) {
            fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
            if (fd_ < 0) throw Error("cannot open " + path_ + ": " + std::strerror(errno));
            if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
                char holder[32] = {0};
                const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
                ::close(fd_);
                throw Error(target.string() + " is being written by another voxlight bake (process " +
                            (n > 0 ? std::string(holder, size_t(n)) : std::string("?")) +
                            "): wait for it to finish, or bake into another folder");
            }
            struct stat locked{}, named{};
            if (::fstat(fd_, &locked) == 0 && ::stat(path_.c_str(), &named) == 0 && locked.st_ino == named.st_ino &&
                locked.st_dev == named.st_dev)
                break;
            ::close(fd_);
            if (attempt == 10) throw Error("cannot lock " + path_ + ": it keeps being replaced");
        }
        const std::string pid = std::to_string(::getpid());
        // The pid is for the refused bake's message only: a failed write leaves it "?".
        if (::ftruncate(fd_, 0) == 0) (void)!::pwrite(fd_, pid.data(), pid.size(), 0);
    }
    ~OutputLock() {
        ::unlink(path_.c_str());  // while still held: no other bake can have it now
        ::close(fd_);
    }
    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;

private:
    std::string path_;
    int fd_ = -1;
};

// Staging folders of bakes of `target` that died (kill -9, power loss): with the lock held no
// live bake owns one.
void removeDeadStaging(const fs::path& target) {
    const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    const std::string prefix = target.filename().string() + kStagingInfix;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(parent, ec))
        if (entry.path().filename().string().rfind(prefix, 0) == 0) fs::remove_all(entry.path(), ec);
}

void bakeToFolder(const BakeJob& job, BakeReport& report, const fs::path& staging) {
    const BakeSettings& settings = job.settings;
    validateBakeSettings(settings);
    Diagnostics diagnostics(settings.strict);

    const auto loadStart = std::chrono::steady_clock::now();
    Scene scene = loadJobScene(job);
    const ExportSource source = exportSourceOf(scene);
    report.stages.push_back({"load", std::chrono::duration<double>(std::chrono::steady_clock::now() - loadStart).count()});
    report.triangles = scene.triangleCount();
    report.warnings = scene.warnings;

    BakeResult result = bake(std::move(scene), settings, diagnostics);
    report.stages.insert(report.stages.end(), result.stages.begin(), result.stages.end());
    writeBakeFiles(job, result, source, report, staging, diagnostics);
}

}  // namespace

ExportSource exportSourceOf(const Scene& scene) {
    ExportSource source;
    source.sourcePath = scene.sourcePath;
    for (const Mesh& mesh : scene.meshes) source.meshSources.push_back(mesh.source);
    source.viewerSky = scene.sky.meanRadiance();  // glTF holds no sky: viewers get its mean
    source.lights = scene.lights;
    return source;
}

void writeBakeFiles(const BakeJob& job, BakeResult& result, const ExportSource& source, BakeReport& report,
                    const std::string& stagingDir, Diagnostics& diagnostics) {
    const BakeSettings& settings = job.settings;
    const fs::path staging(stagingDir);
    report.voxels = result.voxels.size();
    report.voxelSize = result.voxels.voxelSize;
    report.voxelSizeChoice = result.voxelSizeChoice;
    report.gatherPoints = result.gatherPoints;
    report.brightPatches = result.brightPatches;
    if (!result.volume.empty()) {
        report.volumeProbes = result.volume.counts;
        report.volumeSpacing = result.volume.spacing.x;
        report.volumeValidProbes = size_t(std::count(result.volume.valid.begin(), result.volume.valid.end(), uint8_t(1)));
    }
    report.gatherVisibility = result.gatherVisibility;
    report.lightmapUvs = result.lightmapUvs;

    const auto writeStart = std::chrono::steady_clock::now();
    if (!result.lightmaps.empty()) {
        std::vector<LightmapSeamReport> seams;
        for (const BakedLightmap& lightmap : result.lightmaps) seams.push_back(lightmap.seams);
        report.lightmapSeams = combineSeamReports(seams);
    }
    StagedFiles files(staging, report);
    std::vector<std::vector<uint8_t>> shadowmasks;  // per lightmap, as scene.glb carries them
    for (const BakedLightmap& lightmap : result.lightmaps)
        shadowmasks.push_back(lightmap.shadowmask.empty() ? std::vector<uint8_t>() : shadowmaskBytes(lightmap.shadowmask));
    for (size_t l = 0; l < result.lightmaps.size(); ++l) {
        const BakedLightmap& lightmap = result.lightmaps[l];
        report.lightmapTexels += lightmap.total.pixels.size() / 3;
        report.coveredTexels += lightmap.coveredTexels;
        report.buriedTexels += lightmap.buriedTexels;
        const std::string stem = safeName(lightmap.name);
        files.exr(lightmap.total, stem + ".exr");
        files.exr(lightmap.direct, stem + "_direct.exr");
        files.exr(lightmap.indirect, stem + "_indirect.exr");
        files.exr(lightmap.mask, stem + "_mask.exr");
        files.png(lightmap.total, stem + ".png");
        if (!shadowmasks[l].empty())
            files.png8(lightmap.shadowmask.width, lightmap.shadowmask.height, shadowmasks[l], stem + "_shadowmask.png");
    }
    for (size_t c = 0; c < result.images.size(); ++c) {
        const BakedImage& image = result.images[c];
        report.pixels += image.beauty.pixels.size() / 3;
        const std::string stem = result.images.size() == 1 ? "image" : "image_" + std::to_string(c) + "_" + safeName(image.camera);
        files.exr(image.beauty, stem + ".exr");
        files.exr(image.direct, stem + "_direct.exr");
        files.exr(image.indirect, stem + "_indirect.exr");
        files.exr(image.albedo, stem + "_albedo.exr");
        files.png(image.beauty, stem + ".png");
        if (!image.lightmapped.empty()) {
            files.exr(image.lightmapped, stem + "_lightmapped.exr");
            files.png(image.lightmapped, stem + "_lightmapped.png");
        }
    }
    if (settings.outputs.grids) {
        result.voxels.sourceScene = job.scenePath;
        result.voxels.settings = describeBakeSettings(settings);
        result.mips.addParentLevels();  // a bake that gathered by rays built level 0 alone
        files.add("grids.vdb", [&](const std::string& p) { writeVoxelFile(result.voxels, p, mipGridsForFile(result.mips)); });
    }
    report.mipLevels = static_cast<size_t>(result.mips.levelCount());
    if (settings.outputs.gltf && isGltfFile(source.sourcePath))
        files.add("scene.glb", [&](const std::string& p) {
            std::vector<ExportedLightmap> lightmaps;
            for (size_t l = 0; l < result.lightmaps.size(); ++l) {
                const BakedLightmap& lightmap = result.lightmaps[l];
                lightmaps.push_back({lightmap.name, lightmap.meshes, encodeRgbm(lightmap.total), shadowmasks[l]});
            }
            std::optional<ExportedIrradianceVolume> volume;
            if (!result.volume.empty()) volume = encodeIrradianceVolume(result.volume);
            writeLightmappedGlb(source.sourcePath, source.meshSources, result.generatedLayouts, lightmaps,
                                job.addedCameras, p, diagnostics, source.viewerSky, job.addedLights, settings.lightBake,
                                source.lights, volume ? &*volume : nullptr);
        });
    files.writeAll();
    report.stages.push_back({"write", std::chrono::duration<double>(std::chrono::steady_clock::now() - writeStart).count()});
    report.warnings.insert(report.warnings.end(), diagnostics.warnings().begin(), diagnostics.warnings().end());
    report.peakMemoryBytes = std::max(report.peakMemoryBytes, peakResidentBytes());
    report.files.push_back("bake.json");
    writeAtomically((staging / "bake.json").string(), [&](const std::string& temp) {
        std::ofstream out(temp);
        out << reportJson(report, settings).dump(2) << '\n';
        if (!out) throw Error("cannot write " + temp);
    });
}

BakeReport publishBake(const BakeJob& job, const std::function<void(BakeReport&, const std::string&)>& write) {
    BakeReport report;
    report.scenePath = job.scenePath;
    report.outputDir = job.outputDir;
    const fs::path target(job.outputDir);
    const fs::path staging = target.parent_path() / (target.filename().string() + kStagingInfix + std::to_string(getpid()));
    try {
        const OutputLock lock(target);
        removeDeadStaging(target);
        fs::create_directories(staging);
        write(report, staging.string());
        publish(staging, target);
        report.ok = true;
    } catch (const std::exception& e) {
        report.error = e.what();
        report.files.clear();
        std::error_code ignored;
        fs::remove_all(staging, ignored);
    }
    report.peakMemoryBytes = std::max(report.peakMemoryBytes, peakResidentBytes());
    return report;
}

BakeReport runBake(const BakeJob& job) {
    return publishBake(job, [&](BakeReport& report, const std::string& staging) { bakeToFolder(job, report, staging); });
}

void printBakeSummary(const std::vector<BakeReport>& reports) {
    std::fprintf(stderr, "\n%-28s %-6s %9s %10s %10s %9s %8s  %s\n", "scene", "status", "voxels", "texels", "pixels",
                 "seconds", "peak MB", "output");
    for (const BakeReport& r : reports) {
        const std::string name = fs::path(r.scenePath).filename().string();
        std::fprintf(stderr, "%-28s %-6s %9zu %10zu %10zu %9.2f %8.0f  %s\n", name.c_str(), r.ok ? "ok" : "FAILED",
                     r.voxels, r.coveredTexels, r.pixels, r.totalSeconds(), r.peakMemoryBytes / 1048576.0,
                     r.ok ? r.outputDir.c_str() : r.error.c_str());
    }
}

void addJobLightsAndCameras(const BakeJob& job, Scene& scene) {
    // A job file places them in world space; the scene works in its local frame (scene.h).
    const glm::dmat3 toLocalAxes = glm::transpose(scene.frame);
    const auto toLocal = [&](const vec3& world) { return vec3(toLocalAxes * (glm::dvec3(world) - scene.origin)); };
    const auto turn = [&](const vec3& direction) { return vec3(toLocalAxes * glm::dvec3(direction)); };
    for (Light light : job.addedLights) {
        light.position = toLocal(light.position);
        light.direction = turn(light.direction);
        scene.lights.push_back(light);
    }
    for (Camera camera : job.addedCameras) {
        camera.position = toLocal(camera.position);
        camera.forward = turn(camera.forward);
        camera.up = turn(camera.up);
        scene.cameras.push_back(camera);
    }
    applySkySettings(job.settings, scene);
}

Scene loadJobScene(const BakeJob& job) {
    LoadOptions options;
    options.strict = job.settings.strict;
    options.filesOutsideScene = job.settings.filesOutsideScene;
    Scene scene = loadGltf(job.scenePath, options);
    if (job.settings.lambertMaterials)
        for (Material& material : scene.materials) {
            material.metallic = 0.0f;
            material.transmission = 0.0f;
        }
    addJobLightsAndCameras(job, scene);
    resolveLightBake(scene, job.settings.lightBake);
    return scene;
}

}  // namespace vl
