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
