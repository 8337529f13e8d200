// The final gather in a lightmap's own texel space: takes an atlas's receivers, the voxels' light
// (level 0 of the mips, the face light the rays read and the bright patches split off it), the
// BVH and the traced scene; gives each covered texel's indirect irradiance and the sky's, from
// records on a lattice of the atlas's texels smoothed by an edge-stopping filter.
//
// Why not the voxel gather points (gather/irradiance_cache.h): a point stands for one side of a
// 4³-voxel cell, so two surfaces facing one way within a cell of each other (a sofa's arm and
// its cushion) share it, and the texels of both took its light in blocks a cell wide. Why the
// sky here: a texel sees a window's sky through a few of its own rays, and its neighbours
// through others (a speckled sofa); the records' rays see it as they see the rest, filtered
// (docs/decisions.md, "Texel records: how the lightmap gathers").
#pragma once

#include "gather/bright_patches.h"
#include "receivers/receivers.h"
#include "cone/radiance_mips.h"
#include "core/image.h"
#include "lighting/direct_light.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <vector>

namespace vl {

struct TexelGatherSettings {
    int spacing = 0;         // texels between records; 0: texelGatherSpacing's choice (1 … 8)
    int raysPerAxis = 0;     // each record's n × n fan; 0: texelGatherRays's choice
    int brightSamples = 64;  // the bright patches' shadow rays per record
    int filterPasses = 3;    // the edge-stopping filter's passes over the lattice (steps 1, 2, 4 …); 0: none
    bool gatherSky = true;     // the records gather the sky's direct light; false: the caller lights samples by it
    int skyDrawsPerAxis = 10;  // under an image sky, draws from its image per record (n × n)
    DirectLightSettings direct;  // the direct light that tells a record is open (lights, emitters: no sky)
    const std::vector<FaceRadiance>* lightsAtHits = nullptr;  // hit-light exact (gather/ray_gather.h FanExtras)
    float nearField = 0.0f;  // world units: hits nearer than it traced on, not read (gather/ray_gather.h FanExtras)
    // Each sample takes its records' light turned to its own normal by their rotation
    // gradients (gather/ray_gather.h RotationGradients, smoothed by the filter as their light is).
    bool gradients = true;
    uint64_t seed = 0;  // turns the records' fans and draws (BakeSettings::lightmapSeed)
};

struct TexelGather {
    Image indirect;  // RGB E_indirect / π per covered texel (W/(m²·sr), the lightmap's convention)
    Image sky;       // RGB E_sky / π: the sky's direct light
    Image open;      // 1 channel: the weight of each covered texel's samples that are not buried
};

// Records are gathered at the texels of a lattice every `spacing` texels: n × n rays reading the
// voxels' light where they hit (gather/ray_gather.h) and the sky where they leave the scene, plus
// the bright patches' sampled light (gather/bright_patches.h). The lattice's records are smoothed
// by a few passes of an edge-stopping filter (à-trous, as Dammertz et al. 2010 and SVGF):
// records on one surface (near in space, facing one way, in one plane) whose difference the
// records' own noise explains are averaged; a difference beyond it, or another surface, stops
// the filter. Each texel sample then takes the lattice's records around it that lie on its own
// surface, bilinearly, each record's light turned to the sample's normal by its rotation
// gradient (gather/ray_gather.h RotationGradients); a sample no record applies to (a chart
// narrower than the lattice, a corner) shares a record of its own with the samples of its
// s × s block on its surface. A sample inside closed geometry (shade_element.h isBuried) takes
// no light: where a block's record is buried, the block's samples that are open take records of
// their own.
//
// Covered texels of rows [rowBegin, rowEnd); other texels 0. A texel's value does not depend on
// the rows gathered with it: the lattice's records are gathered past the band as far as the
// filter reads. `faces`: the light the rays read (the voxels' face radiance less the bright
// patches'). A record that neither a light, an emitter nor the sky reaches may lie inside closed
// geometry (shade_element.h isBuried): then it gathers nothing and gives nothing, and a sample
// beside it that its texel's direct light (`direct`, E/π, lights and emitters; null: none) does
// not show open is tested itself. TBB-parallel; the same bytes at any thread count.
TexelGather gatherAtlasTexels(const LightmapAtlas& atlas, int rowBegin, int rowEnd, const Image* direct,
                              const MipView& mips, const std::vector<FaceRadiance>& faces, const BrightPatchSplit& bright,
                              const BvhView& bvh, const TraceSceneView& scene, const TexelGatherSettings& settings);

// The spacing the atlas's records take for `settings.spacing` 0: about 0.6 voxels of the texels'
// median size in the scene (1 … 8).
int texelGatherSpacing(const LightmapAtlas& atlas, float voxelSize, const TexelGatherSettings& settings);

// The rays per axis of each record's fan: `settings.raysPerAxis`, or for 0 the default 8.
int texelGatherRays(const TexelGatherSettings& settings);

}  // namespace vl
