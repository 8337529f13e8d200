#include "cluster/units.h"

#include "cluster/unit_file.h"
#include "cluster/voxel_state.h"
#include "core/error.h"
#include "scene/own_frame.h"
#include "voxel/voxelize.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/resource.h>
#include <unistd.h>

namespace vl::cluster {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kRecordFile = "unit.json";
constexpr const char* kStateFile = "voxel-state.vxu";
constexpr const char* kBandFile = "band.vxu";
constexpr const char* kImageFile = "image.vxu";

std::string hostName() {
    char name[256] = {0};
    if (::gethostname(name, sizeof name - 1) != 0) return "unknown-host";
    return name;
}

std::string slurmJobText() {
    const char* array = std::getenv("SLURM_ARRAY_JOB_ID");
    const char* task = std::getenv("SLURM_ARRAY_TASK_ID");
    if (array && task) return std::string(array) + "_" + task;
    const char* job = std::getenv("SLURM_JOB_ID");
    return job ? job : "";
}

long peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss * 1024L;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double unixSeconds() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

void writeRecord(const fs::path& folder, const UnitRecord& record, double startedAt) {
    const json j = {{"ok", record.ok},
                    {"error", record.error},
                    {"seconds", record.seconds},
                    {"wall_seconds", record.wallSeconds},
                    {"started_at", startedAt},  // Unix time: where the scheduler's gaps show
                    {"ended_at", unixSeconds()},
                    {"host", record.host},
                    {"slurm_job", record.slurmJob},
                    {"peak_memory_bytes", record.peakMemoryBytes}};
    std::ofstream out(folder / kRecordFile);
    out << j.dump(2) << '\n';
    if (!out) throw Error("cannot write " + (folder / kRecordFile).string());
}

// Runs `work` into a staging folder beside sceneWork/folder, records how it went in
// unit.json there and renames the staging folder into place (an older result goes first).
// Whatever `work` throws is recorded, never thrown.
template <typename Work>
UnitRecord runUnit(const std::string& sceneWork, const std::string& folder, Work&& work) {
    UnitRecord record;
    record.host = hostName();
    record.slurmJob = slurmJobText();
    const fs::path target = fs::path(sceneWork) / folder;
    const fs::path staging =
        fs::path(sceneWork) / (folder + ".partial-" + record.host + "-" + std::to_string(::getpid()));
    const auto start = std::chrono::steady_clock::now();
    const double startedAt = unixSeconds();
    try {
        fs::remove_all(staging);
        fs::create_directories(staging);
        work(staging, record);
        record.ok = true;
    } catch (const std::exception& e) {
        record.ok = false;
        record.error = e.what();
    } catch (...) {
        record.ok = false;
        record.error = "the " + folder + " unit failed with an exception that is not an error voxlight knows";
    }
    record.peakMemoryBytes = peakResidentBytes();
    record.wallSeconds = secondsSince(start);
    std::error_code ec;
    fs::create_directories(staging, ec);
    writeRecord(staging, record, startedAt);
    fs::remove_all(target);
    fs::rename(staging, target);
    return record;
}

std::pair<int, int> bandRows(int height, int band, int bands) {
    return {static_cast<int>(int64_t(height) * band / bands), static_cast<int>(int64_t(height) * (band + 1) / bands)};
}

// The voxel unit's state, once its record says it succeeded.
VoxelState finishedVoxelState(const std::string& sceneWork) {
    const fs::path folder = fs::path(sceneWork) / kVoxelFolder;
    const std::optional<UnitRecord> record = readUnitRecord(folder.string());
    if (!record) throw Error("the voxel unit has not finished (" + folder.string() + " holds no result)");
    if (!record->ok) throw Error(record->error);
    return readVoxelState((folder / kStateFile).string());
}

std::vector<float> rows(const Image& image, int rowBegin, int rowEnd) {
    const size_t rowFloats = size_t(image.width) * size_t(image.channels);
    return std::vector<float>(image.pixels.begin() + long(rowFloats * size_t(rowBegin)),
                              image.pixels.begin() + long(rowFloats * size_t(rowEnd)));
}

}  // namespace

int SceneUnits::receiverCount() const {
    int count = cameras;
    for (const Atlas& atlas : atlases) count += atlas.bands;
    return count;
}

ReceiverUnit receiverUnit(const SceneUnits& units, int receiver) {
    ReceiverUnit unit;
    int first = 0;
    for (size_t a = 0; a < units.atlases.size(); ++a) {
        if (receiver < first + units.atlases[a].bands) {
            unit.atlas = static_cast<int>(a);
            unit.band = receiver - first;
            unit.bands = units.atlases[a].bands;
            return unit;
        }
        first += units.atlases[a].bands;
    }
    unit.camera = receiver - first;
    return unit;
}

SceneUnits planSceneUnits(const BakeJob& job, int bands, int cameras) {
    SceneUnits units;
    const BakeSettings& s = job.settings;
    if (!s.outputs.lightmaps && !(s.outputs.images && cameras < 0)) {
        units.cameras = s.outputs.images ? cameras : 0;
        return units;
    }
    Scene scene = loadJobScene(job);
    if (s.outputs.images) units.cameras = cameras >= 0 ? cameras : static_cast<int>(bakeCameras(scene, s).size());
    if (!s.outputs.lightmaps) return units;
    // The atlases as the bake will make them: the scene anchored at its voxel size and given
    // its generated lightmap UVs (sized by lightmap-texel or auto), the same floats as the bake's.
    VoxelSettings voxel = s.voxel;
    if (voxel.ownFrame) turnToOwnFrame(scene);
    voxel.voxelSize = chooseVoxelSize(scene, s).voxelSize;
    const double voxelSize = voxelSizeFor(scene, voxel);
    anchorToVoxelGrid(scene, voxelSize);
    Diagnostics quiet(false, false);
    BakeSettings silent = s;
    silent.quiet = true;
    const GeneratedUvs generated = generateSharedAtlasUvs(scene, silent, voxelSize, quiet);
    for (const LightmapAtlas& atlas : buildLightmapReceivers(scene, generated.lightmap, quiet)) {
        const double texels = double(atlas.receivers.width) * atlas.receivers.height;
        const int wanted = bands > 0 ? bands : static_cast<int>(std::ceil(texels / kTexelsPerBand));
        units.atlases.push_back({atlas.name, std::clamp(wanted, 1, std::max(1, atlas.receivers.height))});
    }
    return units;
}

std::string receiverName(const SceneUnits& units, int receiver) {
    const ReceiverUnit unit = receiverUnit(units, receiver);
    if (unit.atlas >= 0)
        return "atlas '" + units.atlases[size_t(unit.atlas)].name + "' rows " + std::to_string(unit.band) + " of " +
               std::to_string(unit.bands);
    return "camera " + std::to_string(unit.camera);
}

std::string receiverFolder(const SceneUnits& units, int receiver) {
    const ReceiverUnit unit = receiverUnit(units, receiver);
    if (unit.atlas >= 0)
        return "atlas-" + std::to_string(unit.atlas) + "-band-" + std::to_string(unit.band) + "-of-" +
               std::to_string(unit.bands);
    return "camera-" + std::to_string(unit.camera);
}

std::optional<UnitRecord> readUnitRecord(const std::string& unitFolder) {
    std::ifstream in(fs::path(unitFolder) / kRecordFile);
    if (!in) return std::nullopt;
    json j;
    try {
        in >> j;
        UnitRecord record;
        record.ok = j.at("ok").get<bool>();
        record.error = j.at("error").get<std::string>();
        record.seconds = j.at("seconds").get<double>();
        record.wallSeconds = j.value("wall_seconds", record.seconds);
        record.host = j.at("host").get<std::string>();
        record.slurmJob = j.at("slurm_job").get<std::string>();
        record.peakMemoryBytes = j.at("peak_memory_bytes").get<long>();
        return record;
    } catch (const std::exception& e) {
        UnitRecord record;
        record.error = unitFolder + "/unit.json cannot be read: " + e.what();
        return record;
    }
}

UnitRecord recordUnitFailure(const std::string& sceneWork, const std::string& folder, const std::string& error) {
    return runUnit(sceneWork, folder, [&](const fs::path&, UnitRecord&) { throw Error(error); });
}

UnitRecord runVoxelUnit(const BakeJob& job, const std::string& sceneWork) {
    return runUnit(sceneWork, kVoxelFolder, [&](const fs::path& dir, UnitRecord& record) {
        const BakeSettings& settings = job.settings;
        validateBakeSettings(settings);
        Diagnostics diagnostics(settings.strict);
        const auto loadStart = std::chrono::steady_clock::now();
        Scene scene = loadJobScene(job);
        const double loadSeconds = secondsSince(loadStart);
        const size_t triangles = scene.triangleCount();
        const std::vector<std::string> sceneWarnings = scene.warnings;
        const VoxelStages stages = bakeVoxelStages(scene, settings, diagnostics);
        writeVoxelState(stages, triangles, sceneWarnings, loadSeconds, diagnostics.warnings(),
                        (dir / kStateFile).string());
        record.seconds = loadSeconds + totalSeconds(stages.result.stages);
    });
}

UnitRecord runReceiverUnit(const BakeJob& job, const std::string& sceneWork, const SceneUnits& units, int receiver) {
    if (receiver < 0 || receiver >= units.receiverCount())
        return recordUnitFailure(sceneWork, "receiver-" + std::to_string(receiver),
                                 "receiver unit " + std::to_string(receiver) + " of a scene with " +
                                     std::to_string(units.receiverCount()));
    return runUnit(sceneWork, receiverFolder(units, receiver), [&](const fs::path& dir, UnitRecord& record) {
        const BakeSettings& settings = job.settings;
        const VoxelState state = finishedVoxelState(sceneWork);
        const auto start = std::chrono::steady_clock::now();
        const Scene scene = receiverScene(loadJobScene(job), state);
        const ReceiverScene tracing(scene, settings.lightTrees);
        const IndirectLight light = restoreIndirectLight(state, tracing, settings);
        const ReceiverGather gather = bakeReceiverGather(tracing, light, settings, state.onGpu);
        UnitFile file;
        const ReceiverUnit unit = receiverUnit(units, receiver);
        if (unit.atlas >= 0) {
            Diagnostics ignored(false, false);  // the merge reports the atlases' warnings once
            const std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, state.lightmap, ignored);
            const std::string& planned = units.atlases[size_t(unit.atlas)].name;
            if (atlases.size() != units.atlases.size() || atlases[size_t(unit.atlas)].name != planned)
                throw InputError(job.scenePath + ": its lightmap atlases are not the " +
                                 std::to_string(units.atlases.size()) + " planned (atlas " +
                                 std::to_string(unit.atlas) + " '" + planned +
                                 "'): the scene or its settings changed since the job was submitted");
            const LightmapAtlas& atlas = atlases[size_t(unit.atlas)];
            const auto [rowBegin, rowEnd] = bandRows(atlas.receivers.height, unit.band, unit.bands);
            const ReceiverLighting lit = gather.atlasRows(atlas, rowBegin, rowEnd);
            file.header = {{"kind", "lightmap band"},
                           {"atlas", atlas.name},
                           {"width", atlas.receivers.width},
                           {"height", atlas.receivers.height},
                           {"row_begin", rowBegin},
                           {"row_end", rowEnd}};
            file.add(rows(lit.direct, rowBegin, rowEnd));
            file.add(rows(lit.indirect, rowBegin, rowEnd));
            file.add(lit.open.pixels.empty() ? std::vector<float>() : rows(lit.open, rowBegin, rowEnd));
            file.add(lit.shadowmask.empty() ? std::vector<float>() : rows(lit.shadowmask, rowBegin, rowEnd));
            writeUnitFile(file, (dir / kBandFile).string());
        } else {
            const std::vector<Camera> cameras = bakeCameras(scene, settings);
            const size_t c = size_t(unit.camera);
            if (c >= cameras.size())
                throw InputError(job.scenePath + ": has " + std::to_string(cameras.size()) + " cameras, not " +
                                 std::to_string(c + 1) + ": the scene changed since the job was submitted");
            const BakedImage image = bakeCameraImage(gather, tracing, cameras[c], settings);
            file.header = {{"kind", "camera image"},
                           {"camera", image.camera},
                           {"width", image.beauty.width},
                           {"height", image.beauty.height}};
            for (const Image* i : {&image.beauty, &image.direct, &image.indirect, &image.albedo}) file.add(i->pixels);
            writeUnitFile(file, (dir / kImageFile).string());
        }
        record.seconds = secondsSince(start);
    });
}

BakeReport mergeScene(const BakeJob& job, const std::string& sceneWork, const SceneUnits& units) {
    return publishBake(job, [&](BakeReport& report, const std::string& staging) {
        // A failed unit fails the scene with its own error: the voxel unit's first, then the
        // receivers' in the order a local bake shades them.
        std::vector<UnitRecord> records;
        for (int r = -1; r < units.receiverCount(); ++r) {
            const std::string name = r < 0 ? "voxel" : receiverName(units, r);
            const fs::path folder = fs::path(sceneWork) / (r < 0 ? std::string(kVoxelFolder) : receiverFolder(units, r));
            const std::optional<UnitRecord> record = readUnitRecord(folder.string());
            if (!record)
                throw Error("the " + name + " unit left no result in " + folder.string() +
                            " (killed, out of time, or its node failed: see its log)");
            if (!record->ok) throw Error(r < 0 ? record->error : "the " + name + " unit: " + record->error);
            records.push_back(*record);
        }
        VoxelState state = finishedVoxelState(sceneWork);
        report.stages.push_back({"load", state.loadSeconds});
        report.triangles = state.triangles;
        report.warnings = state.sceneWarnings;
        Diagnostics diagnostics(job.settings.strict, false);
        for (const std::string& warning : state.stageWarnings) diagnostics.warn(warning);

        Scene loaded = loadJobScene(job);
        const ExportSource source = exportSourceOf(loaded);
        const Scene scene = receiverScene(std::move(loaded), state);
        // The irradiance volume, lit as a receiver unit lights its texels.
        BakeResult volume;
        if (irradianceVolumeSpacing(scene, job.settings) > 0.0) {
            const ReceiverScene tracing(scene, job.settings.lightTrees);
            const IndirectLight light = restoreIndirectLight(state, tracing, job.settings);
            addIrradianceVolume(scene, tracing, bakeReceiverGather(tracing, light, job.settings, state.onGpu),
                                job.settings, volume);
        }
        BakeResult result = std::move(state.result);
        result.volume = std::move(volume.volume);
        report.stages.insert(report.stages.end(), result.stages.begin(), result.stages.end());
        report.stages.insert(report.stages.end(), volume.stages.begin(), volume.stages.end());
        // As the bake left them (writeBakeFiles adds the coarser levels for grids.vdb).
        result.mips = receiverMips(result.voxels, result.gatherVisibility.visibility, state.gathered);

        double lightmapSeconds = 0.0, imageSeconds = 0.0;
        if (job.settings.outputs.lightmaps) {
            const std::vector<LightmapAtlas> atlases = buildLightmapReceivers(scene, state.lightmap, diagnostics);
            if (atlases.size() != units.atlases.size())
                throw InputError(job.scenePath + ": " + std::to_string(atlases.size()) + " lightmap atlases, " +
                                 std::to_string(units.atlases.size()) + " when the job was submitted");
            int receiver = 0;
            for (size_t a = 0; a < atlases.size(); ++a) {
                const LightmapAtlas& atlas = atlases[a];
                Image direct(atlas.receivers.width, atlas.receivers.height, 3);
                Image indirect = direct;
                Image open(atlas.receivers.width, atlas.receivers.height, 1);
                Image shadowmask(atlas.receivers.width, atlas.receivers.height, kShadowmaskChannels);
                bool anyOpen = false;  // the bands say which of their samples are buried
                bool anyMask = false;  // and whether some light has a shadowmask
                for (int band = 0; band < units.atlases[a].bands; ++band, ++receiver) {
                    const std::string path = (fs::path(sceneWork) / receiverFolder(units, receiver) / kBandFile).string();
                    const UnitFile file = readUnitFile(path);
                    const auto [rowBegin, rowEnd] = bandRows(atlas.receivers.height, band, units.atlases[a].bands);
                    const json& h = file.header;
                    if (h.value("atlas", "") != atlas.name || h.value("row_begin", -1) != rowBegin ||
                        h.value("row_end", -1) != rowEnd || h.value("width", -1) != atlas.receivers.width)
                        throw InputError(path + ": not rows " + std::to_string(rowBegin) + "-" + std::to_string(rowEnd) +
                                         " of the scene's atlas '" + atlas.name + "'");
                    const size_t offset = size_t(rowBegin) * size_t(atlas.receivers.width) * 3;
                    const size_t floats = size_t(rowEnd - rowBegin) * size_t(atlas.receivers.width) * 3;
                    const std::vector<float> d = file.take<float>(0, path), i = file.take<float>(1, path),
                                             o = file.take<float>(2, path), s = file.take<float>(3, path);
                    if (d.size() != floats || i.size() != floats || (!o.empty() && o.size() != floats / 3) ||
                        (!s.empty() && s.size() != floats / 3 * size_t(kShadowmaskChannels)))
                        throw InputError(path + ": a band of the wrong size");
                    std::copy(s.begin(), s.end(), shadowmask.pixels.begin() + long(offset / 3 * size_t(kShadowmaskChannels)));
                    anyMask = anyMask || !s.empty();
                    std::copy(d.begin(), d.end(), direct.pixels.begin() + long(offset));
                    std::copy(i.begin(), i.end(), indirect.pixels.begin() + long(offset));
                    std::copy(o.begin(), o.end(), open.pixels.begin() + long(offset / 3));
                    anyOpen = anyOpen || !o.empty();
                    lightmapSeconds += records[size_t(receiver) + 1].seconds;
                }
                result.lightmaps.push_back(finishLightmap(atlas, direct, indirect, anyOpen ? open : Image(), scene,
                                                          job.settings, anyMask ? shadowmask : Image()));
            }
        }
        for (int c = 0; c < units.cameras; ++c) {
            const int r = units.receiverCount() - units.cameras + c;
            const std::string path = (fs::path(sceneWork) / receiverFolder(units, r) / kImageFile).string();
            const UnitFile file = readUnitFile(path);
            const int width = file.header.at("width").get<int>(), height = file.header.at("height").get<int>();
            BakedImage image;
            image.camera = file.header.at("camera").get<std::string>();
            Image* parts[] = {&image.beauty, &image.direct, &image.indirect, &image.albedo};
            for (size_t k = 0; k < 4; ++k) {
                *parts[k] = Image(width, height, 3);
                parts[k]->pixels = file.take<float>(k, path);
                if (parts[k]->pixels.size() != size_t(width) * size_t(height) * 3)
                    throw InputError(path + ": an image of the wrong size");
            }
            result.images.push_back(std::move(image));
            imageSeconds += records[size_t(r) + 1].seconds;
        }
        if (job.settings.outputs.lightmaps) report.stages.push_back({"lightmaps", lightmapSeconds});
        if (units.cameras > 0) report.stages.push_back({"images", imageSeconds});
        // The lightmap-lit images need every atlas finished, so they are made here.
        if (makesLightmapImages(job.settings) && units.cameras > 0) {
            const auto start = std::chrono::steady_clock::now();
            addLightmapImages(scene, ReceiverScene(scene, job.settings.lightTrees), job.settings, result);
            report.stages.push_back({"lightmap image", secondsSince(start)});
        }
        for (const UnitRecord& record : records)
            report.peakMemoryBytes = std::max(report.peakMemoryBytes, record.peakMemoryBytes);
        writeBakeFiles(job, result, source, report, staging, diagnostics);
    });
}

}  // namespace vl::cluster
