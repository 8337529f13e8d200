// libFuzzer: a texture's bytes decoded as the loader decodes a material's base colour or
// emission image (scene/gltf_images.h: PNG and JPEG through tinygltf's stb_image). An image
// that cannot be decoded is reported as a problem string, never a crash.
#include "core/error.h"
#include "scene/gltf_images.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    tinygltf::Model model;
    model.images.resize(1);
    model.images[0].uri = "fuzz.png";
    vl::gltf::EncodedImages encoded;
    encoded.bytes[0].assign(data, data + size);
    std::string problem;
    try {
        (void)vl::gltf::decodeColorImage(model, 0, encoded, "fuzz", problem);
    } catch (const vl::Error&) {
    }
    return 0;
}
