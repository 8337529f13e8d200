#include "bake/settings_table.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace vl {

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
