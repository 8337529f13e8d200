// glTF 2.0 (.gltf, .glb) → Scene. Throws InputError naming the file and the element
// (mesh / primitive / accessor / image) for input it cannot represent faithfully.
#pragma once

#include "core/diagnostics.h"
#include "scene/scene.h"

#include <string>

namespace vl {

struct LoadOptions {
    bool strict = false;  // every warning becomes an error
};

Scene loadGltf(const std::string& path, const LoadOptions& options = {});

}  // namespace vl
