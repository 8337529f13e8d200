// The final gather in a lightmap's own texel space: takes an atlas's receivers, the voxels' light
// (level 0 of the mips, the face light the rays read and the bright patches split off it), the
// BVH and the traced scene; gives each covered texel's indirect irradiance.
//
// Records are gathered at the texels of a lattice every `spacing` texels (each by n × n rays
// reading the voxels' light where they hit, bake/ray_gather.h, plus the bright patches' sampled
// light, bake/bright_patches.h) and interpolated bilinearly between the lattice's records around
// a texel that lie on its own surface: near in space, facing its way, in its plane. A texel
// sample no record applies to (a chart narrower than the lattice, a corner) is a record itself.
//
// Why not the voxel gather points (cone/irradiance_cache.h): a point stands for one side of a
// 4³-voxel cell, so two surfaces facing one way within 20 cm of each other (a sofa's arm and its
// cushion) share it, and the texels of both take its light in blocks a cell wide. A texel's
// records lie on its own chart, which is one surface.
#pragma once

#include "bake/bright_patches.h"
#include "bake/receivers.h"
#include "cone/radiance_mips.h"
#include "core/image.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <vector>

namespace vl {

struct TexelGatherSettings {
    int spacing = 0;        // texels between records; 0: about 1.5 voxels in the atlas's texels (1 … 8)
    int raysPerAxis = 14;   // each record's n × n fan
    int brightSamples = 64; // the bright patches' shadow rays per record
};

// Indirect irradiance / π per texel (RGB, W/(m²·sr): the lightmap's convention) of the atlas's
// covered texels in rows [rowBegin, rowEnd); other texels 0. A texel's value does not depend on
// the rows shaded with it. `faces`: the light the rays read (the voxels' face radiance less the
// bright patches'). A texel without direct light (`direct`, E/π per texel; null: any) may lie
// inside closed geometry (shade_element.h isBuried): a record there gathers nothing and gives
// nothing, and a sample beside such a record is tested itself. TBB-parallel; the same bytes at
// any thread count.
Image gatherAtlasIndirect(const LightmapAtlas& atlas, int rowBegin, int rowEnd, const Image* direct,
                          const MipView& mips, const std::vector<FaceRadiance>& faces, const BrightPatchSplit& bright,
                          const BvhView& bvh, const TraceSceneView& scene, const TexelGatherSettings& settings);

// The spacing the atlas's records take for `settings.spacing` 0: about 1.5 voxels of the texels'
// median size in the scene (1 … 8).
int texelGatherSpacing(const LightmapAtlas& atlas, float voxelSize, const TexelGatherSettings& settings);

}  // namespace vl
