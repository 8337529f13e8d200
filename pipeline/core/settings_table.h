// Named settings, shared by command-line flags and job files so each setting is declared
// once: its name, its help text with the default, and how a string value is parsed and
// checked into the settings struct. A bad value is a SettingsError naming the setting.
#pragma once

#include "core/error.h"

#include <functional>
#include <string>
#include <vector>

namespace vl {

template <typename Settings>
struct SettingSpec {
    std::string name;  // flag is --name, job-file key is name
    std::string help;  // ends with the default, e.g. "(default 128)"
    std::function<void(Settings&, const std::string&)> apply;
};

template <typename Settings>
using SettingsTable = std::vector<SettingSpec<Settings>>;

// Parse helpers: each names the setting in its error and checks the value's range.
int parseIntSetting(const std::string& name, const std::string& value, long long lo, long long hi);
double parseRealSetting(const std::string& name, const std::string& value, double lo, double hi);
bool parseBoolSetting(const std::string& name, const std::string& value);
// One of `choices`; returns its index.
int parseChoiceSetting(const std::string& name, const std::string& value, const std::vector<std::string>& choices);

// The name in `known` closest to `name` by edit distance (letter case aside, a swap of two
// neighbours one edit), when it is close enough to be what was meant; "" when none is.
std::string closestName(const std::string& name, const std::vector<std::string>& known);

template <typename Settings>
std::vector<std::string> settingNames(const SettingsTable<Settings>& table) {
    std::vector<std::string> names;
    for (const auto& spec : table) names.push_back(spec.name);
    return names;
}

// The setting of that name; nullptr when the table has none. Every reader of setting names
// (flags, job files, bench specs) looks them up here.
template <typename Settings>
const SettingSpec<Settings>* findSetting(const SettingsTable<Settings>& table, const std::string& name) {
    for (const auto& spec : table)
        if (spec.name == name) return &spec;
    return nullptr;
}

// Applies one named setting; an unknown name is a SettingsError with the closest known one,
// or the list of them when none is close.
template <typename Settings>
void applySetting(const SettingsTable<Settings>& table, Settings& settings, const std::string& name,
                  const std::string& value) {
    if (const SettingSpec<Settings>* spec = findSetting(table, name)) {
        spec->apply(settings, value);
        return;
    }
    const std::vector<std::string> names = settingNames(table);
    const std::string closest = closestName(name, names);
    if (!closest.empty()) throw SettingsError("unknown setting '" + name + "' (did you mean '" + closest + "'?)");
    std::string known;
    for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
    throw SettingsError("unknown setting '" + name + "' (known: " + known + ")");
}

// Applies one setting written "name=value"; SettingsError when it has no name or no '='.
template <typename Settings>
void applySetting(const SettingsTable<Settings>& table, Settings& settings, const std::string& assignment) {
    const size_t eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0) throw SettingsError("'" + assignment + "' is not name=value");
    applySetting(table, settings, assignment.substr(0, eq), assignment.substr(eq + 1));
}

}  // namespace vl
