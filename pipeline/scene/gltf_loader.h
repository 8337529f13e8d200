// glTF 2.0 (.gltf, .glb) → Scene. Throws InputError naming the file and the element
// (mesh / primitive / accessor / image) for input it cannot represent faithfully.
//
// What it reads: the default scene (or scene 0; the parentless nodes when the file has no
// scenes) with its node hierarchy (TRS or matrix); triangles, strips and fans, indexed or not,
// sparse and normalized accessors; POSITION, NORMAL (area-weighted when absent), TEXCOORD_0/1,
// COLOR_0; materials with KHR_materials_emissive_strength, _transmission, _ior and
// KHR_texture_transform; base colour and emissive textures decoded to linear RGBA;
// KHR_lights_punctual; perspective cameras. Units as scene.h states.
// Warnings (points/lines skipped, missing images, out-of-spec factors, degenerate triangles
// dropped) go to stderr and Scene::warnings; under `strict` the first one throws.
#pragma once

#include "core/diagnostics.h"
#include "scene/scene.h"

#include <string>

namespace vl {

struct LoadOptions {
    bool strict = false;        // every warning becomes an error
    bool echoWarnings = true;   // print warnings to stderr as they are raised
    // Read buffers and images whose uri leaves the scene's folder (`../`, an absolute path, a
    // link leading out). Off: such a scene is refused, naming the uri, so a downloaded scene
    // cannot read other files of the machine into a texture. data: URIs and files in the
    // scene's folder (or below it) load either way; other schemes (file:, http:) never do.
    bool filesOutsideScene = false;
};

Scene loadGltf(const std::string& path, const LoadOptions& options = {});

// A uri's percent-encoding (RFC 3986) undone: "%20" is a space in a file name.
std::string percentDecoded(const std::string& uri);

// The extensions loadGltf understands; a file that requires any other is refused.
const std::vector<std::string>& supportedGltfExtensions();

}  // namespace vl
