#include "cluster/plan.h"

#include "bake/output_names.h"
#include "core/error.h"
#include "scene/gltf_loader.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <sys/stat.h>

namespace vl::cluster {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kPlanVersion = 1;

json sceneUnitsJson(const SceneUnits& units) {
    json atlases = json::array();
    for (const SceneUnits::Atlas& atlas : units.atlases) atlases.push_back({{"name", atlas.name}, {"bands", atlas.bands}});
    return {{"atlases", atlases}, {"cameras", units.cameras}};
}

// The files a glTF or GLB points at through its buffers' and images' uris (data: uris aside),
// resolved against its folder; nothing for a file that does not parse (its bake says why).
std::vector<fs::path> referencedFiles(const std::string& scenePath) {
    std::vector<fs::path> files;
    std::ifstream in(scenePath, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (text.size() >= 20 && text.compare(0, 4, "glTF") == 0) {  // GLB: the JSON chunk first
        uint32_t length = 0;
        std::memcpy(&length, text.data() + 12, 4);
        text = text.substr(20, std::min<size_t>(length, text.size() - 20));
    }
    const json gltf = json::parse(text, nullptr, false);
    if (gltf.is_discarded() || !gltf.is_object()) return files;
    for (const char* key : {"buffers", "images"})
        if (gltf.contains(key) && gltf[key].is_array())
            for (const json& item : gltf[key])
                if (item.is_object() && item.contains("uri") && item["uri"].is_string()) {
                    const std::string uri = item["uri"].get<std::string>();
                    if (uri.rfind("data:", 0) != 0) files.push_back(fs::absolute(scenePath).parent_path() / percentDecoded(uri));
                }
    return files;
}

}  // namespace

std::string workFolder(const std::string& outputRoot) {
    return (fs::absolute(outputRoot) / kClusterWorkFolder).lexically_normal().string();
}

std::string sceneWorkFolder(const std::string& workDir, size_t scene) {
    return (fs::path(workDir) / ("scene-" + std::to_string(scene))).string();
}

void writePlan(const ClusterPlan& plan) {
    json j;
    j["version"] = kPlanVersion;
    j["tool_version"] = VOXLIGHT_VERSION;
    j["command"] = {{"inputs", plan.command.inputs},
                    {"output", plan.command.output},
                    {"settings", plan.command.settings},
                    {"strict", plan.command.strict}};
    j["work"] = plan.workDir;
    j["voxlight"] = plan.voxlight;
    j["chdir"] = plan.chdir;
    j["scenes"] = json::array();
    for (const ClusterPlan::Scene& s : plan.scenes)
        j["scenes"].push_back({{"scene", s.scenePath}, {"output", s.outputDir}, {"fingerprint", s.fingerprint},
                               {"units", sceneUnitsJson(s.units)}, {"plan_error", s.planError}});
    j["slurm"] = {{"voxel_job", plan.voxelJob},       {"voxel_tasks", plan.voxelTasks},
                  {"receiver_jobs", plan.receiverJobs}, {"receiver_tasks", plan.receiverTasks},
                  {"merge_job", plan.mergeJob}};
    fs::create_directories(plan.workDir);
    const fs::path path = fs::path(plan.workDir) / kPlanFile;
    const fs::path temp = path.string() + ".tmp";
    {
        std::ofstream out(temp);
        out << j.dump(2) << '\n';
        if (!out) throw Error("cannot write " + temp.string());
    }
    fs::rename(temp, path);
}

ClusterPlan readPlan(const std::string& workDir) {
    const fs::path path = fs::path(workDir) / kPlanFile;
    std::ifstream in(path);
    if (!in) throw InputError(path.string() + ": no cluster bake was submitted into this folder");
    try {
        json j;
        in >> j;
        if (j.at("version").get<int>() != kPlanVersion) throw InputError("version");
        ClusterPlan plan;
        const json& c = j.at("command");
        plan.command.inputs = c.at("inputs").get<std::vector<std::string>>();
        plan.command.output = c.at("output").get<std::string>();
        plan.command.settings = c.at("settings").get<std::vector<std::pair<std::string, std::string>>>();
        plan.command.strict = c.at("strict").get<bool>();
        plan.workDir = j.at("work").get<std::string>();
        plan.voxlight = j.at("voxlight").get<std::string>();
        plan.chdir = j.at("chdir").get<std::string>();
        for (const json& s : j.at("scenes")) {
            ClusterPlan::Scene scene;
            scene.scenePath = s.at("scene").get<std::string>();
            scene.outputDir = s.at("output").get<std::string>();
            scene.fingerprint = s.at("fingerprint").get<std::string>();
            scene.planError = s.at("plan_error").get<std::string>();
            for (const json& atlas : s.at("units").at("atlases"))
                scene.units.atlases.push_back({atlas.at("name").get<std::string>(), atlas.at("bands").get<int>()});
            scene.units.cameras = s.at("units").at("cameras").get<int>();
            plan.scenes.push_back(scene);
        }
        const json& slurm = j.at("slurm");
        plan.voxelJob = slurm.at("voxel_job").get<std::string>();
        plan.voxelTasks = slurm.at("voxel_tasks").get<std::vector<int>>();
        plan.receiverJobs = slurm.at("receiver_jobs").get<std::vector<std::string>>();
        plan.receiverTasks = slurm.at("receiver_tasks").get<std::vector<std::vector<int>>>();
        plan.mergeJob = slurm.at("merge_job").get<std::string>();
        return plan;
    } catch (const InputError&) {
        throw InputError(path.string() + ": written by another voxlight version; submit the job again");
    } catch (const std::exception& e) {
        throw InputError(path.string() + ": not a cluster bake plan (" + e.what() + ")");
    }
}

std::string fingerprint(const BakeJob& job, const std::vector<std::string>& jobFiles) {
    std::ostringstream text;
    text << VOXLIGHT_VERSION << '\n' << describeBakeSettings(job.settings) << '\n' << job.scenePath << '\n'
         << job.outputDir << '\n' << job.addedLights.size() << ' ' << job.addedCameras.size() << '\n';
    const auto stamp = [&](const fs::path& file) {
        struct stat st {};
        if (::stat(file.c_str(), &st) == 0)
            text << file.string() << ' ' << st.st_size << ' ' << st.st_mtim.tv_sec << '.' << st.st_mtim.tv_nsec << '\n';
    };
    // The scene file, the files it points at (buffers, textures), the sky image, the job files.
    stamp(fs::absolute(job.scenePath));
    for (const fs::path& f : referencedFiles(job.scenePath)) stamp(f);
    if (!job.settings.skyImage.empty()) stamp(fs::absolute(job.settings.skyImage));
    for (const std::string& f : jobFiles) stamp(fs::absolute(f));
    uint64_t hash = 0xcbf29ce484222325ull;
    for (char c : text.str()) hash = (hash ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
    return hex;
}

json readSummary(const std::string& workDir) {
    std::ifstream in(fs::path(workDir) / kSummaryFile);
    if (!in) return nullptr;
    json j;
    try {
        in >> j;
    } catch (const std::exception&) {
        return nullptr;
    }
    return j;
}

void writeSummary(const std::string& workDir, const std::vector<BakeReport>& reports,
                  const std::vector<double>& mergeSeconds) {
    json j;
    j["scenes"] = json::array();
    for (size_t k = 0; k < reports.size(); ++k) {
        const BakeReport& r = reports[k];
        j["scenes"].push_back({{"scene", r.scenePath}, {"output", r.outputDir}, {"ok", r.ok}, {"error", r.error},
                               {"seconds", r.totalSeconds()}, {"merge_seconds", mergeSeconds.at(k)}});
    }
    const fs::path path = fs::path(workDir) / kSummaryFile;
    const fs::path temp = path.string() + ".tmp";
    {
        std::ofstream out(temp);
        out << j.dump(2) << '\n';
        if (!out) throw Error("cannot write " + temp.string());
    }
    fs::rename(temp, path);
}

}  // namespace vl::cluster
