// The Slurm commands a cluster bake runs (sbatch, squeue, scontrol, sacct, scancel): each a
// program with arguments, no shell, and what its output says.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace vl::cluster {

struct ProgramResult {
    int status = -1;  // exit code; -1 when it could not run, 127 when it was not found
    std::string out, err;
    std::string message() const;  // what it said: standard error, else standard output, trimmed
};
ProgramResult runProgram(const std::vector<std::string>& arguments);

// `sbatch --parsable EXTRA… script`: the job id, or an Error with what sbatch said.
std::string submitScript(const std::string& scriptPath, const std::vector<std::string>& extra);

// This user's jobs in the queue, by id ("123", "123_4"): "STATE|REASON|NODES". Nothing when
// squeue fails (`error` then says why).
std::optional<std::map<std::string, std::string>> queue(std::string* error = nullptr);
// A queue entry as --slurm-status shows it: "queued (Dependency)", "running on node1".
std::string queuedText(const std::string& entry);
// "JobState (Reason), exit code N" of a job that left the queue, while Slurm remembers it
// (scontrol, then sacct); empty when nothing does.
std::string finishedJobState(const std::string& id);
// Slurm's MaxArraySize: array indices must stay below it (1001 unless the site set it).
int maxArraySize();

}  // namespace vl::cluster
