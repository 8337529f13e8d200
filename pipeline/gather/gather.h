// The indirect light's stage. Takes the lit voxels (lighting/: their face radiance), the points
// on their surfaces (lighting/surface_points.h) and what rays meet (gather_scene.h); gives the
// voxels their bounces, and the radiance mips and final gather the receivers read:
//   visibility (rays or cones) → bounces → mips → final gather (bright patches apart)
// then lights receivers from them (ReceiverGather): a lightmap atlas's rows, a camera's
// samples. Its settings: gather_settings.h; its parts: one header each in this folder.
#pragma once

#include "cone/radiance_mips.h"
#include "core/stage_time.h"
#include "gather/bright_patches.h"
#include "gather/gather_device.h"
#include "gather/gather_scene.h"
#include "gather/gather_settings.h"
#include "gather/irradiance_cache.h"
#include "gather/ray_gather.h"
#include "gather/shade_receivers.h"
#include "lighting/direct_light.h"
#include "lighting/surface_points.h"
#include "receivers/lightmap_sides.h"
#include "receivers/receiver_scene.h"
#include "receivers/receivers.h"
#include "voxel/voxel_scene.h"

#include <vector>

namespace vl {

// What the receivers read of the voxels' light.
struct IndirectLight {
    GatherVisibilityChoice visibility;  // rays or cones, and why
    // The voxels' final light: level 0 alone where rays read it from the final gather's
    // points, every level where cones (or receivers without points) read it.
    RadianceMips mips;
    IrradianceCache cache;    // the final gather's points and irradiance; none without one
    BrightPatchSplit bright;  // its bright patches, and the light its rays read
};

// Whether the final gather needs the voxels' surface points (voxelSurfacePoints): its bright
// patches and the lights at its rays' hits are taken from them.
bool gatherNeedsSurfacePoints(const GatherSettings& settings, const GatherInputs& inputs, bool punctualLights);

// Runs the stage on `voxels` (their light gains the bounces), each step timed into `stages`
// ("visibility", "bounces", "mips", "gather"). `surfacePoints`: as gatherNeedsSurfacePoints
// asks (else may be empty). `device`: where cones may run; null: the CPU. The same bytes at
// any thread count on the CPU.
IndirectLight gatherIndirect(VoxelScene& voxels, const VoxelSurfacePoints& surfacePoints, const GatherScene& scene,
                             const GatherSettings& settings, const GatherInputs& inputs, const GatherDevice* device,
                             std::vector<StageTime>& stages);

// The mips of voxels whose light is final, as gatherIndirect leaves them: level 0 alone where
// rays read them from final gather points (`gathered`), every level otherwise.
RadianceMips receiverMips(const VoxelScene& voxels, GatherVisibility visibility, bool gathered);

// What gatherIndirect left, rebuilt from voxels whose light is final and the final gather's
// irradiance (`gathered`, one per point; null: there was no final gather): the points placed
// and linked again, the bright patches split again, the same bytes. A cluster's receiver units
// read this. InputError when `gathered` does not hold one value per point.
IndirectLight restoreIndirectLight(const VoxelScene& voxels, const GatherVisibilityChoice& visibility,
                                   const std::vector<vec3>* gathered, const VoxelSurfacePoints& surfacePoints,
                                   const GatherScene& scene, const GatherSettings& settings, const GatherInputs& inputs);

// Receivers lit from an IndirectLight: direct light per sample (lighting/direct_light.h) and
// indirect light from the final gather's points, or, for lightmaps whose final gather went by
// rays on the CPU, from records on the atlas's own texels (texel_gather.h).
class ReceiverGather {
public:
    // Everything given is read, not copied: it must outlive this.
    ReceiverGather(const ReceiverScene& tracing, const IndirectLight& light, const GatherSettings& settings,
                   const DirectLightSettings& direct, LightmapSide side, bool quiet, const GatherDevice* device);
    ReceiverGather(const ReceiverGather&) = delete;  // its cache view points into itself
    ReceiverGather& operator=(const ReceiverGather&) = delete;
    // Rows [rowBegin, rowEnd) of an atlas; the other rows stay 0. A texel's value does not
    // depend on which rows are lit with it.
    ReceiverLighting atlasRows(const LightmapAtlas& atlas, int rowBegin, int rowEnd) const;
    // Every element of a camera's receivers.
    ReceiverLighting cameraSamples(const SurfaceSampleSet& receivers) const;
    // Lightmaps gather in their own texel space: the setting's choice, where the final gather
    // went by rays on the CPU.
    bool texelGather() const;
    // Points in open space (an irradiance volume's probes, probes/irradiance_volume.h), each
    // lit as a surface facing each of `normals` (unit, the scene's local frame) would be: per
    // point, normal after normal, E (W/m²) of all the light a lightmap texel holds but the
    // punctual lights' direct light, which the caller takes exactly. Its indirect light and
    // sky by a fan of raysPerAxis² rays as a lightmap's records gather them (gather/ray_gather.h,
    // the near field and the lights at hits included), its bright patches' by their shadow
    // rays, and the emitters' direct light as a texel's (lighting/direct_light.h). Point k's
    // fans are seeded by firstIndex + k (a batch's place among all the points): the same bytes
    // at any thread count and any batching.
    std::vector<vec3> openPoints(const std::vector<vec3>& points, const std::vector<vec3>& normals, int raysPerAxis,
                                 uint64_t firstIndex = 0) const;

private:
    const ReceiverScene& tracing_;
    const IndirectLight& light_;
    const GatherSettings& settings_;
    const DirectLightSettings& direct_;
    LightmapSide side_;
    bool quiet_;
    const GatherDevice* device_;
    MipView mipView_;
    IrradianceCacheView cacheView_;
    const IrradianceCacheView* gathered_;
};

}  // namespace vl
