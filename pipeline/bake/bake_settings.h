// Every setting of a bake, by stage, with its default. Each is a command-line flag
// (--name value) and a job-file key ("name": value) through bakeSettingsTable().
#pragma once

#include "bake/direct_light.h"
#include "bake/receivers.h"
#include "bake/settings_table.h"
#include "cone/cone_settings.h"
#include "cuda/device_choice.h"
#include "lighting/lighting.h"
#include "voxel/voxel_scene.h"

#include <string>

namespace vl {

struct BakeOutputs {
    bool lightmaps = true;  // lightmap atlases (EXR total/direct/indirect, PNG preview)
    bool images = true;     // camera images (EXR + PNG + AOVs)
    bool grids = true;      // grids.vdb with every channel and the radiance mips
};

struct BakeSettings {
    VoxelSettings voxel;
    LightingSettings lighting;
    ConeSettings cone;
    // Voxel-to-voxel bounces before the final gather (the receiver's gather is one more).
    // 4: the lowest lightmap error on the Cycles Cornell box (relRMSE 9.1%, against 10.0% at
    // 2 and 9.5% at 8; `voxlight bench` regenerates the sweep).
    int bounces = 4;
    LightmapSettings lightmap;
    DirectLightSettings direct;
    int imageWidth = 256;
    int imageHeight = 256;
    int imageSubsamples = 2;  // n × n primary rays per pixel
    BakeOutputs outputs;
    bool strict = false;  // every warning is an error
    bool quiet = false;   // no progress on stderr
    // [added by cuda] Where voxel lighting and receiver shading run (cuda/device_choice.h);
    // cpu by default, so a bake's bytes do not depend on the machine.
    cuda::DeviceChoice device = cuda::DeviceChoice::Cpu;
};

const SettingsTable<BakeSettings>& bakeSettingsTable();

// Checks every range (SettingsError naming the setting); runs before any work.
void validateBakeSettings(const BakeSettings& settings);

// "name=value, …" of every setting, for reports and file metadata.
std::string describeBakeSettings(const BakeSettings& settings);

}  // namespace vl
