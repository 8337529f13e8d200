#include "gather/gather_settings.h"

#include "core/error.h"
#include "core/text.h"
#include "gather/irradiance_cache.h"

#include <cmath>
#include <utility>

namespace vl {
ConeSettings bounceConeSettings(const GatherSettings& settings) {
    ConeSettings bounce = settings.cone;
    bounce.coneCount = settings.bounceCones;
    return bounce;
}

bool takesLightsAtHits(const GatherSettings& settings, const GatherInputs& inputs, bool punctualLights) {
    return settings.hitLightExact && punctualLights && inputs.voxelsLitByRays;
}

BrightPatchSettings gatherBrightPatches(const GatherSettings& settings, const GatherInputs& inputs, bool punctualLights) {
    BrightPatchSettings patches = settings.brightPatches;
    if (takesLightsAtHits(settings, inputs, punctualLights)) patches.factor = 0.0f;
    return patches;
}

void validateGatherSettings(const GatherSettings& s) {
    validateConeSettings(s.cone, "bake settings");
    validateConeSettings(bounceConeSettings(s), "bake settings (bounce-cones)");
    if (s.bounces < 0 || s.bounces > 1024) throw SettingsError("setting bounces = " + std::to_string(s.bounces) + " is outside 0..1024");
    if (s.gatherLevel < -1 || s.gatherLevel > kMaxCacheLevel)
        throw SettingsError("setting gather-level = " + std::to_string(s.gatherLevel) + " is outside -1.." +
                            std::to_string(kMaxCacheLevel));
    if (s.gatherTurns < 1 || s.gatherTurns > kMaxGatherTurns)
        throw SettingsError("setting gather-turns = " + std::to_string(s.gatherTurns) + " is outside 1.." +
                            std::to_string(kMaxGatherTurns));
    if (!(s.brightPatches.factor >= 0.0f) || !std::isfinite(s.brightPatches.factor))
        throw SettingsError("setting bright-patches = " + numberText(s.brightPatches.factor) + " must be 0 or positive and finite");
    if (s.brightPatches.cellVoxels < 1 || s.brightPatches.cellVoxels > 1024)
        throw SettingsError("setting bright-patch-cell = " + std::to_string(s.brightPatches.cellVoxels) + " is outside 1..1024");
    if (s.brightPatches.maxPatches < 0 || s.brightPatches.maxPatches > 65536)
        throw SettingsError("setting bright-patch-max = " + std::to_string(s.brightPatches.maxPatches) + " is outside 0..65536");
    if (s.bounceGatherLevel < 0 || s.bounceGatherLevel > kMaxCacheLevel)
        throw SettingsError("setting bounce-gather-level = " + std::to_string(s.bounceGatherLevel) + " is outside 0.." +
                            std::to_string(kMaxCacheLevel));
    for (const auto& [name, rays] : {std::pair<const char*, int>{"gather-rays", s.gatherRays}, {"bounce-rays", s.bounceRays}})
        if (rays < 1 || rays > kMaxGatherRaysPerAxis)
            throw SettingsError(std::string("setting ") + name + " = " + std::to_string(rays) + " is outside 1.." +
                                std::to_string(kMaxGatherRaysPerAxis));
}

}  // namespace vl
