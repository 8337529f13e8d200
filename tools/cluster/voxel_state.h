// What a cluster bake's voxel unit leaves for the scene's receiver units and its merge
// (cluster/units.h): the voxel stages' result (bake.h VoxelStages) without what is rebuilt
// from it. The radiance mips are rebuilt from the voxels' final light (RadianceMips::relight
// gives what a build gives), the gather points from the voxels and linked through the mips;
// their gathered irradiance, the voxels, the generated lightmap UVs and the atlas list are
// stored. One file, voxel-state.vxu (cluster/unit_file.h).
#pragma once

#include "bake/bake.h"
#include "bake/bake_job.h"

#include <string>
#include <vector>

namespace vl::cluster {

struct VoxelState {
    BakeResult result;  // voxels, choices and counts, the voxel stages' times; no mips, lightmaps or images
    LightmapSettings lightmap;
    bool gathered = false;  // the final gather ran (gather-level >= 0)
    int gatherLevel = 0;
    std::vector<vec3> gatheredIrradiance;
    bool onGpu = false;
    // The scene as the voxel unit loaded it, and the warnings of its load and its stages, in
    // the order a local bake reports them.
    size_t triangles = 0;
    double loadSeconds = 0.0;
    std::vector<std::string> sceneWarnings;
    std::vector<std::string> stageWarnings;
};

// `triangles`, `sceneWarnings`, `loadSeconds`: the scene as loaded, before the stages.
void writeVoxelState(const VoxelStages& stages, size_t triangles, const std::vector<std::string>& sceneWarnings,
                     double loadSeconds, const std::vector<std::string>& stageWarnings, const std::string& path);
VoxelState readVoxelState(const std::string& path);

// The scene the receivers see: the job's scene (`loaded`: loadJobScene, loaded again) anchored
// to the voxel grid and given the generated lightmap UVs, as bakeVoxelStages left it.
Scene receiverScene(Scene loaded, const VoxelState& state);

// What the voxel stages left the receivers (gather/gather.h IndirectLight), restored from the
// state by the gather's own restoreIndirectLight, against `tracing`'s rays.
IndirectLight restoreIndirectLight(const VoxelState& state, const ReceiverScene& tracing, const BakeSettings& settings);

}  // namespace vl::cluster
