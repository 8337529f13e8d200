// A minimal glTF 2.0 writer for the project's own scenes: quad-built meshes with flat
// normals and a shared lightmap atlas in TEXCOORD_1, Lambert and emissive materials,
// KHR_lights_punctual lights and one perspective camera. Scenes are generated, not
// hand-edited, so they stay reproducible; see make_scenes.cpp.
#pragma once

#include "core/math.h"

#include <array>
#include <string>
#include <vector>

namespace vl::scenes {

// Four corners, counter-clockwise seen from the side the face is lit from.
using Quad = std::array<vec3, 4>;

struct SceneMaterial {
    std::string name;
    vec3 baseColor{0.8f};
    vec3 emissiveFactor{0.0f};
    float emissiveStrength = 1.0f;
    // A base colour texture: a PNG beside the .gltf (written by the caller), repeated every
    // textureMetres along each quad's edges in TEXCOORD_0 (0: once over each quad).
    std::string baseColorTexture;
    float textureMetres = 0.0f;
};

struct SceneMesh {
    std::string name;
    int material = 0;
    std::vector<Quad> quads;
    bool lightmapped = true;  // gets a chart in the TEXCOORD_1 atlas
};

struct ScenePointLight {
    std::string name;
    vec3 position{0.0f};
    vec3 color{1.0f};
    float intensityCandela = 1.0f;  // glTF units: W/sr × 683
};

struct SceneCamera {
    vec3 position{0.0f};
    float yfov = 0.8f;  // looks along −Z, +Y up
    float aspectRatio = 1.0f;
};

struct SceneDescription {
    std::vector<SceneMaterial> materials;
    std::vector<SceneMesh> meshes;
    std::vector<ScenePointLight> lights;
    SceneCamera camera;
    int atlasResolution = 256;  // the texel grid the atlas charts are padded for
    int atlasPaddingTexels = 2;
};

// Writes `<stem>.gltf` and `<stem>.bin` into `directory`.
void writeGltf(const SceneDescription& scene, const std::string& directory, const std::string& stem);

}  // namespace vl::scenes
