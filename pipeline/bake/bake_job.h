// The bake: the product's main job (DESIGN.md data flow) for one scene.
//   load → voxelize → voxel direct light → bounces → radiance mips ─┐
//   load → BVH ─→ receivers (lightmap texels, camera pixels) ───────┴→ exact direct + cones → files
// Outputs go to a staging folder beside the target and are moved into it only when every
// file is complete, so a failed or interrupted bake never leaves a finished-looking file.
#pragma once

#include "bake/bake_settings.h"
#include "scene/scene.h"

#include <string>
#include <vector>

namespace vl {

struct BakeJob {
    std::string scenePath;
    std::string outputDir;         // e.g. output/<scene name>
    BakeSettings settings;
    std::vector<Light> addedLights;  // lights a job file adds to the scene
};

struct StageTime {
    std::string stage;
    double seconds = 0.0;
};

struct BakeReport {
    std::string scenePath;
    std::string outputDir;
    bool ok = false;
    std::string error;  // why the bake failed, when !ok
    std::vector<StageTime> stages;
    size_t triangles = 0;
    size_t voxels = 0;
    double voxelSize = 0.0;
    size_t mipLevels = 0;
    size_t lightmapTexels = 0;
    size_t coveredTexels = 0;
    size_t pixels = 0;
    long peakMemoryBytes = 0;  // the process's peak resident set size when the bake ended
    std::vector<std::string> warnings;
    std::vector<std::string> files;  // written, relative to outputDir

    double totalSeconds() const;
};

// Runs one bake; returns a report instead of throwing for problems of the scene or settings.
BakeReport runBake(const BakeJob& job);

// Refuses, before any work, a bake whose estimated memory exceeds what the machine has
// available (SettingsError with both figures).
void checkMemoryBudget(const Scene& scene, const BakeSettings& settings, double voxelSize);

}  // namespace vl
