// The tinygltf model of a glTF file, for the stages that include tinygltf (the loader, and
// glTF out, which writes the same model back with its lightmaps).
#pragma once

#include "scene/gltf_images.h"

#include <tiny_gltf.h>

#include <string>

namespace vl {

// Parses `path` (.gltf or .glb) as loadGltf does, after the same checks (InputError naming
// the file; LoadOptions::filesOutsideScene says whether uris may leave its folder); every uri
// image's bytes are kept in `encoded`, none is decoded.
void readGltfModel(const std::string& path, tinygltf::Model& model, gltf::EncodedImages& encoded,
                   bool filesOutsideScene = false);

}  // namespace vl
