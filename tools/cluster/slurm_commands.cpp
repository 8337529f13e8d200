#include "cluster/slurm_commands.h"

#include "core/error.h"

#include <cerrno>
#include <cstdlib>
#include <fcntl.h>
#include <poll.h>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace vl::cluster {
namespace {

std::string trimmed(std::string text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    size_t start = 0;
    while (start < text.size() && std::isspace(static_cast<unsigned char>(text[start]))) ++start;
    return text.substr(start);
}

}  // namespace

std::string ProgramResult::message() const { return trimmed(err.empty() ? out : err); }


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

std::string submitScript(const std::string& scriptPath, const std::vector<std::string>& extra) {
    std::vector<std::string> arguments{"sbatch", "--parsable"};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    arguments.push_back(scriptPath);
    const ProgramResult r = runProgram(arguments);
    if (r.status == 127 || r.status == -1)
        throw Error("cannot run sbatch: is Slurm's client installed (Debian: apt-get install slurm-client) and on PATH?");
    const std::string id = trimmed(r.out.substr(0, r.out.find(';')));
    if (r.status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
        throw Error("sbatch refused " + scriptPath + ": " + r.message());
    return id;
}

std::optional<std::map<std::string, std::string>> queue(std::string* error) {
    const ProgramResult r = runProgram({"squeue", "--me", "-h", "-r", "-o", "%i|%T|%r|%N"});
    if (r.status != 0) {
        if (error)
            *error = r.status == 127 || r.status == -1 ? "squeue cannot run (is Slurm's client installed?)"
                                                       : "squeue failed: " + r.message();
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


}  // namespace vl::cluster
