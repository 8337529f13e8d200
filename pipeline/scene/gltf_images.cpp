#include "scene/gltf_images.h"

#include "scene/gltf_accessor.h"

#include <array>
#include <climits>
#include <cstring>

namespace vl::gltf {

bool keepEncodedImage(tinygltf::Image* image, int imageIndex, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void* userData) {
    // bufferView images are read later through the checked bufferViewBytes: tinygltf passes
    // their pointer without checking the view against its buffer.
    if (image->bufferView >= 0) return true;
    if (bytes && size > 0)
        static_cast<EncodedImages*>(userData)->bytes[imageIndex].assign(bytes, bytes + size);
    return true;
}

namespace {

uint32_t bigEndian32(const unsigned char* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }
uint32_t bigEndian16(const unsigned char* p) { return uint32_t(p[0]) << 8 | p[1]; }

std::string sizeProblem(uint32_t width, uint32_t height) {
    if (width == 0 || height == 0) return "claims " + std::to_string(width) + " x " + std::to_string(height) + " texels";
    if (uint64_t(width) * height > kMaxTextureTexels)
        return "claims " + std::to_string(width) + " x " + std::to_string(height) +
               " texels, more than the loader decodes (8192 x 8192)";
    return "";
}

// PNG: every chunk within the file, the header's size within bounds.
std::string pngProblem(const unsigned char* bytes, size_t size) {
    size_t at = 8;
    bool header = false;
    while (at + 12 <= size) {
        const uint32_t length = bigEndian32(bytes + at);
        const std::string type(reinterpret_cast<const char*>(bytes + at + 4), 4);
        if (length > size - at - 12)
            return "is malformed: its '" + type + "' chunk claims " + std::to_string(length) + " bytes, " +
                   std::to_string(size - at - 12) + " remain";
        if (!header) {
            if (type != "IHDR" || length < 8) return "is malformed: it does not begin with its header (IHDR)";
            if (std::string problem = sizeProblem(bigEndian32(bytes + at + 8), bigEndian32(bytes + at + 12)); !problem.empty())
                return problem;
            header = true;
        }
        if (type == "IEND") return "";
        at += 12 + size_t(length);
    }
    return "is truncated: it ends before its last chunk (IEND)";
}

// JPEG: every segment before the scan within the file, the frame's size within bounds.
std::string jpegProblem(const unsigned char* bytes, size_t size) {
    size_t at = 2;
    bool frame = false;
    while (at + 4 <= size) {
        if (bytes[at] != 0xFF) return "is malformed: no marker where one is due (byte " + std::to_string(at) + ")";
        const unsigned char marker = bytes[at + 1];
        if (marker == 0xFF) {  // fill byte
            ++at;
            continue;
        }
        if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {  // no length
            at += 2;
            continue;
        }
        const uint32_t length = bigEndian16(bytes + at + 2);
        if (length < 2 || length > size - at - 2)
            return "is malformed: a segment claims " + std::to_string(length) + " bytes, " + std::to_string(size - at - 2) +
                   " remain";
        const bool startOfFrame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
        if (startOfFrame) {
            if (length < 7) return "is malformed: a frame header of " + std::to_string(length) + " bytes";
            if (std::string problem = sizeProblem(bigEndian16(bytes + at + 7), bigEndian16(bytes + at + 5)); !problem.empty())
                return problem;
            frame = true;
        }
        if (marker == 0xDA) return frame ? "" : "is malformed: its scan comes before its frame header";
        at += 2 + size_t(length);
    }
    return "is truncated: it ends before its scan";
}

}  // namespace

std::string encodedImageProblem(const unsigned char* bytes, size_t size) {
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    if (size >= 8 && std::memcmp(bytes, png, 8) == 0) return pngProblem(bytes, size);
    if (size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) return jpegProblem(bytes, size);
    return "is neither PNG nor JPEG (the image formats of glTF)";
}

std::string imageName(const tinygltf::Model& model, int imageIndex) {
    std::string name = "image " + std::to_string(imageIndex);
    if (imageIndex < 0 || static_cast<size_t>(imageIndex) >= model.images.size()) return name;
    const tinygltf::Image& image = model.images[static_cast<size_t>(imageIndex)];
    if (!image.name.empty())
        name += " ('" + image.name + "')";
    else if (!image.uri.empty() && image.uri.rfind("data:", 0) != 0)
        name += " ('" + image.uri + "')";
    return name;
}

Image decodeColorImage(const tinygltf::Model& model, int imageIndex, const EncodedImages& encoded,
                       const std::string& where, std::string& problem) {
    if (imageIndex < 0 || static_cast<size_t>(imageIndex) >= model.images.size()) {
        problem = "does not exist";
        return {};
    }
    const tinygltf::Image& source = model.images[static_cast<size_t>(imageIndex)];
    const unsigned char* bytes = nullptr;
    size_t size = 0;
    if (source.bufferView >= 0) {
        const auto view = bufferViewBytes(model, source.bufferView, where + ": " + imageName(model, imageIndex));
        bytes = view.first;
        size = view.second;
    } else if (auto it = encoded.bytes.find(imageIndex); it != encoded.bytes.end()) {
        bytes = it->second.data();
        size = it->second.size();
    }
    if (!bytes || size == 0) {
        problem = "is missing";
        return {};
    }
    if (size > static_cast<size_t>(INT_MAX)) {
        problem = "is larger than 2 GB";
        return {};
    }

    // The decoder trusts what a file claims (a chunk of 2 GB in a file of 2 kB, a 10^5-texel
    // side): claims are checked against the bytes there before it allocates for them.
    if (std::string claim = encodedImageProblem(bytes, size); !claim.empty()) {
        problem = claim;
        return {};
    }
    tinygltf::Image decoded;
    std::string err, warn;
    // Default options: stb expands every image to 4 channels (RGBA), 8 or 16 bits.
    if (!tinygltf::LoadImageData(&decoded, imageIndex, &err, &warn, 0, 0, bytes, static_cast<int>(size), nullptr)) {
        problem = "cannot be decoded (" + (err.empty() ? std::string("unknown format") : err) + ")";
        while (!problem.empty() && (problem.back() == '\n' || problem.back() == '.')) problem.pop_back();
        return {};
    }
    const size_t texels = static_cast<size_t>(decoded.width) * static_cast<size_t>(decoded.height);
    const size_t bytesPerChannel = decoded.bits == 16 ? 2 : 1;
    if (decoded.component != 4 || decoded.image.size() < texels * 4 * bytesPerChannel) {
        problem = "decoded to an unexpected layout";
        return {};
    }

    Image image(decoded.width, decoded.height, 4);
    if (bytesPerChannel == 1) {
        std::array<float, 256> srgb{};
        for (int v = 0; v < 256; ++v) srgb[static_cast<size_t>(v)] = srgbToLinear(static_cast<float>(v) / 255.0f);
        for (size_t i = 0; i < texels * 4; ++i) {
            const unsigned char v = decoded.image[i];
            image.pixels[i] = (i % 4 == 3) ? static_cast<float>(v) / 255.0f : srgb[v];
        }
    } else {
        for (size_t i = 0; i < texels * 4; ++i) {
            uint16_t v;
            std::memcpy(&v, decoded.image.data() + 2 * i, 2);
            const float f = static_cast<float>(v) / 65535.0f;
            image.pixels[i] = (i % 4 == 3) ? f : srgbToLinear(f);
        }
    }
    return image;
}

}  // namespace vl::gltf
