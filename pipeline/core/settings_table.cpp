#include "core/settings_table.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace vl {
namespace {

// Edits (insert, delete, replace, swap of neighbours) that turn a into b, letter case aside.
size_t editDistance(const std::string& a, const std::string& b) {
    const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
    std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
    for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
    for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
    for (size_t i = 1; i <= a.size(); ++i)
        for (size_t j = 1; j <= b.size(); ++j) {
            const bool same = lower(a[i - 1]) == lower(b[j - 1]);
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same ? 0 : 1)});
            if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[a.size()][b.size()];
}

}  // namespace

std::string closestName(const std::string& name, const std::vector<std::string>& known) {
    // Keys are short: what lies within a third of the known name's length (at least one edit)
    // is a slip of the keyboard; further is another word. Ties go to the first listed.
    if (name.size() > 256) return "";  // no key is that long; spare the table
    std::string best;
    size_t bestDistance = 0;
    for (const std::string& candidate : known) {
        const size_t distance = editDistance(name, candidate);
        if (distance > std::max<size_t>(1, candidate.size() / 3) || distance >= candidate.size()) continue;
        if (best.empty() || distance < bestDistance) {
            best = candidate;
            bestDistance = distance;
        }
    }
    return best;
}


int parseIntSetting(const std::string& name, const std::string& value, long long lo, long long hi) {
    errno = 0;
    char* end = nullptr;
    const long long v = std::strtoll(value.c_str(), &end, 10);
    if (value.empty() || *end != '\0' || errno == ERANGE)
        throw SettingsError("setting " + name + ": '" + value + "' is not an integer");
    if (v < lo || v > hi)
        throw SettingsError("setting " + name + " = " + value + " is out of range [" + std::to_string(lo) + ", " +
                            std::to_string(hi) + "]");
    return static_cast<int>(v);
}

double parseRealSetting(const std::string& name, const std::string& value, double lo, double hi) {
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !std::isfinite(v))
        throw SettingsError("setting " + name + ": '" + value + "' is not a finite number");
    if (v < lo || v > hi)
        throw SettingsError("setting " + name + " = " + value + " is out of range [" + std::to_string(lo) + ", " +
                            std::to_string(hi) + "]");
    return v;
}

bool parseBoolSetting(const std::string& name, const std::string& value) {
    if (value == "true" || value == "1" || value == "on" || value == "yes") return true;
    if (value == "false" || value == "0" || value == "off" || value == "no") return false;
    throw SettingsError("setting " + name + ": '" + value + "' is not true or false");
}

int parseChoiceSetting(const std::string& name, const std::string& value, const std::vector<std::string>& choices) {
    std::string list;
    for (size_t i = 0; i < choices.size(); ++i) {
        if (choices[i] == value) return static_cast<int>(i);
        list += (i ? ", " : "") + choices[i];
    }
    throw SettingsError("setting " + name + ": '" + value + "' is not one of " + list);
}

}  // namespace vl
