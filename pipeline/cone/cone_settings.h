// Settings of the cone-tracing stage. Plain data (no strings, no containers) so the CUDA
// launchers copy it to the device as it is.
#pragma once

#include <string>

namespace vl {

struct ConeSettings {
    // Cones per hemisphere: 6, 16 or 32 (cone_set.h). More cones: less blur of the
    // incident light, fewer gaps between cones, proportionally more time.
    int coneCount = 16;
    // Half-angle of every cone in degrees, in (0, 90). 0 = the set's default: the half-angle
    // whose cap has the solid angle of one cone's share of the hemisphere (2π/N), so the
    // cones tile it (33.6° for 6, 20.4° for 16, 14.4° for 32).
    float apertureDegrees = 0.0f;
    // The cone apex sits this far (in voxels of size h) along the receiver's normal, so the
    // receiver's own surface voxels do not occlude it. 1.5 clears a surface lying anywhere
    // in its voxel: the level-0 trilinear footprint reaches one voxel, the surface up to half
    // a voxel off the centre.
    float startOffset = 1.5f;
    // Step along the cone = stepFactor × the cone's diameter there; the opacity of every
    // sample is corrected for that length, so this trades speed for sampling accuracy only.
    float stepFactor = 0.5f;
    // Metres; 0 = march until the cone is opaque (A ≥ 0.99) or leaves the grid.
    float maxDistance = 0.0f;
};

// Throws SettingsError naming the setting when a value is out of range (coneCount not 6, 16
// or 32; aperture negative, ≥ 90° or NaN; startOffset negative or above 16 voxels; stepFactor
// not in [0.05, 4]; maxDistance negative or NaN). `where` prefixes the message (e.g. the job
// file and scene).
void validateConeSettings(const ConeSettings& settings, const std::string& where = "cone settings");

}  // namespace vl
