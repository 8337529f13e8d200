#include "cluster/slurm.h"

#include "core/error.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
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

// Runs a program with arguments (no shell), collecting its standard output and error.
ProgramResult runProgram(const std::vector<std::string>& arguments) {
    int outPipe[2], errPipe[2];
    if (::pipe(outPipe) != 0) return {};
    if (::pipe(errPipe) != 0) {
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
        for (int fd : {outPipe[0], outPipe[1], errPipe[0], errPipe[1]}) ::close(fd);
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
    // Both pipes drained in turn by poll-free reads: sbatch and squeue write little to stderr.
    char buffer[4096];
    for (ssize_t n; (n = ::read(outPipe[0], buffer, sizeof buffer)) > 0;) result.out.append(buffer, size_t(n));
    for (ssize_t n; (n = ::read(errPipe[0], buffer, sizeof buffer)) > 0;) result.err.append(buffer, size_t(n));
    ::close(outPipe[0]);
    ::close(errPipe[0]);
    int status = 0;
    ::waitpid(pid, &status, 0);
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

std::string listText(const std::vector<int>& values) {
    std::string out;
    for (int v : values) out += (out.empty() ? "" : ",") + std::to_string(v);
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

// Every job of the queue, by id ("123", "123_4"): "STATE|REASON|NODES".
std::map<std::string, std::string> queue() {
    std::map<std::string, std::string> jobs;
    const ProgramResult r = runProgram({"squeue", "-h", "-r", "-o", "%i|%T|%r|%N"});
    if (r.status != 0) return jobs;
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
    if (r.status != 0) return "";
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

bool anyQueued(const ClusterPlan& plan) {
    const std::map<std::string, std::string> jobs = queue();
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
                               {"units", sceneUnitsJson(s.units)}});
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
    std::vector<fs::path> files;
    std::error_code ec;
    const fs::path sceneFolder = fs::absolute(job.scenePath).parent_path();
    for (const auto& entry : fs::directory_iterator(sceneFolder, ec))
        if (entry.is_regular_file(ec)) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) stamp(f);
    for (const std::string& f : jobFiles) stamp(fs::absolute(f));
    uint64_t hash = 0xcbf29ce484222325ull;
    for (char c : text.str()) hash = (hash ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
    return hex;
}

std::vector<std::string> submit(ClusterPlan& plan, const SlurmOptions& options) {
    std::vector<std::string> lines;
    // A job submitted here before: keep its units' results when nothing changed.
    const fs::path planPath = fs::path(plan.workDir) / kPlanFile;
    if (fs::exists(planPath)) {
        bool same = false;
        try {
            const ClusterPlan old = readPlan(plan.workDir);
            if (!options.dryRun && anyQueued(old))
                throw Error("the bake submitted into " + plan.workDir +
                            " earlier is still queued or running (voxlight bake --slurm-status shows it): wait for it, "
                            "or scancel its jobs");
            same = old.scenes.size() == plan.scenes.size();
            for (size_t k = 0; same && k < plan.scenes.size(); ++k)
                same = old.scenes[k].fingerprint == plan.scenes[k].fingerprint &&
                       sameUnits(old.scenes[k].units, plan.scenes[k].units);
        } catch (const InputError&) {
            same = false;
        }
        if (!same && !options.dryRun) {
            for (size_t k = 0;; ++k) {
                const fs::path scene = sceneWorkFolder(plan.workDir, k);
                if (!fs::exists(scene)) break;
                fs::remove_all(scene);
            }
            lines.push_back("the job changed since its last submission: every unit runs again");
        }
    }
    const fs::path logs = fs::path(plan.workDir) / "logs", scripts = fs::path(plan.workDir) / "scripts";
    if (!options.dryRun) {
        fs::remove(fs::path(plan.workDir) / kSummaryFile);  // the last merge's, not this one's
        fs::create_directories(logs);
        fs::create_directories(scripts);
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
    const auto run = [&](const std::string& script, std::vector<std::string> extra, const std::string& placeholder) {
        std::string command = "sbatch --parsable";
        for (const std::string& e : extra) command += " " + e;
        lines.push_back(command + " " + script);
        return options.dryRun ? placeholder : submitScript(script, extra);
    };

    // Voxel units: one array over the scenes whose voxel unit has no result.
    plan.voxelTasks.clear();
    for (size_t k = 0; k < plan.scenes.size(); ++k) {
        const std::optional<UnitRecord> done =
            readUnitRecord((fs::path(sceneWorkFolder(plan.workDir, k)) / kVoxelFolder).string());
        if (!(done && done->ok)) plan.voxelTasks.push_back(int(k));
    }
    plan.voxelJob.clear();
    std::vector<std::string> all;
    if (!plan.voxelTasks.empty()) {
        const std::string script = writeScript(
            "voxel.sh", batchScript(plan, options, "voxlight-voxel", (logs / "voxel-%a.out").string(),
                                    "--unit voxel --scene \"$SLURM_ARRAY_TASK_ID\""));
        plan.voxelJob = run(script, {"--array=" + listText(plan.voxelTasks) + limit}, "<voxel job>");
        all.push_back(plan.voxelJob);
    }
    // Receivers: per scene an array after its voxel unit.
    plan.receiverJobs.assign(plan.scenes.size(), "");
    plan.receiverTasks.assign(plan.scenes.size(), {});
    for (size_t k = 0; k < plan.scenes.size(); ++k) {
        const SceneUnits& units = plan.scenes[k].units;
        for (int r = 0; r < units.receiverCount(); ++r) {
            const std::optional<UnitRecord> done =
                readUnitRecord((fs::path(sceneWorkFolder(plan.workDir, k)) / receiverFolder(units, r)).string());
            if (!(done && done->ok)) plan.receiverTasks[k].push_back(r);
        }
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
        all.push_back(plan.receiverJobs[k]);
    }
    // The merge, after every unit however it ended.
    const std::string script =
        writeScript("merge.sh", batchScript(plan, options, "voxlight-merge", (logs / "merge.out").string(), "--unit merge"));
    std::vector<std::string> extra;
    if (!all.empty()) {
        std::string dependency = "--dependency=afterany";
        for (const std::string& id : all) dependency += ":" + id;
        extra.push_back(dependency);
    }
    plan.mergeJob = run(script, extra, "<merge job>");
    if (!options.dryRun) {
        writePlan(plan);
        size_t units = 0;
        for (const auto& tasks : plan.receiverTasks) units += tasks.size();
        lines.push_back("submitted " + std::to_string(plan.voxelTasks.size()) + " voxel unit(s), " +
                        std::to_string(units) + " receiver unit(s) and the merge (job " + plan.mergeJob +
                        ") of " + std::to_string(plan.scenes.size()) + " scene(s); follow it with: voxlight bake "
                        "--slurm-status " + fs::path(plan.workDir).parent_path().string());
    }
    return lines;
}

std::vector<std::string> slurmStatus(const std::string& outputRoot) {
    const std::string workDir = workFolder(outputRoot);
    const ClusterPlan plan = readPlan(workDir);
    const std::map<std::string, std::string> jobs = queue();
    std::vector<std::string> lines;
    std::string voxelFailed;  // the scene's, while its units are listed
    const auto stateOf = [&](const std::string& folder, const std::string& job, bool submitted) -> std::string {
        const std::optional<UnitRecord> record = readUnitRecord(folder);
        if (record) {
            char seconds[32];
            std::snprintf(seconds, sizeof seconds, "%.2f s", record->wallSeconds);
            return record->ok ? "done on " + record->host + " in " + seconds : "failed: " + record->error;
        }
        if (!submitted) return "not submitted";
        const auto queued = jobs.find(job);
        if (queued == jobs.end() && !voxelFailed.empty()) return "not run: its voxel unit failed";
        if (queued != jobs.end()) return queuedText(queued->second);
        const std::string finished = finishedJobState(job);
        return "failed: no result" + (finished.empty() ? std::string(" (killed, out of time, or its node failed)")
                                                       : std::string(": Slurm says ") + finished);
    };
    for (size_t k = 0; k < plan.scenes.size(); ++k) {
        const ClusterPlan::Scene& scene = plan.scenes[k];
        const fs::path work = sceneWorkFolder(workDir, k);
        lines.push_back(scene.scenePath + " -> " + scene.outputDir);
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
            if (!s.at("ok").get<bool>())
                lines.push_back("  " + s.at("error").get<std::string>());
    } else {
        const auto queued = jobs.find(plan.mergeJob);
        lines.push_back("merge: " + (queued != jobs.end() ? queuedText(queued->second)
                                                          : "failed: no result" + [&] {
                                                                const std::string f = finishedJobState(plan.mergeJob);
                                                                return f.empty() ? std::string() : ": Slurm says " + f;
                                                            }()));
    }
    return lines;
}

bool waitForMerge(const ClusterPlan& plan, double pollSeconds) {
    if (plan.mergeJob.empty()) return false;
    for (;;) {
        const std::map<std::string, std::string> jobs = queue();
        if (jobs.find(plan.mergeJob) == jobs.end()) return true;
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
