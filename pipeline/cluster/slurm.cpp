#include "cluster/slurm.h"

#include "core/error.h"
#include "scene/gltf_loader.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cstring>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <cerrno>
#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace vl::cluster {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kPlanFile = "plan.json";
constexpr int kPlanVersion = 1;

struct ProgramResult {
    int status = -1;  // exit code; -1 when it could not run
    std::string out, err;
};

// Runs a program with arguments (no shell), collecting its standard output and error (both
// drained together, so neither pipe fills while the other is read).
ProgramResult runProgram(const std::vector<std::string>& arguments) {
    int outPipe[2], errPipe[2];
    if (::pipe2(outPipe, O_CLOEXEC) != 0) return {};
    if (::pipe2(errPipe, O_CLOEXEC) != 0) {
        ::close(outPipe[0]);
        ::close(outPipe[1]);
        return {};
    }
    std::vector<char*> argv;
    for (const std::string& a : arguments) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::dup2(outPipe[1], STDOUT_FILENO);
        ::dup2(errPipe[1], STDERR_FILENO);
        ::execvp(argv[0], argv.data());
        ::_exit(127);
    }
    ::close(outPipe[1]);
    ::close(errPipe[1]);
    ProgramResult result;
    if (pid < 0) {
        ::close(outPipe[0]);
        ::close(errPipe[0]);
        return result;
    }
    pollfd fds[2] = {{outPipe[0], POLLIN, 0}, {errPipe[0], POLLIN, 0}};
    std::string* sinks[2] = {&result.out, &result.err};
    for (int open = 2; open > 0;) {
        if (::poll(fds, 2, -1) < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (int k = 0; k < 2; ++k) {
            if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            char buffer[4096];
            const ssize_t n = ::read(fds[k].fd, buffer, sizeof buffer);
            if (n > 0) {
                sinks[k]->append(buffer, size_t(n));
            } else if (n == 0 || errno != EINTR) {
                ::close(fds[k].fd);
                fds[k].fd = -1;
                --open;
            }
        }
    }
    for (const pollfd& f : fds)
        if (f.fd >= 0) ::close(f.fd);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return result;
    result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
}

std::string trimmed(std::string text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    size_t start = 0;
    while (start < text.size() && std::isspace(static_cast<unsigned char>(text[start]))) ++start;
    return text.substr(start);
}

std::string shellQuoted(const std::string& text) {
    std::string out = "'";
    for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

// "0-3,7,9-10": sbatch's array list, runs of consecutive indices as ranges.
std::string listText(const std::vector<int>& values) {
    std::string out;
    for (size_t k = 0; k < values.size();) {
        size_t end = k;
        while (end + 1 < values.size() && values[end + 1] == values[end] + 1) ++end;
        out += (out.empty() ? "" : ",") + std::to_string(values[k]);
        if (end > k) out += "-" + std::to_string(values[end]);
        k = end + 1;
    }
    return out;
}

json sceneUnitsJson(const SceneUnits& units) {
    json atlases = json::array();
    for (const SceneUnits::Atlas& atlas : units.atlases) atlases.push_back({{"name", atlas.name}, {"bands", atlas.bands}});
    return {{"atlases", atlases}, {"cameras", units.cameras}};
}

bool sameUnits(const SceneUnits& a, const SceneUnits& b) {
    if (a.cameras != b.cameras || a.atlases.size() != b.atlases.size()) return false;
    for (size_t k = 0; k < a.atlases.size(); ++k)
        if (a.atlases[k].name != b.atlases[k].name || a.atlases[k].bands != b.atlases[k].bands) return false;
    return true;
}

// The batch script of one kind of unit; `unitArguments` follow `voxlight bake-unit <work>`.
std::string batchScript(const ClusterPlan& plan, const SlurmOptions& options, const std::string& name,
                        const std::string& log, const std::string& unitArguments) {
    std::ostringstream s;
    s << "#!/bin/sh\n";
    s << "#SBATCH --job-name=" << name << "\n";
    s << "#SBATCH --output=" << log << "\n";
    s << "#SBATCH --chdir=" << plan.chdir << "\n";
    if (!options.partition.empty()) s << "#SBATCH --partition=" << options.partition << "\n";
    if (!options.time.empty()) s << "#SBATCH --time=" << options.time << "\n";
    if (options.cpusPerTask > 0) s << "#SBATCH --cpus-per-task=" << options.cpusPerTask << "\n";
    s << "exec " << shellQuoted(plan.voxlight) << " bake-unit " << shellQuoted(plan.workDir) << " " << unitArguments
      << "\n";
    return s.str();
}

// sbatch's job id, or an Error with what sbatch said.
std::string submitScript(const std::string& scriptPath, const std::vector<std::string>& extra) {
    std::vector<std::string> arguments{"sbatch", "--parsable"};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    arguments.push_back(scriptPath);
    const ProgramResult r = runProgram(arguments);
    if (r.status == 127 || r.status == -1)
        throw Error("cannot run sbatch: is Slurm's client installed (Debian: apt-get install slurm-client) and on PATH?");
    const std::string id = trimmed(r.out.substr(0, r.out.find(';')));
    if (r.status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
        throw Error("sbatch refused " + scriptPath + ": " + trimmed(r.err.empty() ? r.out : r.err));
    return id;
}

// This user's jobs in the queue, by id ("123", "123_4"): "STATE|REASON|NODES". Nothing when
// squeue fails (`error` then says why).
std::optional<std::map<std::string, std::string>> queue(std::string* error = nullptr) {
    const ProgramResult r = runProgram({"squeue", "--me", "-h", "-r", "-o", "%i|%T|%r|%N"});
    if (r.status != 0) {
        if (error)
            *error = r.status == 127 || r.status == -1 ? "squeue cannot run (is Slurm's client installed?)"
                                                       : "squeue failed: " + trimmed(r.err.empty() ? r.out : r.err);
        return std::nullopt;
    }
    std::map<std::string, std::string> jobs;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
        const size_t bar = line.find('|');
        if (bar != std::string::npos) jobs[trimmed(line.substr(0, bar))] = line.substr(bar + 1);
    }
    return jobs;
}

// scontrol's "JobState=… Reason=…" of a job that left the queue, while Slurm still keeps it.
std::string finishedJobState(const std::string& id) {
    const ProgramResult r = runProgram({"scontrol", "-o", "show", "job", id});
    if (r.status != 0) {
        // Slurm forgets a finished job after MinJobAge; accounting (where a site keeps it) does not.
        const ProgramResult a = runProgram({"sacct", "-n", "-P", "-X", "-j", id, "-o", "State,ExitCode"});
        const std::string line = trimmed(a.out.substr(0, a.out.find('\n')));
        if (a.status != 0 || line.empty()) return "";
        const size_t bar = line.find('|');
        return line.substr(0, bar) + (bar == std::string::npos ? "" : ", exit code " + line.substr(bar + 1));
    }
    const auto field = [&](const std::string& key) {
        const size_t at = r.out.find(" " + key + "=");
        if (at == std::string::npos) return std::string();
        const size_t begin = at + key.size() + 2;
        return r.out.substr(begin, r.out.find(' ', begin) - begin);
    };
    return field("JobState") + (field("Reason") == "None" ? "" : " (" + field("Reason") + ")") +
           (field("ExitCode").empty() ? "" : ", exit code " + field("ExitCode"));
}

std::string queuedText(const std::string& entry) {
    std::istringstream parts(entry);
    std::string state, reason, nodes;
    std::getline(parts, state, '|');
    std::getline(parts, reason, '|');
    std::getline(parts, nodes, '|');
    std::string text = state == "PENDING" ? "queued" : state == "RUNNING" ? "running" : state;
    if (state == "RUNNING" && !nodes.empty()) text += " on " + nodes;
    if (!reason.empty() && reason != "None") text += " (" + reason + ")";
    return text;
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

bool anyQueued(const ClusterPlan& plan) {
    std::string error;
    const std::optional<std::map<std::string, std::string>> queued = queue(&error);
    if (!queued) throw Error("cannot tell whether the bake submitted into " + plan.workDir + " still runs: " + error);
    const std::map<std::string, std::string>& jobs = *queued;
    std::vector<std::string> ids{plan.voxelJob, plan.mergeJob};
    ids.insert(ids.end(), plan.receiverJobs.begin(), plan.receiverJobs.end());
    for (const auto& [id, entry] : jobs)
        for (const std::string& mine : ids)
            if (!mine.empty() && (id == mine || id.rfind(mine + "_", 0) == 0)) return true;
    return false;
}

}  // namespace

std::string workFolder(const std::string& outputRoot) {
    return (fs::absolute(outputRoot) / ".voxlight-slurm").lexically_normal().string();
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

namespace {

// One submission at a time per work folder: an exclusive lock on <work>/submit.lock, held
// while it plans, submits and releases, and dropped by the system however the command ends.
class SubmitLock {
public:
    explicit SubmitLock(const std::string& workDir) {
        fs::create_directories(workDir);
        const std::string path = (fs::path(workDir) / "submit.lock").string();
        fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd_ < 0 || ::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
            if (fd_ >= 0) ::close(fd_);
            throw Error("another voxlight bake --slurm is submitting into " + workDir + ": wait for it");
        }
    }
    ~SubmitLock() { ::close(fd_); }
    SubmitLock(const SubmitLock&) = delete;
    SubmitLock& operator=(const SubmitLock&) = delete;

private:
    int fd_ = -1;
};

// Slurm's MaxArraySize: array indices must stay below it (1001 unless the site set it).
int maxArraySize() {
    const ProgramResult r = runProgram({"scontrol", "show", "config"});
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);)
        if (line.rfind("MaxArraySize", 0) == 0) {
            const size_t eq = line.find('=');
            if (eq != std::string::npos) return std::atoi(trimmed(line.substr(eq + 1)).c_str());
        }
    return 1001;
}

}  // namespace

std::vector<std::string> submit(ClusterPlan& plan, const SlurmOptions& options) {
    std::vector<std::string> lines;
    std::optional<SubmitLock> lock;
    if (!options.dryRun) lock.emplace(plan.workDir);
    // A job submitted here before: keep its units' results when nothing changed.
    bool same = false;
    if (fs::exists(fs::path(plan.workDir) / kPlanFile)) {
        try {
            const ClusterPlan old = readPlan(plan.workDir);
            if (!options.dryRun && anyQueued(old))
                throw Error("the bake submitted into " + plan.workDir +
                            " earlier is still queued or running (voxlight bake --slurm-status shows it): wait for it, "
                            "or scancel its jobs");
            same = old.scenes.size() == plan.scenes.size();
            for (size_t k = 0; same && k < plan.scenes.size(); ++k)
                same = old.scenes[k].fingerprint == plan.scenes[k].fingerprint &&
                       old.scenes[k].planError == plan.scenes[k].planError &&
                       sameUnits(old.scenes[k].units, plan.scenes[k].units);
        } catch (const InputError&) {
            same = false;
        }
        if (!same) lines.push_back("the job changed since its last submission: every unit runs again");
    }
    // What is done; the rest runs, its old results and staging folders removed first so that
    // neither --slurm-status nor the merge reads a result of the last run as this one's.
    plan.voxelTasks.clear();
    plan.receiverTasks.assign(plan.scenes.size(), {});
    const auto done = [&](const fs::path& folder) {
        const std::optional<UnitRecord> record = same ? readUnitRecord(folder.string()) : std::nullopt;
        return record && record->ok;
    };
    for (size_t k = 0; k < plan.scenes.size(); ++k) {
        const fs::path work = sceneWorkFolder(plan.workDir, k);
        if (!options.dryRun) {
            std::error_code ec;
            if (!same) fs::remove_all(work, ec);
            for (const auto& entry : fs::directory_iterator(work, ec))
                if (entry.path().filename().string().find(".partial-") != std::string::npos)
                    fs::remove_all(entry.path(), ec);
        }
        if (!plan.scenes[k].planError.empty()) continue;  // the merge reports it
        if (!done(work / kVoxelFolder)) plan.voxelTasks.push_back(int(k));
        const SceneUnits& units = plan.scenes[k].units;
        for (int r = 0; r < units.receiverCount(); ++r)
            if (!done(work / receiverFolder(units, r))) plan.receiverTasks[k].push_back(r);
        if (!options.dryRun) {
            std::error_code ec;
            if (!done(work / kVoxelFolder)) fs::remove_all(work / kVoxelFolder, ec);
            for (int r : plan.receiverTasks[k]) fs::remove_all(work / receiverFolder(units, r), ec);
        }
    }
    // Array indices are scene and unit numbers: Slurm refuses any at or past MaxArraySize.
    const int arrayLimit = options.dryRun ? 1001 : maxArraySize();
    if (!plan.voxelTasks.empty() && plan.voxelTasks.back() >= arrayLimit)
        throw SettingsError("the job has " + std::to_string(plan.scenes.size()) + " scenes; Slurm's MaxArraySize (" +
                            std::to_string(arrayLimit) + ") allows array indices below it: split the job");
    for (size_t k = 0; k < plan.scenes.size(); ++k)
        if (!plan.receiverTasks[k].empty() && plan.receiverTasks[k].back() >= arrayLimit)
            throw SettingsError(plan.scenes[k].scenePath + ": " + std::to_string(plan.scenes[k].units.receiverCount()) +
                                " receiver units; Slurm's MaxArraySize (" + std::to_string(arrayLimit) +
                                ") allows array indices below it: lower --lightmap-bands");

    const fs::path logs = fs::path(plan.workDir) / "logs", scripts = fs::path(plan.workDir) / "scripts";
    plan.voxelJob.clear();
    plan.receiverJobs.assign(plan.scenes.size(), "");
    plan.mergeJob.clear();
    if (!options.dryRun) {
        fs::remove(fs::path(plan.workDir) / kSummaryFile);  // the last merge's, not this one's
        fs::create_directories(logs);
        fs::create_directories(scripts);
        // The plan is on disk before any unit can start: every unit reads it first.
        writePlan(plan);
    }
    const std::string limit = options.maxParallel > 0 ? "%" + std::to_string(options.maxParallel) : "";
    const auto writeScript = [&](const std::string& file, const std::string& text) {
        const fs::path path = scripts / file;
        if (options.dryRun) {
            lines.push_back("# " + path.string() + ":");
            std::istringstream in(text);
            for (std::string line; std::getline(in, line);) lines.push_back(line);
            return path.string();
        }
        std::ofstream out(path);
        out << text;
        if (!out) throw Error("cannot write " + path.string());
        fs::permissions(path, fs::perms::owner_exec, fs::perm_options::add);
        return path.string();
    };
    // Jobs are submitted held and released together once all are in: a submission that fails
    // half-way cancels what it submitted and leaves nothing running.
    std::vector<std::string> submitted;
    const auto run = [&](const std::string& script, std::vector<std::string> extra, const std::string& placeholder) {
        std::string command = "sbatch --parsable";
        for (const std::string& e : extra) command += " " + e;
        lines.push_back(command + " " + script);
        if (options.dryRun) return placeholder;
        extra.insert(extra.begin(), "--hold");
        submitted.push_back(submitScript(script, extra));
        return submitted.back();
    };
    try {
        // Voxel units: one array over the scenes whose voxel unit has no result.
        if (!plan.voxelTasks.empty()) {
            const std::string script = writeScript(
                "voxel.sh", batchScript(plan, options, "voxlight-voxel", (logs / "voxel-%a.out").string(),
                                        "--unit voxel --scene \"$SLURM_ARRAY_TASK_ID\""));
            plan.voxelJob = run(script, {"--array=" + listText(plan.voxelTasks) + limit}, "<voxel job>");
        }
        // Receivers: per scene an array after its voxel unit.
        for (size_t k = 0; k < plan.scenes.size(); ++k) {
            if (plan.receiverTasks[k].empty()) continue;
            const std::string scene = std::to_string(k);
            const std::string script = writeScript(
                "scene-" + scene + "-receivers.sh",
                batchScript(plan, options, "voxlight-receivers-" + scene,
                            (logs / ("scene-" + scene + "-receiver-%a.out")).string(),
                            "--unit receiver --scene " + scene + " --index \"$SLURM_ARRAY_TASK_ID\""));
            std::vector<std::string> extra{"--array=" + listText(plan.receiverTasks[k]) + limit};
            if (std::find(plan.voxelTasks.begin(), plan.voxelTasks.end(), int(k)) != plan.voxelTasks.end()) {
                extra.push_back("--dependency=afterok:" + plan.voxelJob + "_" + scene);
                extra.push_back("--kill-on-invalid-dep=yes");
            }
            plan.receiverJobs[k] = run(script, extra, "<scene " + scene + " receivers job>");
        }
        // The merge, after every unit however it ended.
        std::vector<std::string> all = submitted;
        if (options.dryRun) {
            if (!plan.voxelJob.empty()) all.push_back(plan.voxelJob);
            for (const std::string& id : plan.receiverJobs)
                if (!id.empty()) all.push_back(id);
        }
        const std::string script = writeScript(
            "merge.sh", batchScript(plan, options, "voxlight-merge", (logs / "merge.out").string(), "--unit merge"));
        std::vector<std::string> extra;
        if (!all.empty()) {
            std::string dependency = "--dependency=afterany";
            for (const std::string& id : all) dependency += ":" + id;
            extra.push_back(dependency);
        }
        plan.mergeJob = run(script, extra, "<merge job>");
        if (options.dryRun) return lines;
        writePlan(plan);
        std::vector<std::string> release{"scontrol", "release"};
        release.insert(release.end(), submitted.begin(), submitted.end());
        const ProgramResult released = runProgram(release);
        if (released.status != 0)
            throw Error("scontrol release failed: " + trimmed(released.err.empty() ? released.out : released.err));
    } catch (...) {
        if (!submitted.empty()) {
            std::vector<std::string> cancel{"scancel"};
            cancel.insert(cancel.end(), submitted.begin(), submitted.end());
            runProgram(cancel);
            plan.voxelJob.clear();
            plan.receiverJobs.assign(plan.scenes.size(), "");
            plan.mergeJob.clear();
            if (!options.dryRun) writePlan(plan);
        }
        throw;
    }
    size_t units = 0;
    for (const auto& tasks : plan.receiverTasks) units += tasks.size();
    lines.push_back("submitted " + std::to_string(plan.voxelTasks.size()) + " voxel unit(s), " + std::to_string(units) +
                    " receiver unit(s) and the merge (job " + plan.mergeJob + ") of " +
                    std::to_string(plan.scenes.size()) + " scene(s); follow it with: voxlight bake --slurm-status " +
                    fs::path(plan.workDir).parent_path().string());
    return lines;
}

std::vector<std::string> slurmStatus(const std::string& outputRoot) {
    const std::string workDir = workFolder(outputRoot);
    const ClusterPlan plan = readPlan(workDir);
    std::string queueError;
    const std::optional<std::map<std::string, std::string>> queued = queue(&queueError);
    std::vector<std::string> lines;
    if (!queued) lines.push_back("(" + queueError + ": units without a result are shown as unknown)");
    const auto jobState = [&](const std::string& job) -> std::string {
        if (!queued) return "unknown";
        const auto entry = queued->find(job);
        if (entry != queued->end()) return queuedText(entry->second);
        const std::string finished = finishedJobState(job);
        return "failed: no result" + (finished.empty() ? std::string(" (killed, out of time, or its node failed)")
                                                       : std::string(": Slurm says ") + finished);
    };
    std::string voxelFailed;  // the scene's, while its units are listed
    const auto stateOf = [&](const std::string& folder, const std::string& job, bool submitted) -> std::string {
        const std::optional<UnitRecord> record = readUnitRecord(folder);
        if (record) {
            char seconds[32];
            std::snprintf(seconds, sizeof seconds, "%.2f s", record->wallSeconds);
            return record->ok ? "done on " + record->host + " in " + seconds : "failed: " + record->error;
        }
        if (!submitted || job.empty() || job[0] == '_') return "not submitted";
        if (queued && queued->find(job) == queued->end() && !voxelFailed.empty()) return "not run: its voxel unit failed";
        return jobState(job);
    };
    for (size_t k = 0; k < plan.scenes.size(); ++k) {
        const ClusterPlan::Scene& scene = plan.scenes[k];
        const fs::path work = sceneWorkFolder(workDir, k);
        lines.push_back(scene.scenePath + " -> " + scene.outputDir);
        if (!scene.planError.empty()) {
            lines.push_back("  planning failed: " + scene.planError);
            continue;
        }
        const bool voxelSubmitted =
            std::find(plan.voxelTasks.begin(), plan.voxelTasks.end(), int(k)) != plan.voxelTasks.end();
        voxelFailed.clear();
        lines.push_back("  voxel: " + stateOf((work / kVoxelFolder).string(), plan.voxelJob + "_" + std::to_string(k),
                                              voxelSubmitted));
        if (lines.back().rfind("  voxel: failed", 0) == 0) voxelFailed = lines.back();
        for (int r = 0; r < scene.units.receiverCount(); ++r) {
            const auto& tasks = plan.receiverTasks[k];
            const bool submitted = std::find(tasks.begin(), tasks.end(), r) != tasks.end();
            lines.push_back("  " + receiverName(scene.units, r) + ": " +
                            stateOf((work / receiverFolder(scene.units, r)).string(),
                                    plan.receiverJobs[k] + "_" + std::to_string(r), submitted));
        }
    }
    const json summary = readSummary(workDir);
    if (!summary.is_null()) {
        size_t ok = 0, failed = 0;
        for (const json& s : summary.at("scenes")) (s.at("ok").get<bool>() ? ok : failed)++;
        lines.push_back("merge: done: " + std::to_string(ok) + " scene(s) published, " + std::to_string(failed) +
                        " failed");
        for (const json& s : summary.at("scenes"))
            if (!s.at("ok").get<bool>()) lines.push_back("  " + s.at("error").get<std::string>());
    } else {
        lines.push_back("merge: " + (plan.mergeJob.empty() ? std::string("not submitted") : jobState(plan.mergeJob)));
    }
    return lines;
}

bool waitForMerge(const ClusterPlan& plan, double pollSeconds) {
    if (plan.mergeJob.empty()) return false;
    for (int failures = 0;;) {
        std::string error;
        const std::optional<std::map<std::string, std::string>> jobs = queue(&error);
        if (!jobs) {
            // A busy controller times out now and then; a minute of failures is an error.
            if (++failures * pollSeconds > 60.0) throw Error("cannot follow the merge job " + plan.mergeJob + ": " + error);
        } else {
            failures = 0;
            if (jobs->find(plan.mergeJob) == jobs->end()) return true;
        }
        std::this_thread::sleep_for(std::chrono::duration<double>(pollSeconds));
    }
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
