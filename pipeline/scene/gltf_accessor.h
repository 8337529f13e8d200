// glTF accessors → plain arrays, every byte range checked first: the loader's only way to
// touch buffer bytes. Internal to the scene stage (it includes tinygltf).
// Errors are InputErrors that start with the caller's `where` ("<file>: mesh 'M' (mesh 0)
// primitive 0 POSITION") and name the accessor, buffer view or buffer at fault.
#pragma once

#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vl::gltf {

// Above this an accessor is refused rather than allocated (2^28 elements, ~3 GB of vec3).
constexpr size_t kMaxAccessorCount = size_t(1) << 28;
// For accessors without a bufferView (zeros plus sparse values), which no file bytes bound.
constexpr size_t kMaxUnbackedAccessorCount = size_t(1) << 24;

// Components per element for SCALAR and VEC2..4; 0 for matrices and unknown types.
int vectorComponents(int type);

struct FloatArray {
    size_t count = 0;    // elements
    int components = 0;  // floats per element
    std::vector<float> values;  // count × components; normalized integers mapped to [0,1] / [-1,1]
};

// Reads accessor `accessor` (sparse substitution applied) as floats. `allowedComponents`
// lists the vector sizes the caller can use (e.g. {3} for POSITION, {3, 4} for COLOR_0).
FloatArray readFloatAccessor(const tinygltf::Model& model, int accessor, std::initializer_list<int> allowedComponents,
                             const std::string& where);

// Reads an index accessor (SCALAR, unsigned byte / short / int).
std::vector<uint32_t> readIndexAccessor(const tinygltf::Model& model, int accessor, const std::string& where);

// The bytes of buffer view `view` after checking that it lies inside a loaded buffer.
std::pair<const unsigned char*, size_t> bufferViewBytes(const tinygltf::Model& model, int view, const std::string& where);

}  // namespace vl::gltf
