// Every setting of a bake, by stage, with its default. Each is a command-line flag
// (--name value) and a job-file key ("name": value) through bakeSettingsTable().
#pragma once

#include "bake/lightmap_sides.h"
#include "bake/bright_patches.h"
#include "lighting/direct_light.h"
#include "bake/gather_visibility.h"
#include "bake/receivers.h"
#include "bake/settings_table.h"
#include "cone/cone_settings.h"
#include "cuda/device_choice.h"
#include "lighting/lighting.h"
#include "voxel/voxel_scene.h"

#include <string>

namespace vl {

struct Scene;

struct BakeOutputs {
    bool lightmaps = true;  // lightmap atlases (EXR total/direct/indirect, PNG preview)
    bool images = true;     // camera images (EXR + PNG + AOVs)
    bool grids = true;      // grids.vdb with every channel and the radiance mips
    bool gltf = true;       // scene.glb: the input scene with its lightmaps (export/gltf_export.h)
    // Each camera lit by the lightmaps as scene.glb carries them (bake/lightmap_image.h): what
    // the viewer shows, to measure the lightmap by. Needs lightmaps and images.
    bool lightmapImage = true;
};

// Where a lightmap's indirect light is gathered.
enum class LightmapGather {
    Texels,  // records on the atlas's own texel lattice (bake/texel_gather.h)
    Points,  // the voxel gather points, interpolated (cone/irradiance_cache.h), as images are
};

struct BakeSettings {
    // Neither a voxel size nor a resolution: the bake chooses one from the scene
    // (bake/voxel_size.h); a user's voxel-size or resolution wins.
    VoxelSettings voxel{0.0, 0};
    LightingSettings lighting;
    // The receivers' final gather: 32 cones. It sees small bright regions (the hot spot a
    // point light makes on a ceiling) directly, and a cone set too sparse for them misses or
    // doubles them by turns: on the Cycles point-light Cornell box 16 cones leave the
    // lightmap at 13.3% relRMSE and the image at 13.4%, 32 at 8.9% and 9.5% (README).
    ConeSettings cone = ConeSettings{32};
    // Voxel-to-voxel bounces before the final gather (the receiver's gather is one more),
    // each with bounceCones cones. The bounces gather light already spread over many voxels
    // and every voxel turns its set differently (cone_trace.h coneTurn), so 6 cones do: on
    // the Cycles Cornell boxes 8 bounces of 6 cones give lower error (lightmaps 6.6% / 8.9%,
    // quad / point) than 4 of 16 (7.7% / 9.6%) in less time (14 s against 17 s on the quad
    // box, 2 cores). `voxlight bench` regenerates the sweep.
    int bounces = 8;
    int bounceCones = 6;
    // After the bounces, the rest of the series as a geometric tail (cone/bounces.h): a
    // bright interior keeps its light for many bounces (zdm2's image error: 46.6% after 8
    // bounces, 28.0% with the tail; `voxlight bench tools/bench/zdm2.json --vct
    // 'bounce-tail=false'`, 2026-11-24).
    bool bounceTail = true;
    // Where indirect irradiance is gathered (cone/irradiance_cache.h): at one point per
    // surface side of each block of 2^level voxels per axis, interpolated at every texel,
    // pixel sample and voxel. The bounces gather at bounceGatherLevel, the receivers at
    // gatherLevel (−1: every receiver sample gathers its own cones, as a reference for the
    // interpolation's error). On the Cycles Cornell boxes (lightmap / image relative RMSE,
    // quad; point): gather level 3: 5.82% / 7.87%; 7.56% / 8.67%. Level 2: 5.91% / 7.88%;
    // 7.76% / 8.99%. Every sample: 6.42% / 8.54%; 9.05% / 10.83%. Bounces at level 2 instead of
    // 3: 5.85% / 7.86%; 7.63% / 8.69%. The interpolation averages the cone sets of several
    // points, each turned its own way, and that average errs less than any one set.
    // By rays the cells' size is what the boxes' error follows, more than the voxels': 63
    // voxels at level 2 gave the quad box's lightmap 2.70% in 0.14 s, at level 3 3.26% in
    // 0.11 s, and 111 voxels at level 3 (the default until 2026-11-27) 2.48% in 0.21 s; the
    // two rooms at 103 / 127 voxels 2.48% / 2.24% at level 2, 3.06% (111) / 2.63% at level 3
    // (`voxlight bench`, 2026-11-27). Level 2 with the voxel size the free paths choose
    // (bake/voxel_size.h, 63 voxels on the boxes) gives 2.70% / 2.69% against 2.48% / 2.53% in
    // 0.6× the time, and the best error² × time of each scene's resolution sweep.
    int gatherLevel = 2;
    int bounceGatherLevel = 2;
    // Cone sets per gather point of the final gather, turned by 1/n turn from one another
    // (irradiance_cache.h gatherAtPoint): 2 halve the gaps between the cones that a small
    // bright region (a point light's hot spot) falls into (one set: 5.99% / 8.16%;
    // 8.05% / 9.66%).
    int gatherTurns = 2;
    // The final gather's bright patches (bake/bright_patches.h): faces brighter than `factor`
    // times the mean face, merged per 8³ voxels, gathered by shadow rays at the gather points
    // and left out of the cones' mips (factor 0: none). Lightmap / image relative RMSE on the
    // Cycles Cornell boxes (quad; point) and zdm2's image against the path tracer, 2026-11-24:
    // none: 5.31% / 6.45%; 8.18% / 9.43%; 28.3%. Factor 2: 4.26% / 4.97%; 5.16% / 5.80%;
    // 30.0%. Factor 8 (default): 4.74% / 5.39%; 5.56% / 5.90%; 25.8%. Factor 2 suits the
    // boxes, whose bright patches are small and far from the receivers; on zdm2 it takes in
    // wide lit walls next to the receivers, where one shadow ray per patch is too coarse.
    // A gather at every sample (gather level −1) keeps all the light in the cones.
    BrightPatchSettings brightPatches;
    // Rays or cones for the bounces' and the final gather's visibility (GatherVisibility), and
    // the rays per axis of each point's n × n fan when rays: 14 × 14 at every bounce and at
    // the final gather. The bounces trace their rays once (bake/ray_gather.h rayTransport);
    // when the final gather sends as many rays from the same points it applies the same
    // transport, so the bounces' rays cost only their time, once. Lightmap / image relative
    // RMSE on the Cycles Cornell boxes (quad; point) at 111 voxels, `voxlight bench`,
    // 2026-11-24: rays 2.9% / 4.3%; 3.0% / 3.9%. Cones 5.9% / 6.3%; 5.8% / 6.4%. 8 × 8 rays at
    // the final gather: 3.3% / 4.7%; 3.4% / 4.5% (run of dec5125). Bounces of 8 × 8 rays
    // (before the transport) left the point box at 3.1% / 4.0% and the bright sealed rooms
    // of scenes/two_rooms.gltf 2.6% too bright (16 × 16: 2.7% / 3.6%, +1.3%). 14 × 14 since
    // 2026-11-27: the same Cornell errors as 16 × 16 (2.5% / 4.1% quad, `voxlight bench`;
    // sixteen turns of it 2.99% at worst against 2.97%, `build/accuracy/accuracy_rotations`),
    // the two rooms' lightmap 3.3% against 3.2% (`voxlight bench scenes/two_rooms.gltf`), for
    // a quarter fewer rays: the bench's default 0.24 s against 0.25 s (12 × 12 took a turned
    // quad box to 3.01%).
    GatherVisibility gatherVisibility = GatherVisibility::Auto;
    // Texels by default where the final gather goes by rays: a voxel gather point stands for a
    // 4³-voxel cell's side, and two surfaces facing one way in a cell (a sofa's arm and its
    // cushion) took its light in blocks (docs/accuracy.md). texelGatherSpacing 0: automatic.
    LightmapGather lightmapGather = LightmapGather::Texels;
    int texelGatherSpacing = 0;
    int lightmapFilterPasses = 3;  // the texel records' edge-stopping filter (bake/texel_gather.h); 0: off
    bool lightmapGradients = true;  // the texel records' rotation gradients (bake/texel_gather.h)
    LightmapSide lightmapSide = LightmapSide::Inside;  // a double-sided surface's side lightmaps hold (bake/lightmap_sides.h)
    int gatherRays = 14;
    int bounceRays = 14;
    LightmapSettings lightmap;
    // Chart seams stitched after dilation (bake/lightmap_seams.h): the two sides of a surface
    // split between charts read one value, so the viewer shows no line there.
    bool lightmapStitch = true;
    // hit-light exact: the lightmap records' rays take the punctual lights' reflection at their
    // hits by a shadow ray, not from the hit's voxel (whose face averages shaded and sunlit
    // surfaces a few centimetres apart); with punctual lights the bright patches are then off.
    // docs/accuracy.md.
    bool hitLightExact = true;
    // many-lights tree: past 64 point lights or emissive triangles, receivers and voxels take a
    // cut of a tree of them (trace/light_tree.h); each: every receiver visits every light, the
    // exact sums. docs/many-lights.md.
    bool lightTrees = true;
    // near-field: a lightmap record's ray that hits a surface nearer than this many voxels
    // traces its light on instead of reading the voxel there (bake/ray_gather.h FanExtras);
    // 0: every hit reads its voxel. docs/accuracy.md.
    float nearFieldVoxels = 3.0f;
    DirectLightSettings direct;
    // A uniform sky's radiance, W/(m²·sr) (scene.h Sky; glTF has none): zero, no sky.
    vec3 sky{0.0f};
    // An equirectangular HDR sky image (trace/sky.h), added to `sky`: its file ("": none),
    // its turn about +Y in degrees (counterclockwise seen from above) and its scale.
    std::string skyImage;
    float skyRotation = 0.0f;
    float skyIntensity = 1.0f;
    int imageWidth = 256;
    int imageHeight = 256;
    int imageSubsamples = 2;  // n × n primary rays per pixel
    // n × n primary rays per pixel of the lightmap-lit image, each reading the lightmap at its
    // own hit: the pixel's box, as the references filter theirs (bake/lightmap_image.h).
    int lightmapImageSubsamples = 4;
    BakeOutputs outputs;
    // TEXCOORD_1 for scenes that have none (unwrap/lightmap_uvs.h; bake.cpp needsLightmapUvs).
    bool generateLightmapUvs = true;
    // Every material as Lambert (metallic 0, no transmission, its base colour), for the bake and
    // for the references the bench and `voxlight reference` trace: the transport alone, without
    // the light a diffuse lightmap cannot hold (a mirror's image, a glass's refraction).
    bool lambertMaterials = false;
    bool strict = false;  // every warning is an error
    bool filesOutsideScene = false;  // read uris that leave the scene's folder (LoadOptions)
    bool quiet = false;   // no progress on stderr
    // [added by cuda] Where voxel lighting and receiver shading run (cuda/device_choice.h);
    // cpu by default, so a bake's bytes do not depend on the machine.
    cuda::DeviceChoice device = cuda::DeviceChoice::Cpu;
};

const SettingsTable<BakeSettings>& bakeSettingsTable();

// The cone settings of the voxel-to-voxel bounces: `cone` with bounceCones cones.
ConeSettings bounceConeSettings(const BakeSettings& settings);

// Whether the lightmap records' rays take the punctual lights at their hits: hit-light exact,
// in a scene with punctual lights, lit by voxel-visibility rays (whose lights it takes apart).
bool takesLightsAtHits(const BakeSettings& settings, bool punctualLights);
// The bright patches the final gather splits off: the settings', none where the rays take the
// lights at their hits.
BrightPatchSettings gatherBrightPatches(const BakeSettings& settings, bool punctualLights);

// Checks every range (SettingsError naming the setting); runs before any work.
void validateBakeSettings(const BakeSettings& settings);

// "name=value, …" of every setting, for reports and file metadata.
std::string describeBakeSettings(const BakeSettings& settings);

// The settings' sky into the scene's (scene.h Sky), the image read from its file (InputError
// naming it); a scene keeps its own sky where the settings give none.
void applySkySettings(const BakeSettings& settings, Scene& scene);

}  // namespace vl
