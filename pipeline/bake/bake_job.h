// The bake as a file job for one scene: load the glTF (plus lights a job file adds), bake in
// memory (bake.h), write lightmaps, images, grids.vdb and bake.json. Outputs go to a staging
// folder beside the target and are moved into it only when every file is complete, so a
// failed or interrupted bake never leaves a finished-looking file.
#pragma once

#include "bake/bake.h"

#include <functional>
#include <string>
#include <vector>

namespace vl {

struct BakeJob {
    std::string scenePath;
    std::string outputDir;           // e.g. output/<scene name>
    BakeSettings settings;
    std::vector<Light> addedLights;    // lights a job file adds to the scene
    std::vector<Camera> addedCameras;  // cameras a job file adds (a level exported without one)
};

// The loaded scene with the job's added lights and cameras (given in world space, placed in
// the scene's local frame) and its sky (the `sky` setting).
void addJobLightsAndCameras(const BakeJob& job, Scene& scene);

// The job's scene as every bake of it sees it: the glTF loaded (strict when its settings are)
// with the job's added lights and cameras.
Scene loadJobScene(const BakeJob& job);

struct BakeReport {
    std::string scenePath;
    std::string outputDir;
    bool ok = false;
    std::string error;  // why the bake failed, when !ok
    std::vector<StageTime> stages;
    size_t triangles = 0;
    size_t voxels = 0;
    double voxelSize = 0.0;
    VoxelSizeChoice voxelSizeChoice;  // what set the voxel size, and each light's clearance
    size_t mipLevels = 0;
    size_t gatherPoints = 0;
    size_t brightPatches = 0;
    // The irradiance volume's probes along x, y, z (zero: none), its spacing and how many lie in open space.
    glm::ivec3 volumeProbes{0};
    double volumeSpacing = 0.0;
    size_t volumeValidProbes = 0;
    GatherVisibilityChoice gatherVisibility;  // rays or cones, and why
    std::optional<LightmapUvReport> lightmapUvs;  // when the bake generated TEXCOORD_1
    size_t lightmapTexels = 0;
    size_t coveredTexels = 0;
    size_t buriedTexels = 0;  // of them, wholly inside closed geometry: filled from their neighbours
    // The lightmaps' chart seams (lightmap/lightmap_seams.h), all atlases pooled; none without lightmaps.
    std::optional<LightmapSeamReport> lightmapSeams;
    size_t pixels = 0;
    long peakMemoryBytes = 0;  // the process's peak resident set size when the bake ended
    std::vector<std::string> warnings;
    std::vector<std::string> files;  // written, relative to outputDir

    double totalSeconds() const;
};

// Runs one bake; returns a report instead of throwing for problems of the scene or settings.
BakeReport runBake(const BakeJob& job);

// The batch's table on stderr: per scene its status, voxels, texels, pixels, seconds, peak
// memory and output folder (or error).
void printBakeSummary(const std::vector<BakeReport>& reports);

// What glTF out needs of the scene a bake consumed: its file and where each mesh came from.
struct ExportSource {
    std::string sourcePath;
    std::vector<Mesh::Source> meshSources;
    vec3 viewerSky{0.0f};  // glTF holds no sky: viewers get its mean radiance
    std::vector<Light> lights;  // the scene's, bake modes resolved (bake.h resolveLightBake)
};
ExportSource exportSourceOf(const Scene& scene);

// A bake's files from its result, into `staging`: lightmaps and images (EXR, PNG), grids.vdb,
// scene.glb, then bake.json from `report` (its figures filled from `result` here) with the
// warnings `diagnostics` collected appended. A local bake and a cluster bake's merge
// (cluster/units.h) write through this one function.
void writeBakeFiles(const BakeJob& job, BakeResult& result, const ExportSource& source, BakeReport& report,
                    const std::string& staging, Diagnostics& diagnostics);

// Runs `write` into a staging folder beside job.outputDir while holding the folder's lock,
// then moves its files in (bake.json last); on an exception no file is moved and the report
// says why.
BakeReport publishBake(const BakeJob& job, const std::function<void(BakeReport& report, const std::string& staging)>& write);

}  // namespace vl
