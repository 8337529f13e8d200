// The indirect light's settings: what the gather stage is built from. Each field is a bake
// setting (bake/bake_settings.h: a flag and a job-file key of the same name); why each default
// is what it is, with the bench runs that chose it: docs/decisions.md.
#pragma once

#include "cone/cone_settings.h"
#include "gather/bright_patches.h"
#include "gather/gather_visibility.h"

namespace vl {

// Where a lightmap's indirect light is gathered.
enum class LightmapGather {
    Texels,  // records on the atlas's own texel lattice (gather/texel_gather.h)
    Points,  // the voxel gather points, interpolated (gather/irradiance_cache.h), as images are
};

struct GatherSettings {
    // The final gather's cones, where it goes by cones; a set too sparse misses or doubles a
    // small bright region (a point light's hot spot on a ceiling).
    ConeSettings cone = ConeSettings{32};
    // Voxel-to-voxel bounces before the final gather (which is one more), each of bounceCones
    // cones where they go by cones; then the series' geometric tail (gather/bounces.h).
    int bounces = 24;
    int bounceCones = 6;
    bool bounceTail = true;
    // The gather points' cell level (gather/irradiance_cache.h): one point per surface side of
    // each block of 2^level voxels per axis. gatherLevel −1: every receiver sample gathers its
    // own cones, the reference for the interpolation's error.
    int gatherLevel = 2;
    int bounceGatherLevel = 2;
    // Cone sets per final gather point, each turned 1/n turn from the last: they halve the gaps
    // a small bright region falls into.
    int gatherTurns = 2;
    // The final gather's bright patches (gather/bright_patches.h), gathered by shadow rays.
    BrightPatchSettings brightPatches;
    // Rays or cones for what the bounces' and the final gather's points see, and the n × n
    // fan of each point when rays.
    GatherVisibility visibility = GatherVisibility::Auto;
    int gatherRays = 14;
    int bounceRays = 14;
    // The lightmap records' rays take the punctual lights' reflection at their hits by a
    // shadow ray, not from the hit's voxel (gather/ray_gather.h FanExtras::lightsAtHits).
    bool hitLightExact = true;
    // A lightmap record's hit nearer than this many voxels traces its light on instead of
    // reading its voxel (gather/ray_gather.h FanExtras::nearField); 0: every hit reads it.
    float nearFieldVoxels = 3.0f;
    LightmapGather lightmapGather = LightmapGather::Texels;
    int texelGatherSpacing = 0;     // texels between lightmap records; 0: chosen (gather/texel_gather.h)
    int texelGatherRays = 0;        // each lightmap record's n × n fan; 0: chosen (gather/texel_gather.h)
    // Turns the lightmap records' fans and draws: two bakes at two seeds differ by the
    // lightmap's noise alone.
    int lightmapSeed = 0;
    int lightmapFilterPasses = 3;   // the records' edge-stopping filter; 0: off
    bool lightmapGradients = true;  // the records' rotation gradients
};

// How the voxels were lit and what reads the gather: the other stages' settings it follows.
struct GatherInputs {
    bool receivers = true;         // lightmaps or images read the final gather
    bool voxelsLitByRays = false;  // the voxel pass by rays lit them, their sky included
    int skyStrata = 10;            // an image sky's draws per axis (lighting/direct_light.h)
    bool quiet = false;            // no progress on stderr
};

// The bounces' cones: `cone` with bounceCones cones.
ConeSettings bounceConeSettings(const GatherSettings& settings);

// Whether the lightmap records' rays take the punctual lights at their hits: hit-light exact,
// in a scene with punctual lights, lit by voxel-visibility rays (whose lights it takes apart).
bool takesLightsAtHits(const GatherSettings& settings, const GatherInputs& inputs, bool punctualLights);
// The bright patches the final gather splits off: the settings', none where the rays take the
// lights at their hits.
BrightPatchSettings gatherBrightPatches(const GatherSettings& settings, const GatherInputs& inputs, bool punctualLights);

// Throws SettingsError naming the setting whose value is out of range.
void validateGatherSettings(const GatherSettings& settings);

}  // namespace vl
