// The accuracy tools' first argument, a job file (its first scene) or a glTF scene, with the
// command line's name=value settings applied over it (as `voxlight bake` applies them).
#pragma once

#include "bake/bake_job.h"
#include "bake/bake_settings.h"
#include "bake/job_file.h"
#include "core/error.h"

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace vl {

inline BakeJob accuracyJob(const std::string& input, const SettingAssignments& assignments) {
    BakeSettings settings;
    settings.quiet = true;
    for (const auto& [name, value] : assignments) applySetting(bakeSettingsTable(), settings, name, value);
    if (input.size() > 5 && input.compare(input.size() - 5, 5, ".json") == 0) {
        const std::vector<BakeJob> jobs = readJobFile(input, settings, "output", assignments);
        if (jobs.empty()) throw InputError(input + ": no scenes");
        return jobs.front();
    }
    BakeJob job;
    job.scenePath = input;
    job.settings = settings;
    return job;
}

// A command line's name=value setting onto `assignments`; SettingsError naming the argument otherwise.
inline void addAssignment(SettingAssignments& assignments, const std::string& arg) {
    const size_t eq = arg.find('=');
    if (eq == std::string::npos) throw SettingsError("not name=value: " + arg);
    assignments.emplace_back(arg.substr(0, eq), arg.substr(eq + 1));
}

// "X,Y" after a flag such as --pixel; SettingsError naming the flag otherwise.
inline std::pair<int, int> parsePoint(const std::string& flag, const char* text) {
    int x = 0, y = 0;
    if (std::sscanf(text, "%d,%d", &x, &y) != 2) throw SettingsError(flag + ": '" + text + "' is not X,Y");
    return {x, y};
}

}  // namespace vl
