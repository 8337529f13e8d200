#include "cone/cone_settings.h"

#include "core/error.h"

#include <cmath>
#include <cstdio>

namespace vl {

namespace {

std::string number(float v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", double(v));
    return text;
}

}  // namespace

void validateConeSettings(const ConeSettings& s, const std::string& where) {
    const auto fail = [&](const std::string& what) { throw SettingsError(where + ": " + what); };
    if (s.coneCount != 6 && s.coneCount != 16 && s.coneCount != 32)
        fail("cone count " + std::to_string(s.coneCount) + " is not supported (use 6, 16 or 32)");
    if (!(s.apertureDegrees >= 0.0f && s.apertureDegrees < 90.0f))
        fail("cone aperture " + number(s.apertureDegrees) + "° is outside (0°, 90°) (0 = the default for the cone count)");
    if (!(s.startOffset >= 0.0f && s.startOffset <= 16.0f))
        fail("cone start offset " + number(s.startOffset) + " voxels is outside [0, 16]");
    if (!(s.stepFactor >= 0.05f && s.stepFactor <= 4.0f))
        fail("cone step factor " + number(s.stepFactor) + " is outside [0.05, 4]");
    if (!(s.maxDistance >= 0.0f) || !std::isfinite(s.maxDistance))
        fail("cone max distance " + number(s.maxDistance) + " m is negative or not finite (0 = unlimited)");
}

}  // namespace vl
