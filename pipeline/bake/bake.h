// The bake in memory: a Scene and BakeSettings in, lit voxels, radiance mips, lightmaps and
// camera images out (docs/DESIGN.md, "Data flow").
//   voxelize → voxel direct light → bounces → radiance mips ─┐
//   BVH → receivers (lightmap texels, camera pixels) ────────┴→ exact direct + gathered indirect
// bake_job.h wraps it with loading, checks and files.
#pragma once

#include "bake/bake_settings.h"
#include "bake/voxel_size.h"
#include "core/diagnostics.h"
#include "core/image.h"
#include "core/stage_time.h"
#include "export/gltf_export.h"
#include "gather/gather.h"
#include "lightmap/lightmap_image.h"
#include "lightmap/lightmap_seams.h"
#include "probes/irradiance_volume.h"
#include "receivers/receiver_scene.h"
#include "receivers/receivers.h"
#include "scene/scene.h"
#include "unwrap/lightmap_uvs.h"
#include "voxel/voxel_scene.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vl {

struct BakedLightmap {
    std::string name;  // the atlas name ("lightmap" for the shared atlas)
    Image total;       // RGB E/π, padding dilated
    Image direct;
    Image indirect;
    Image mask;        // 1 channel: 1 where a texel holds its own light; 0 padding, and buried texels
    size_t coveredTexels = 0;
    size_t buriedTexels = 0;       // covered, but wholly inside closed geometry: filled as padding
    std::vector<uint32_t> meshes;  // indices into Scene::meshes baked into it
    LightmapSeamReport seams;      // its chart seams' jumps, before and after stitching
    Image shadowmask;              // RGBA 0..1, padding dilated (gather/shadowmask.h); empty: no shadowmask light
};

struct BakedImage {
    std::string camera;
    Image beauty;    // RGB radiance: emission + albedo·(E_direct + E_indirect)/π
    Image direct;    // albedo·E_direct/π
    Image indirect;  // albedo·E_indirect/π
    Image albedo;
    Image lightmapped;  // RGB radiance lit by the shipped lightmaps (lightmap/lightmap_image.h); empty: not made
};

struct BakeResult {
    VoxelSizeChoice voxelSizeChoice;  // the voxel size and what set it (bake/voxel_size.h)
    VoxelScene voxels;  // lit, bounces included
    RadianceMips mips;
    std::vector<BakedLightmap> lightmaps;
    std::vector<BakedImage> images;
    std::vector<StageTime> stages;
    size_t gatherPoints = 0;  // where the receivers' indirect light was gathered (0: at every sample)
    size_t brightPatches = 0;  // gathered by shadow rays at the gather points (gather/bright_patches.h)
    GatherVisibilityChoice gatherVisibility;  // rays or cones, and why (gather/ray_gather.h)
    std::optional<LightmapUvReport> lightmapUvs;  // when the bake generated TEXCOORD_1 (unwrap/lightmap_uvs.h)
    std::vector<GeneratedLayout> generatedLayouts;  // then, per scene mesh: what glTF out writes
    IrradianceVolume volume;  // the probes scene.glb carries (probes/irradiance_volume.h); empty: none
};

// The bake runs in two halves: the voxel stages, once per scene, and the receivers (each
// lightmap atlas, each camera), which read only what the voxel stages left. `bake` runs both
// in one process; a cluster bake (cluster/units.h) runs them as separate units, and the
// receivers of one atlas in bands of rows.

// Lightmap UVs for the shared atlas's meshes that have no TEXCOORD_1 (when the settings
// generate them), written into `scene`, and the lightmap settings they leave: the shared atlas
// at lightmap-res, or sized for lightmap-texel or `lightmap-res auto` (at least
// kAutoTexelPerVoxel × voxelSize per texel), or a group of their own appended where other
// meshes of the shared atlas have TEXCOORD_1 (which the settings' texel size sizes too).
// Charts under kSmallChartTexels that no neighbour took are a warning naming their meshes.
struct GeneratedUvs {
    LightmapSettings lightmap;
    std::optional<LightmapUvReport> report;  // none generated: empty
    std::vector<GeneratedLayout> layouts;    // then per scene mesh: what glTF out writes
};
GeneratedUvs generateSharedAtlasUvs(Scene& scene, const BakeSettings& settings, double voxelSize, Diagnostics& diagnostics);

struct VoxelStages {
    BakeResult result;          // every field but mips, lightmaps and images
    LightmapSettings lightmap;  // the settings', with the atlas generated lightmap UVs need
    IndirectLight indirect;     // the bounced voxels' mips and final gather (gather/gather.h)
    bool onGpu = false;         // the device the settings resolved to
    std::unique_ptr<ReceiverScene> tracing;
};

// The voxel size, generated lightmap UVs, voxelize, voxel light, visibility, bounces, mips and
// the final gather. `scene` leaves anchored to the voxel grid and with its generated UVs: the
// scene its receivers see. Checks that cost nothing come first (see bake below).
VoxelStages bakeVoxelStages(Scene& scene, const BakeSettings& settings, Diagnostics& diagnostics);

// The cameras a bake renders: the scene's, else one looking at its bounds.
std::vector<Camera> bakeCameras(const Scene& scene, const BakeSettings& settings);

// A camera's receivers as the bake shades its image: settings.imageSubsamples² primary rays
// per pixel, one sample per triangle a pixel sees, emitters and the sky seen directly on a
// finer grid (bake.cpp).
CameraReceivers bakeCameraReceivers(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                                    const BakeSettings& settings);

// A camera's lightmap-lit image (lightmap/lightmap_image.h) from `lightmaps`: what is seen
// directly as in bakeCameraReceivers, settings.lightmapImageSubsamples² lightmap reads a pixel.
Image bakeLightmapImage(const TraceScene& trace, const Bvh& bvh, const CameraModel& camera, const Scene& scene,
                        const SceneTriangles& triangles, const BakeSettings& settings,
                        const std::vector<ShippedLightmap>& lightmaps);

// The receivers' gather (gather/gather.h ReceiverGather) that a bake's settings make, on the
// device they resolved to. `tracing` and `light` are read, not copied: they must outlive it.
ReceiverGather bakeReceiverGather(const ReceiverScene& tracing, const IndirectLight& light, const BakeSettings& settings,
                                  bool onGpu);

// Auto spacing of the irradiance volume: this, finer where the scene's longest side would hold
// fewer than kAutoVolumeProbesAlong probes (a model on a table), and coarser where more than
// kAutoVolumeProbes would cover its bounds (a hall, a level), so the probes cost about what a
// room's do.
constexpr double kAutoVolumeSpacing = 0.5;  // metres
constexpr double kAutoVolumeProbesAlong = 8.0;
constexpr double kAutoVolumeProbes = 32768.0;
// The spacing settings.irradianceVolume asks for on `scene` (auto resolved); 0: no volume,
// also where the bake cannot light one (bake_settings.h lightsVolume).
double irradianceVolumeSpacing(const Scene& scene, const BakeSettings& settings);

// The irradiance volume of a baked scene into result.volume, timed as "irradiance volume".
void addIrradianceVolume(const Scene& scene, const ReceiverScene& tracing, const ReceiverGather& gather,
                         const BakeSettings& settings, BakeResult& result);

// A camera's image as the bake renders it: its receivers (bakeCameraReceivers) lit by `gather`.
BakedImage bakeCameraImage(const ReceiverGather& gather, const ReceiverScene& tracing, const Camera& camera,
                           const BakeSettings& settings);

// An atlas's finished images from its receivers' direct and indirect light: the total, and
// padding texels dilated from their covered neighbours in all three; then its chart seams
// (lightmap/lightmap_seams.h) measured and, with settings.lightmapStitch, stitched. `open`
// (ReceiverLighting::open, may be empty): a texel partly inside closed geometry holds the light
// of its open samples alone, and one wholly inside is filled as padding is, so that bilinear
// filtering beside it (a wall at a panel's foot) does not pull in black. `scene`: the one the
// atlas was built from (its TEXCOORD_1). A `shadowmask` (ReceiverLighting::shadowmask, may be
// empty) has its buried and unseen texels and its padding filled from their neighbours
// (lightmap/dilate.h fillUnseenShadowmask), then is stitched as the light is.
BakedLightmap finishLightmap(const LightmapAtlas& atlas, const Image& direct, const Image& indirect, const Image& open,
                             const Scene& scene, const BakeSettings& settings, const Image& shadowmask = Image());

// Whether a bake with these settings renders its cameras' lightmap-lit images: it asks for
// them and bakes both lightmaps and images.
bool makesLightmapImages(const BakeSettings& settings);

// Each camera image's lightmap-lit twin (lightmap/lightmap_image.h) into result.images[c].lightmapped,
// from result.lightmaps as they ship; the cameras are bakeCameras(scene, settings), the order
// of result.images. A local bake and a cluster bake's merge both call this.
void addLightmapImages(const Scene& scene, const ReceiverScene& tracing, const BakeSettings& settings,
                       BakeResult& result);

// Checks that cost nothing (settings ranges, voxel count, memory) run first; throws
// SettingsError / InputError before any expensive stage.
// The scene is anchored to the voxel grid first (voxelize.h anchorToVoxelGrid); outputs that
// carry positions (the grids' transform) keep it where it was in world space.
BakeResult bake(Scene scene, const BakeSettings& settings, Diagnostics& diagnostics);

// What a bake of `scene` with `settings` at `voxelSize` is estimated to take: voxels,
// triangles, receivers and images (against core/memory.h availableMemoryBytes); an infinite
// voxel size counts no voxels.
double estimateBakeMemory(const Scene& scene, const BakeSettings& settings, double voxelSize);

// Gives every light without a bake mode of its own (LightBake::Unset) the setting's, and each
// LightBake::Shadowmask light its channel of the shadowmask, in the scene's order. InputError
// naming the scene and the light for a fifth shadowmask light, or one a glTF file places by
// several nodes (one channel, one place).
void resolveLightBake(Scene& scene, LightBake setting);

// Refuses, before any work, a bake whose estimated memory exceeds what the machine has
// available (SettingsError with both figures).
void checkMemoryBudget(const Scene& scene, const BakeSettings& settings, double voxelSize);

// Refuses, before the voxel size is chosen, a scene whose triangles, lightmaps and images alone
// (no voxels yet) would need more than `available` bytes (SettingsError naming the file and
// the triangles, with both figures).
void checkSceneMemoryBudget(const Scene& scene, const BakeSettings& settings, double available);

}  // namespace vl
