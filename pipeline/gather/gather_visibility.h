// The choice between cones and rays for what a gather point sees (gather/ray_gather.h), as a
// setting: small, so bake_settings.h stays light.
#pragma once

#include <string>

namespace vl {

// What decides which surfaces a gather point sees: cones compositing the mips' opacity, or
// rays against the triangles. Auto: rays, unless more than kBackShareLimit of the rays from
// the bounces' gather points (kProbeRaysPerAxis² each) hit the back of a single-sided surface,
// which the voxels do not show; then cones.
enum class GatherVisibility { Auto, Cones, Rays };
GatherVisibility parseGatherVisibility(const std::string& text);  // SettingsError naming the choices
const char* toString(GatherVisibility visibility);
// The limit lies between zdm2 (every surface single-sided), well above it, where rays lose
// light at every bounce, and the default Cornell box, below it, whose backs are mostly seen
// from floor points under its bottomless blocks that no light reaches either way, and which
// rays bake better (docs/decisions.md, "Where the voxels cannot answer a ray").
constexpr double kBackShareLimit = 0.15;
constexpr int kProbeRaysPerAxis = 4;
constexpr int kMaxGatherRaysPerAxis = 64;

}  // namespace vl
