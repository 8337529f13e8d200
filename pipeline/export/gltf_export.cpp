#include "export/gltf_export.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "scene/gltf_accessor.h"
#include "scene/gltf_model.h"

#include <algorithm>
#include <map>
#include <set>

namespace vl {

namespace {

constexpr const char* kLightmapExtension = "MOZ_lightmap";
constexpr int kLinear = 9729;       // GL_LINEAR
constexpr int kClampToEdge = 33071;  // GL_CLAMP_TO_EDGE

// The one buffer a .glb holds: every byte the file's views and images need, each piece on a
// 4-byte boundary (accessors' offsets inside a view stay aligned to their components).
class BinaryBuffer {
public:
    // A new bufferView of `bytes`; its index.
    int addView(tinygltf::Model& model, const unsigned char* bytes, size_t size) {
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = append(bytes, size);
        view.byteLength = size;
        model.bufferViews.push_back(view);
        return static_cast<int>(model.bufferViews.size()) - 1;
    }
    size_t append(const unsigned char* bytes, size_t size) {
        while (data_.size() % 4) data_.push_back(0);
        const size_t offset = data_.size();
        data_.insert(data_.end(), bytes, bytes + size);
        return offset;
    }
    std::vector<unsigned char>& data() { return data_; }

private:
    std::vector<unsigned char> data_;
};

std::string mimeTypeOf(const std::vector<unsigned char>& bytes, const std::string& fallback) {
    if (bytes.size() >= 8 && bytes[0] == 0x89 && bytes[1] == 'P' && bytes[2] == 'N' && bytes[3] == 'G') return "image/png";
    if (bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) return "image/jpeg";
    return fallback;
}

// Moves every bufferView's bytes, then every uri image's, into one buffer.
void packBuffers(tinygltf::Model& model, const gltf::EncodedImages& encoded, BinaryBuffer& bin, const std::string& source,
                 Diagnostics& diagnostics) {
    for (size_t v = 0; v < model.bufferViews.size(); ++v) {
        const auto [bytes, size] = gltf::bufferViewBytes(model, static_cast<int>(v), source + ": bufferView " + std::to_string(v));
        tinygltf::BufferView& view = model.bufferViews[v];
        view.byteOffset = bin.append(bytes, size);
        view.buffer = 0;
    }
    for (size_t i = 0; i < model.images.size(); ++i) {
        tinygltf::Image& image = model.images[i];
        image.image.clear();
        if (image.bufferView >= 0) continue;
        const auto found = encoded.bytes.find(static_cast<int>(i));
        if (found == encoded.bytes.end() || found->second.empty()) {
            diagnostics.warn(source + ": " + gltf::imageName(model, static_cast<int>(i)) +
                             " could not be read, so scene.glb refers to it by its uri '" + image.uri + "'");
            continue;
        }
        image.mimeType = mimeTypeOf(found->second, image.mimeType);
        image.bufferView = bin.addView(model, found->second.data(), found->second.size());
        image.uri.clear();
    }
}

// MOZ_lightmap of a material: the lightmap's texture, read through TEXCOORD_1, scaled by
// the RGBM range.
tinygltf::Value lightmapExtension(int texture, float range) {
    tinygltf::Value::Object object;
    object["index"] = tinygltf::Value(texture);
    object["texCoord"] = tinygltf::Value(1);
    object["intensity"] = tinygltf::Value(double(range));
    return tinygltf::Value(object);
}

}  // namespace

void writeLightmappedGlb(const std::string& source, const std::vector<Mesh::Source>& meshes,
                         const std::vector<ExportedLightmap>& lightmaps, const std::string& path,
                         Diagnostics& diagnostics) {
    tinygltf::Model model;
    gltf::EncodedImages encoded;
    readGltfModel(source, model, encoded);

    BinaryBuffer bin;
    packBuffers(model, encoded, bin, source, diagnostics);

    // Each lightmap: its PNG, a linear clamped sampler (no mipmaps: averaging RGBM texels is
    // not averaging light) and a texture.
    tinygltf::Sampler sampler;
    sampler.magFilter = kLinear;
    sampler.minFilter = kLinear;
    sampler.wrapS = kClampToEdge;
    sampler.wrapT = kClampToEdge;
    sampler.name = "lightmap";
    model.samplers.push_back(sampler);
    const int samplerIndex = static_cast<int>(model.samplers.size()) - 1;
    std::vector<int> textureOf(lightmaps.size());
    for (size_t a = 0; a < lightmaps.size(); ++a) {
        const std::vector<uint8_t> png = rgbmPng(lightmaps[a].encoded);
        tinygltf::Image image;
        image.name = lightmaps[a].name;
        image.mimeType = "image/png";
        image.bufferView = bin.addView(model, png.data(), png.size());
        model.images.push_back(image);
        tinygltf::Texture texture;
        texture.name = lightmaps[a].name;
        texture.source = static_cast<int>(model.images.size()) - 1;
        texture.sampler = samplerIndex;
        model.textures.push_back(texture);
        textureOf[a] = static_cast<int>(model.textures.size()) - 1;
    }

    // Which lightmap each glTF primitive was baked into.
    std::map<std::pair<int, int>, size_t> atlasOf;
    for (size_t a = 0; a < lightmaps.size(); ++a)
        for (uint32_t m : lightmaps[a].meshes) {
            if (m >= meshes.size()) throw Error("writeLightmappedGlb: mesh " + std::to_string(m) + " does not exist");
            const Mesh::Source& from = meshes[m];
            if (from.mesh < 0 || static_cast<size_t>(from.mesh) >= model.meshes.size() || from.primitive < 0 ||
                static_cast<size_t>(from.primitive) >= model.meshes[size_t(from.mesh)].primitives.size())
                continue;  // made in code, not read from the file
            const auto [it, added] = atlasOf.emplace(std::make_pair(from.mesh, from.primitive), a);
            if (!added && it->second != a)
                diagnostics.warn(source + ": mesh " + std::to_string(from.mesh) + " primitive " +
                                 std::to_string(from.primitive) + " is placed by nodes baked into lightmaps '" +
                                 lightmaps[it->second].name + "' and '" + lightmaps[a].name +
                                 "'; its instances share one material, which takes '" + lightmaps[it->second].name + "'");
        }

    // Which lightmaps (or none: kUnlit) each material's primitives use.
    constexpr size_t kUnlit = static_cast<size_t>(-1);
    std::map<int, std::set<size_t>> usesOf;  // material (−1: the default) → lightmaps
    for (size_t m = 0; m < model.meshes.size(); ++m)
        for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
            const auto it = atlasOf.find({int(m), int(p)});
            usesOf[model.meshes[m].primitives[p].material].insert(it == atlasOf.end() ? kUnlit : it->second);
        }
    // The material each (material, lightmap) pair gets: the material itself when it serves
    // that lightmap alone, else a copy.
    std::map<std::pair<int, size_t>, int> materialFor;
    for (const auto& [material, uses] : usesOf) {
        for (size_t a : uses) {
            if (a == kUnlit) continue;
            const bool inPlace = material >= 0 && uses.size() == 1;
            int target = material;
            if (!inPlace) {
                tinygltf::Material copy = material >= 0 ? model.materials[size_t(material)] : tinygltf::Material();
                copy.name = (material >= 0 ? copy.name : std::string("default")) + " (lightmap " + lightmaps[a].name + ")";
                model.materials.push_back(copy);
                target = static_cast<int>(model.materials.size()) - 1;
            }
            model.materials[size_t(target)].extensions[kLightmapExtension] =
                lightmapExtension(textureOf[a], lightmaps[a].encoded.range);
            materialFor[{material, a}] = target;
        }
    }
    for (size_t m = 0; m < model.meshes.size(); ++m)
        for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
            const auto it = atlasOf.find({int(m), int(p)});
            if (it == atlasOf.end()) continue;
            tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
            primitive.material = materialFor.at({primitive.material, it->second});
        }

    if (!lightmaps.empty() &&
        std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), kLightmapExtension) == model.extensionsUsed.end())
        model.extensionsUsed.push_back(kLightmapExtension);
    model.asset.generator = std::string("voxlight ") + VOXLIGHT_VERSION;
    model.buffers.assign(1, tinygltf::Buffer());
    model.buffers[0].data = std::move(bin.data());

    writeAtomically(path, [&](const std::string& temp) {
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToFile(&model, temp, false, true, false, true))
            throw Error("cannot write " + path);
    });
}

}  // namespace vl
