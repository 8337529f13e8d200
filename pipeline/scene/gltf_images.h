// glTF images → linear float RGBA. Internal to the scene stage (it includes tinygltf).
// tinygltf hands every image's encoded bytes to keepEncodedImage while it parses; only the
// images a material actually samples are decoded afterwards, so an unused or broken normal
// map costs neither time nor an error.
#pragma once

#include "core/image.h"

#include <tiny_gltf.h>

#include <map>
#include <string>
#include <vector>

namespace vl::gltf {

struct EncodedImages {
    std::map<int, std::vector<unsigned char>> bytes;  // image index → file bytes (uri images)
};

// A tinygltf::LoadImageDataFunction; user_data is an EncodedImages*. Never fails: a missing
// or undecodable image is the loader's decision (a warning), not tinygltf's.
bool keepEncodedImage(tinygltf::Image* image, int imageIndex, std::string* err, std::string* warn, int reqWidth,
                      int reqHeight, const unsigned char* bytes, int size, void* userData);

// "image 3 ('wood.png')": how messages name an image.
std::string imageName(const tinygltf::Model& model, int imageIndex);

// Textures larger than this are refused (a warning), not decoded: one of 8192² is 1 GB as
// float RGBA.
constexpr uint64_t kMaxTextureTexels = uint64_t(8192) * 8192;

// Why encoded image bytes are not decoded, or "": PNG and JPEG only (glTF's formats), every
// PNG chunk and JPEG segment within the bytes, the size claimed within kMaxTextureTexels.
std::string encodedImageProblem(const unsigned char* bytes, size_t size);

// Decodes image `imageIndex` to RGBA float, RGB sRGB-decoded to linear (colour textures),
// alpha linear. Returns an empty Image and sets `problem` when the image is missing or cannot
// be decoded. Throws InputError (via the buffer-view checks) for a malformed bufferView.
Image decodeColorImage(const tinygltf::Model& model, int imageIndex, const EncodedImages& encoded,
                       const std::string& where, std::string& problem);

}  // namespace vl::gltf
