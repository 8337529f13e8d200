#include "cluster/slurm.h"

#include "cluster/slurm_commands.h"
#include "core/error.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <sys/file.h>
#include <thread>
#include <unistd.h>

namespace vl::cluster {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

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
            throw Error("scontrol release failed: " + released.message());
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

}  // namespace vl::cluster
