// glTF out: takes the glTF file a bake read and the lightmaps it baked, gives one .glb a
// glTF loader and a browser read as it is: the input scene node for node and material for
// material, every buffer and image inside the file, and each lightmapped material pointing
// at its lightmap through MOZ_lightmap (the material extension Mozilla Hubs and its editors
// read: `index` the texture, `texCoord` 1, `intensity` the RGBM range; lightmap_encoding.h).
// The nodes are the file's own, so the scene sits where it sat (the bake's local frame is
// not written).
//
// A material whose primitives all lie in one lightmap carries it in place; a material shared
// by primitives of several lightmaps, or by lightmapped and unlit primitives, is copied once
// per lightmap ("name (lightmap NAME)") and those primitives point at their copy. A glTF
// mesh placed by several nodes shares one material per primitive: its instances must share
// one lightmap, and a warning names a primitive whose instances do not.
#pragma once

#include "core/diagnostics.h"
#include "export/lightmap_encoding.h"
#include "scene/scene.h"

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace vl {

// A mesh's TEXCOORD_1 that the bake made (unwrap/lightmap_uvs.h), for glTF out to write into
// the mesh's primitive with the vertices split as the bake split them (source.vertices).
struct GeneratedLayout {
    Mesh::Source source;
    std::vector<vec2> uv1;
    std::vector<uint32_t> indices;  // triangles in the bake's winding (source.mirrored: swapped)
};

struct ExportedLightmap {
    std::string name;              // the atlas ("lightmap", a group's name): the image's name
    std::vector<uint32_t> meshes;  // indices into Scene::meshes baked into it
    RgbmImage encoded;
    // Its shadowmask, 8-bit linear RGBA of encoded's size (lightmap_encoding.h shadowmaskBytes);
    // empty: none.
    std::vector<uint8_t> shadowmask;

    ExportedLightmap() = default;
    ExportedLightmap(std::string name_, std::vector<uint32_t> meshes_, RgbmImage encoded_,
                     std::vector<uint8_t> shadowmask_ = {})
        : name(std::move(name_)), meshes(std::move(meshes_)), encoded(std::move(encoded_)),
          shadowmask(std::move(shadowmask_)) {}
};

// An irradiance volume as scene.glb carries it (VOXLIGHT_irradiance_volume at the file's top,
// docs/irradiance-volume.md): every image counts.x wide and counts.y · counts.z tall, probe
// (i, j, k) at column i, row j·counts.z + k. `mean`: A (E/π) in RGBM; `gradient` per world axis
// 8-bit linear RGB, B/A per channel as 2 · (code − 127) / 127 (127: none); `valid` 8-bit grey, 255 open.
// More probes than this are refused, baked (SettingsError) or read (InputError).
constexpr size_t kMaxVolumeProbes = 4u << 20;

struct ExportedIrradianceVolume {
    glm::dvec3 origin{0.0}, spacing{0.0};
    glm::ivec3 counts{0};
    RgbmImage mean;
    std::array<std::vector<uint8_t>, 3> gradient;  // RGB, 3 bytes a probe
    std::vector<uint8_t> valid;                    // 1 byte a probe
    // Suns kept apart (probes/irradiance_volume.h kVolumeSuns): direction of travel (world,
    // unit) and E/π facing it; their visibility per probe, RGBA (channel s: sun s; 255 = 1).
    struct Sun {
        vec3 direction{0.0f, -1.0f, 0.0f};
        vec3 irradiance{0.0f};
        bool drawnByEngine = false;
    };
    std::vector<Sun> suns;
    std::vector<uint8_t> sunVisibility;  // 4 bytes a probe; empty without suns
};

// The irradiance volume a scene.glb carries; InputError naming the file and what is wrong
// (no volume, an image missing or not its size).
ExportedIrradianceVolume readIrradianceVolume(const std::string& path);

// Writes `path` (atomically) from the glTF file `source` re-read; `meshes` are the scene's
// meshes as loaded from it (Scene::meshes' sources, by the indices the lightmaps use).
// `layouts`, when not empty, holds one per mesh: the generated TEXCOORD_1 to write (a mesh
// without uv1 is left as it is). A glTF mesh that several nodes place gets a copy per further
// node, since each instance has charts of its own. A primitive with morph targets or sparse
// attributes keeps its own vertices and no lightmap (a warning). InputError naming the file
// when the source no longer reads; Error naming `path` when it cannot be written.
// `addedCameras` (a job file's, in world space) become camera nodes at the scene's root, so a
// viewer can show the bake's images' views. A `sky` (scene.h Sky::meanRadiance; zero: none), which glTF
// cannot hold, goes into the scene's extras as {"voxlight": {"sky": [r, g, b]}} (radiance,
// W/(m²·sr)): what `voxlight view` draws where nothing is.
// Every KHR_lights_punctual light says what the lightmaps hold of it, in the light's
// VOXLIGHT_light_bake extension {"mode": "all" | "indirect" | "shadowmask", "channel": 0..3}
// (docs/light-bake-modes.md). `bakedLights`, when given, are the scene's lights as the bake
// resolved them (resolveLightBake: a file light by Light::sourceLight, then a job file's in
// the order of `addedLights`): their modes and mask channels are written. Without them, or for
// a file light no node places: its own mode as the file gave it, else `lightBake` (a
// shadowmask without a channel written as indirect). `addedLights` (a job file's, in world
// space) that the engine draws (indirect, shadowmask) become lights at the scene's root.
// A lightmap's shadowmask becomes a texture that each of its materials points at through
// VOXLIGHT_shadowmask {"index", "texCoord": 1}.
// `volume`, when given, replaces any irradiance volume the source carried.
void writeLightmappedGlb(const std::string& source, const std::vector<Mesh::Source>& meshes,
                         const std::vector<GeneratedLayout>& layouts, const std::vector<ExportedLightmap>& lightmaps,
                         const std::vector<Camera>& addedCameras, const std::string& path, Diagnostics& diagnostics,
                         const vec3& sky = vec3(0.0f), const std::vector<Light>& addedLights = {},
                         LightBake lightBake = LightBake::All, const std::vector<Light>& bakedLights = {},
                         const ExportedIrradianceVolume* volume = nullptr);

}  // namespace vl
