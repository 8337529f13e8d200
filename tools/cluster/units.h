// A bake split into units that run as separate processes, on one machine or on many that
// share a folder (cluster/slurm.h submits them to Slurm). Per scene:
//   voxel           the voxel stages (bake.h bakeVoxelStages) → voxel-state.vxu (voxel_state.h)
//   atlas a, band t rows [t·H/T, (t+1)·H/T) of the scene's atlas a (a large atlas is split
//                   into T bands) → band.vxu
//   camera c        one camera image → image.vxu
//   merge           every unit's result → the scene's output folder, written by the function a
//                   local bake writes with (bake_job.h writeBakeFiles), under its lock
// Results are the same bytes as a local bake: every receiver sample seeds its generator with
// its index in its whole atlas or image, no value is summed across units, and the padding of
// an atlas is dilated only once all its bands are in.
#pragma once

#include "bake/bake_job.h"

#include <optional>
#include <string>
#include <vector>

namespace vl::cluster {

// Texels a lightmap band is given at most, where the job does not set the number of bands.
constexpr double kTexelsPerBand = 512.0 * 512.0;

struct SceneUnits {
    struct Atlas {
        std::string name;  // as buildLightmapReceivers names it ("lightmap", a group's name)
        int bands = 1;     // units its rows are split into
    };
    std::vector<Atlas> atlases;  // in the order the bake makes them; none without lightmaps
    int cameras = 0;             // 0 when the job writes no images
    int receiverCount() const;
};

// What receiver unit r of a scene shades: band `band` of `bands` of atlas `atlas`, or camera
// `camera` (the atlases' bands come first, atlas by atlas).
struct ReceiverUnit {
    int atlas = -1, band = 0, bands = 1;
    int camera = -1;
};
ReceiverUnit receiverUnit(const SceneUnits& units, int receiver);

// The units of a job's scene. Loads it and prepares it as a bake does (voxel size, anchoring,
// generated lightmap UVs) to list its atlases; each gets `bands` bands (> 0), else one per
// kTexelsPerBand of its texels. The cameras are counted unless `cameras` >= 0. Throws what
// loading throws.
SceneUnits planSceneUnits(const BakeJob& job, int bands, int cameras = -1);

// "atlas 'lightmap' rows 2 of 4", "camera 0".
std::string receiverName(const SceneUnits& units, int receiver);
// The unit's folder name inside the scene's work folder.
std::string receiverFolder(const SceneUnits& units, int receiver);
constexpr const char* kVoxelFolder = "voxel";

struct UnitRecord {
    bool ok = false;
    std::string error;
    double seconds = 0.0;      // its stages: what bake.json counts (a receiver: rebuilding the gather and shading)
    double wallSeconds = 0.0;  // the whole unit, reading and writing its files included
    std::string host;
    std::string slurmJob;  // "JOBID" or "ARRAYJOB_TASK" when Slurm ran it
    long peakMemoryBytes = 0;
};

// unit.json of a finished unit's folder; nothing while the unit has not finished.
std::optional<UnitRecord> readUnitRecord(const std::string& unitFolder);

// Each runs one unit into `sceneWork`/<its folder> and returns its record; a failure is
// recorded in the folder, not thrown. A unit writes into <unit>.partial-<host>-<pid> beside its
// folder and renames it when done; unit.json says whether it succeeded and why not. A unit
// whose folder holds an ok unit.json is done: a second run of the job runs only the others.
// A unit that cannot even start (its plan unreadable, its scene changed since submission):
// its folder records `error`, so --slurm-status and the merge give the real reason.
UnitRecord recordUnitFailure(const std::string& sceneWork, const std::string& folder, const std::string& error);
UnitRecord runVoxelUnit(const BakeJob& job, const std::string& sceneWork);
UnitRecord runReceiverUnit(const BakeJob& job, const std::string& sceneWork, const SceneUnits& units, int receiver);

// The scene's outputs from its units' results, as runBake reports them; a failed or missing
// unit fails the scene with that unit's error (the first in the order of a local bake).
BakeReport mergeScene(const BakeJob& job, const std::string& sceneWork, const SceneUnits& units);

}  // namespace vl::cluster
