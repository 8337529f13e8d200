// Texture bytes that claim more than they hold (issue 15: found by tools/fuzz/fuzz_image): the
// decoder trusted a PNG chunk's length and asked for 2 GB for a 126-byte file. Claims are
// checked against the bytes before anything is decoded; such a texture is a warning, as an
// undecodable one is, not an allocation.
#include "scene/gltf_images.h"

#include <catch2/catch.hpp>

#include <vector>

using namespace vl;

namespace {

std::vector<unsigned char> bigEndian(uint32_t v) {
    return {static_cast<unsigned char>(v >> 24), static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 8),
            static_cast<unsigned char>(v)};
}

// A PNG signature and header of width × height, then `chunks` as given.
std::vector<unsigned char> png(uint32_t width, uint32_t height, const std::vector<unsigned char>& chunks) {
    std::vector<unsigned char> bytes = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
    for (uint32_t v : {width, height}) {
        const auto b = bigEndian(v);
        bytes.insert(bytes.end(), b.begin(), b.end());
    }
    bytes.insert(bytes.end(), {8, 6, 0, 0, 0, 0, 0, 0, 0});  // 8-bit RGBA, then a CRC (unchecked here)
    bytes.insert(bytes.end(), chunks.begin(), chunks.end());
    return bytes;
}

std::string decodeProblem(const std::vector<unsigned char>& bytes) {
    tinygltf::Model model;
    model.images.resize(1);
    gltf::EncodedImages encoded;
    encoded.bytes[0] = bytes;
    std::string problem;
    const Image image = gltf::decodeColorImage(model, 0, encoded, "test", problem);
    CHECK(image.pixels.empty());
    return problem;
}

}  // namespace

TEST_CASE("Texture bytes that claim more than they hold are refused before they are decoded", "[scene]") {
    // The fuzzer's file: 126 bytes whose IDAT chunk claims 0x7F000036 bytes.
    const std::vector<unsigned char> found = {
        0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
        0x02, 0x00, 0x00, 0x00, 0x02, 0x00, 0x01, 0x03, 0x00, 0x00, 0x00, 0xce, 0xb6, 0x46, 0xb9, 0x00, 0x00, 0x00,
        0x03, 0x50, 0x4c, 0x54, 0x45, 0x7f, 0x7f, 0xf1, 0xd7, 0x09, 0xae, 0xa6, 0x7f, 0x00, 0x00, 0x36, 0x49, 0x44,
        0x41, 0x54, 0x78, 0x01, 0xed, 0xc1, 0x81, 0x00, 0x00, 0x00, 0x00, 0xc3, 0xa0, 0xfb, 0x53, 0x1f, 0x64, 0xd5,
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe2, 0x0e, 0x82, 0x00, 0x00, 0x01,
        0x0a, 0x0a, 0xce, 0x79, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
    CHECK(decodeProblem(found) == "is malformed: its 'IDAT' chunk claims 2130706486 bytes, 64 remain");

    const std::vector<unsigned char> end = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
    CHECK(gltf::encodedImageProblem(png(4, 4, end).data(), png(4, 4, end).size()).empty());  // well formed (no data)
    CHECK(decodeProblem(png(100000, 100000, end)) == "claims 100000 x 100000 texels, more than the loader decodes (8192 x 8192)");
    CHECK(decodeProblem(png(0, 4, end)) == "claims 0 x 4 texels");
    CHECK(decodeProblem(png(4, 4, {})) == "is truncated: it ends before its last chunk (IEND)");

    // JPEG: a frame of 65535², a segment longer than the file, a file of another format.
    const std::vector<unsigned char> tall = {0xFF, 0xD8, 0xFF, 0xC0, 0x00, 0x0B, 8, 0xFF, 0xFF, 0xFF, 0xFF, 1, 1, 0x11, 0,
                                             0xFF, 0xDA, 0x00, 0x08, 1, 1, 0, 0, 0x3F, 0};
    CHECK(decodeProblem(tall) == "claims 65535 x 65535 texels, more than the loader decodes (8192 x 8192)");
    const std::vector<unsigned char> overlong = {0xFF, 0xD8, 0xFF, 0xE0, 0x40, 0x00, 'J', 'F', 'I', 'F'};
    CHECK(decodeProblem(overlong) == "is malformed: a segment claims 16384 bytes, 6 remain");
    const std::vector<unsigned char> gif = {'G', 'I', 'F', '8', '9', 'a', 1, 0, 1, 0};
    CHECK(decodeProblem(gif) == "is neither PNG nor JPEG (the image formats of glTF)");
}
