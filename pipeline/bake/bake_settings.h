// Every setting of a bake, by stage, with its default. Each is a command-line flag
// (--name value) and a job-file key ("name": value) through bakeSettingsTable().
#pragma once

#include "receivers/lightmap_sides.h"
#include "lighting/direct_light.h"
#include "gather/gather_settings.h"
#include "receivers/receivers.h"
#include "core/settings_table.h"
#include "cone/cone_settings.h"
#include "cuda/device_choice.h"
#include "lighting/lighting.h"
#include "probes/irradiance_volume.h"
#include "voxel/voxel_scene.h"

#include <string>

namespace vl {

struct Scene;

struct BakeOutputs {
    bool lightmaps = true;  // lightmap atlases (EXR total/direct/indirect, PNG preview)
    bool images = true;     // camera images (EXR + PNG + AOVs)
    bool grids = true;      // grids.vdb with every channel and the radiance mips
    bool gltf = true;       // scene.glb: the input scene with its lightmaps (export/gltf_export.h)
    // Each camera lit by the lightmaps as scene.glb carries them (lightmap/lightmap_image.h): what
    // the viewer shows, to measure the lightmap by. Needs lightmaps and images.
    bool lightmapImage = true;
};

struct BakeSettings {
    // Neither a voxel size nor a resolution: the bake chooses one from the scene
    // (bake/voxel_size.h); a user's voxel-size or resolution wins.
    VoxelSettings voxel{0.0, 0};
    LightingSettings lighting;
    // The indirect light's stage: bounces, gather points, visibility, the lightmap's records.
    GatherSettings gather;
    LightmapSide lightmapSide = LightmapSide::Inside;  // a double-sided surface's side lightmaps hold (receivers/lightmap_sides.h)
    LightmapSettings lightmap;
    // Chart seams stitched after dilation (lightmap/lightmap_seams.h): the two sides of a surface
    // split between charts read one value, so the viewer shows no line there.
    bool lightmapStitch = true;
    // many-lights tree: past 64 point lights or emissive triangles, receivers and voxels take a
    // cut of a tree of them (trace/light_tree.h); each: every receiver visits every light, the
    // exact sums. docs/many-lights.md.
    bool lightTrees = true;
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
    // own hit: the pixel's box, as the references filter theirs (lightmap/lightmap_image.h).
    int lightmapImageSubsamples = 4;
    BakeOutputs outputs;
    // The irradiance volume scene.glb carries (probes/irradiance_volume.h): its spacing in
    // metres; 0: none; negative: auto (bake.h irradianceVolumeSpacing).
    IrradianceVolumeSettings irradianceVolume{-1.0};
    // TEXCOORD_1 for scenes that have none (unwrap/lightmap_uvs.h; bake.cpp needsLightmapUvs).
    bool generateLightmapUvs = true;
    // Every material as Lambert (metallic 0, no transmission, its base colour), for the bake and
    // for the references the bench and `voxlight reference` trace: the transport alone, without
    // the light a diffuse lightmap cannot hold (a mirror's image, a glass's refraction).
    bool lambertMaterials = false;
    // The bake mode of every punctual light that does not give its own (scene.h LightBake):
    // All bakes its direct light too; Indirect leaves that to the engine.
    LightBake lightBake = LightBake::All;
    bool strict = false;  // every warning is an error
    bool filesOutsideScene = false;  // read uris that leave the scene's folder (LoadOptions)
    bool quiet = false;   // no progress on stderr
    // Where voxel lighting and receiver shading run (cuda/device_choice.h);
    // cpu by default, so a bake's bytes do not depend on the machine.
    cuda::DeviceChoice device = cuda::DeviceChoice::Cpu;
};

const SettingsTable<BakeSettings>& bakeSettingsTable();

// Whether the bake can light an irradiance volume: its probes read the final gather (gather/
// gather.h ReceiverGather::openPoints), and scene.glb carries them.
bool lightsVolume(const BakeSettings& settings);

// Checks every range (SettingsError naming the setting); runs before any work.
void validateBakeSettings(const BakeSettings& settings);

// What the gather stage follows of the other stages' settings (gather/gather_settings.h).
GatherInputs gatherInputs(const BakeSettings& settings);

// "name=value, …" of every setting, for reports and file metadata.
std::string describeBakeSettings(const BakeSettings& settings);

// The settings' sky into the scene's (scene.h Sky), the image read from its file (InputError
// naming it); a scene keeps its own sky where the settings give none.
void applySkySettings(const BakeSettings& settings, Scene& scene);

}  // namespace vl
