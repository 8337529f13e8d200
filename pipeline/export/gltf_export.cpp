#include "export/gltf_export.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "scene/gltf_accessor.h"
#include "scene/gltf_model.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

namespace vl {

namespace {

constexpr const char* kLightmapExtension = "MOZ_lightmap";
constexpr const char* kShadowmaskExtension = "VOXLIGHT_shadowmask";
constexpr int kLinear = 9729;       // GL_LINEAR
constexpr int kClampToEdge = 33071;  // GL_CLAMP_TO_EDGE
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

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
    const unsigned char* at(size_t offset) const { return data_.data() + offset; }

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

// A new accessor of `bytes` (tightly packed elements of `like`'s type) in a view of its own.
int addAccessor(tinygltf::Model& model, BinaryBuffer& bin, const tinygltf::Accessor& like,
                const std::vector<unsigned char>& bytes, size_t count, int target) {
    tinygltf::Accessor accessor = like;
    accessor.bufferView = bin.addView(model, bytes.data(), bytes.size());
    model.bufferViews.back().target = target;
    accessor.byteOffset = 0;
    accessor.count = count;
    accessor.sparse.isSparse = false;
    accessor.minValues.clear();
    accessor.maxValues.clear();
    const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
    if (accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && count > 0) {
        // min and max (required of POSITION), from the elements themselves.
        accessor.minValues.assign(size_t(components), std::numeric_limits<double>::max());
        accessor.maxValues.assign(size_t(components), -std::numeric_limits<double>::max());
        for (size_t e = 0; e < count; ++e)
            for (int c = 0; c < components; ++c) {
                float v;
                std::memcpy(&v, bytes.data() + (e * size_t(components) + size_t(c)) * sizeof(float), sizeof v);
                accessor.minValues[size_t(c)] = std::min(accessor.minValues[size_t(c)], double(v));
                accessor.maxValues[size_t(c)] = std::max(accessor.maxValues[size_t(c)], double(v));
            }
    }
    model.accessors.push_back(accessor);
    return static_cast<int>(model.accessors.size()) - 1;
}

// Accessor `index`'s elements at `vertices`, as a new accessor; −1 for a sparse one.
int gatherAccessor(tinygltf::Model& model, BinaryBuffer& bin, int index, const std::vector<uint32_t>& vertices) {
    const tinygltf::Accessor source = model.accessors.at(size_t(index));
    if (source.sparse.isSparse) return -1;
    const size_t element = size_t(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(source.componentType))) *
                           size_t(tinygltf::GetNumComponentsInType(static_cast<uint32_t>(source.type)));
    std::vector<unsigned char> bytes(vertices.size() * element, 0);
    if (source.bufferView >= 0) {
        const tinygltf::BufferView& view = model.bufferViews.at(size_t(source.bufferView));
        const size_t stride = view.byteStride > 0 ? view.byteStride : element;
        for (size_t k = 0; k < vertices.size(); ++k) {
            if (vertices[k] >= source.count) return -1;
            std::memcpy(&bytes[k * element], bin.at(view.byteOffset + source.byteOffset + vertices[k] * stride), element);
        }
    }
    return addAccessor(model, bin, source, bytes, vertices.size(), kArrayBuffer);
}

// Writes a mesh's generated layout into primitive `p` of glTF mesh `m`: every attribute
// gathered at the layout's vertices, TEXCOORD_1, and the triangles (in glTF's winding).
// False, with nothing changed, for a primitive this cannot rewrite.
// `original`: the primitive as the file has it (an earlier instance may have rewritten the
// mesh this one was copied from).
bool writeLayout(tinygltf::Model& model, BinaryBuffer& bin, int m, int p, const tinygltf::Primitive& original,
                 const GeneratedLayout& layout) {
    if (!original.targets.empty()) return false;
    std::map<std::string, int> attributes;
    for (const auto& [name, accessor] : original.attributes) {
        if (name == "TEXCOORD_1") continue;
        const int gathered = gatherAccessor(model, bin, accessor, layout.source.vertices);
        if (gathered < 0) return false;
        attributes[name] = gathered;
    }
    tinygltf::Accessor uvLike;
    uvLike.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    uvLike.type = TINYGLTF_TYPE_VEC2;
    std::vector<unsigned char> uvBytes(layout.uv1.size() * sizeof(vec2));
    std::memcpy(uvBytes.data(), layout.uv1.data(), uvBytes.size());
    attributes["TEXCOORD_1"] = addAccessor(model, bin, uvLike, uvBytes, layout.uv1.size(), kArrayBuffer);
    // glTF numbers texture coordinates from 0 without gaps: a primitive without TEXCOORD_0
    // (no textures) reads the lightmap's coordinates there too, so MOZ_lightmap's texCoord 1
    // holds for every primitive of a material.
    if (!attributes.count("TEXCOORD_0")) attributes["TEXCOORD_0"] = attributes["TEXCOORD_1"];
    std::vector<uint32_t> triangles = layout.indices;
    if (layout.source.mirrored)  // the loader swapped two corners: swap them back
        for (size_t t = 0; t + 2 < triangles.size(); t += 3) std::swap(triangles[t + 1], triangles[t + 2]);
    tinygltf::Accessor indexLike;
    indexLike.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    indexLike.type = TINYGLTF_TYPE_SCALAR;
    std::vector<unsigned char> indexBytes(triangles.size() * sizeof(uint32_t));
    std::memcpy(indexBytes.data(), triangles.data(), indexBytes.size());
    tinygltf::Primitive& primitive = model.meshes.at(size_t(m)).primitives.at(size_t(p));
    primitive.indices = addAccessor(model, bin, indexLike, indexBytes, triangles.size(), kElementArrayBuffer);
    primitive.attributes = attributes;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    return true;
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

using PrimitiveKey = std::pair<int, int>;  // (glTF mesh, primitive)

// Where the generated layouts went: each node's instance of a glTF mesh gets its own mesh (the
// first node keeps the original), whose primitives take the layout's vertices and TEXCOORD_1.
struct WrittenLayouts {
    std::map<int, int> meshOfNode;  // node → the glTF mesh its instance writes to
    std::set<PrimitiveKey> unlit;   // primitives left without a lightmap
    int gltfMesh(const Mesh::Source& from) const {
        const auto it = meshOfNode.find(from.node);
        return it == meshOfNode.end() ? from.mesh : it->second;
    }
};

WrittenLayouts writeLayouts(tinygltf::Model& model, BinaryBuffer& bin, const std::vector<Mesh::Source>& meshes,
                            const std::vector<GeneratedLayout>& layouts, const std::string& source,
                            Diagnostics& diagnostics) {
    WrittenLayouts written;
    const std::vector<tinygltf::Mesh> originals = model.meshes;
    std::set<int> claimed;  // glTF meshes a node has taken
    for (size_t k = 0; k < layouts.size(); ++k) {
        const Mesh::Source& from = meshes[k];
        if (layouts[k].uv1.empty() || from.node < 0 || static_cast<size_t>(from.node) >= model.nodes.size() ||
            from.mesh < 0 || static_cast<size_t>(from.mesh) >= model.meshes.size() || from.primitive < 0 ||
            static_cast<size_t>(from.primitive) >= originals[size_t(from.mesh)].primitives.size())
            continue;
        if (!written.meshOfNode.count(from.node)) {
            if (claimed.insert(from.mesh).second) {
                written.meshOfNode[from.node] = from.mesh;
            } else {
                model.meshes.push_back(originals[size_t(from.mesh)]);
                written.meshOfNode[from.node] = static_cast<int>(model.meshes.size()) - 1;
                model.nodes[size_t(from.node)].mesh = written.meshOfNode[from.node];
            }
        }
        const int target = written.meshOfNode[from.node];
        if (!writeLayout(model, bin, target, from.primitive, originals[size_t(from.mesh)].primitives[size_t(from.primitive)],
                         layouts[k])) {
            written.unlit.insert({target, from.primitive});
            diagnostics.warn(source + ": mesh " + std::to_string(from.mesh) + " primitive " + std::to_string(from.primitive) +
                             " has morph targets or sparse attributes, which glTF out does not rewrite: "
                             "scene.glb shows it without its lightmap");
        }
    }
    return written;
}

struct LightmapTextures {
    std::vector<int> lightmap;    // per lightmap
    std::vector<int> shadowmask;  // per lightmap; -1: none
};

// Each lightmap's PNG, and its shadowmask's, with a linear clamped sampler (no mipmaps:
// averaging RGBM texels is not averaging light), as textures; their indices.
LightmapTextures addLightmapTextures(tinygltf::Model& model, BinaryBuffer& bin, const std::vector<ExportedLightmap>& lightmaps) {
    LightmapTextures textureOf;
    if (lightmaps.empty()) return textureOf;
    tinygltf::Sampler sampler;
    sampler.magFilter = kLinear;
    sampler.minFilter = kLinear;
    sampler.wrapS = kClampToEdge;
    sampler.wrapT = kClampToEdge;
    sampler.name = "lightmap";
    model.samplers.push_back(sampler);
    const int samplerIndex = static_cast<int>(model.samplers.size()) - 1;
    const auto addTexture = [&](const std::string& name, const std::vector<uint8_t>& png) {
        tinygltf::Image image;
        image.name = name;
        image.mimeType = "image/png";
        image.bufferView = bin.addView(model, png.data(), png.size());
        model.images.push_back(image);
        tinygltf::Texture texture;
        texture.name = name;
        texture.source = static_cast<int>(model.images.size()) - 1;
        texture.sampler = samplerIndex;
        model.textures.push_back(texture);
        return static_cast<int>(model.textures.size()) - 1;
    };
    for (const ExportedLightmap& lightmap : lightmaps) {
        textureOf.lightmap.push_back(addTexture(lightmap.name, rgbmPng(lightmap.encoded)));
        if (lightmap.shadowmask.empty()) {
            textureOf.shadowmask.push_back(-1);
            continue;
        }
        if (lightmap.shadowmask.size() != size_t(lightmap.encoded.width) * size_t(lightmap.encoded.height) * 4)
            throw Error("writeLightmappedGlb: lightmap '" + lightmap.name + "': its shadowmask is not its size");
        textureOf.shadowmask.push_back(addTexture(
            lightmap.name + " shadowmask",
            encodePng8(lightmap.encoded.width, lightmap.encoded.height, 4, lightmap.shadowmask)));
    }
    return textureOf;
}

// VOXLIGHT_shadowmask of a material: the shadowmask's texture, read through TEXCOORD_1.
tinygltf::Value shadowmaskExtension(int texture) {
    tinygltf::Value::Object object;
    object["index"] = tinygltf::Value(texture);
    object["texCoord"] = tinygltf::Value(1);
    return tinygltf::Value(object);
}

// Which lightmap each glTF primitive was baked into.
std::map<PrimitiveKey, size_t> lightmapOfPrimitives(const tinygltf::Model& model, const std::vector<Mesh::Source>& meshes,
                                                    const WrittenLayouts& written,
                                                    const std::vector<ExportedLightmap>& lightmaps,
                                                    const std::string& source, Diagnostics& diagnostics) {
    std::map<PrimitiveKey, size_t> lightmapOf;
    for (size_t a = 0; a < lightmaps.size(); ++a)
        for (uint32_t m : lightmaps[a].meshes) {
            if (m >= meshes.size()) throw Error("writeLightmappedGlb: mesh " + std::to_string(m) + " does not exist");
            const Mesh::Source& from = meshes[m];
            const int target = written.gltfMesh(from);
            if (target < 0 || static_cast<size_t>(target) >= model.meshes.size() || from.primitive < 0 ||
                static_cast<size_t>(from.primitive) >= model.meshes[size_t(target)].primitives.size())
                continue;  // made in code, not read from the file
            if (written.unlit.count({target, from.primitive})) continue;
            const auto [it, added] = lightmapOf.emplace(PrimitiveKey(target, from.primitive), a);
            if (!added && it->second != a)
                diagnostics.warn(source + ": mesh " + std::to_string(from.mesh) + " primitive " +
                                 std::to_string(from.primitive) + " is placed by nodes baked into lightmaps '" +
                                 lightmaps[it->second].name + "' and '" + lightmaps[a].name +
                                 "'; its instances share one material, which takes '" + lightmaps[it->second].name + "'");
        }
    return lightmapOf;
}

// Points every lightmapped primitive's material at its lightmap: the material itself when it
// serves that lightmap alone, else a copy per lightmap (the unlit primitives keep the original).
void attachLightmaps(tinygltf::Model& model, const std::map<PrimitiveKey, size_t>& lightmapOf,
                     const LightmapTextures& textureOf, const std::vector<ExportedLightmap>& lightmaps) {
    constexpr size_t kUnlit = static_cast<size_t>(-1);
    // A scene.glb baked again: its old shadowmasks are not this bake's.
    for (tinygltf::Material& material : model.materials) material.extensions.erase(kShadowmaskExtension);
    std::map<int, std::set<size_t>> usesOf;  // material (−1: the default) → lightmaps, kUnlit
    for (size_t m = 0; m < model.meshes.size(); ++m)
        for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
            const auto it = lightmapOf.find({int(m), int(p)});
            usesOf[model.meshes[m].primitives[p].material].insert(it == lightmapOf.end() ? kUnlit : it->second);
        }
    std::map<std::pair<int, size_t>, int> materialFor;
    for (const auto& [material, uses] : usesOf)
        for (size_t a : uses) {
            if (a == kUnlit) continue;
            int target = material;
            if (!(material >= 0 && uses.size() == 1)) {
                tinygltf::Material copy = material >= 0 ? model.materials[size_t(material)] : tinygltf::Material();
                copy.name = (material >= 0 ? copy.name : std::string("default")) + " (lightmap " + lightmaps[a].name + ")";
                model.materials.push_back(copy);
                target = static_cast<int>(model.materials.size()) - 1;
            }
            model.materials[size_t(target)].extensions[kLightmapExtension] =
                lightmapExtension(textureOf.lightmap[a], lightmaps[a].encoded.range);
            if (textureOf.shadowmask[a] >= 0)
                model.materials[size_t(target)].extensions[kShadowmaskExtension] =
                    shadowmaskExtension(textureOf.shadowmask[a]);
            materialFor[{material, a}] = target;
        }
    for (const auto& [key, a] : lightmapOf) {
        tinygltf::Primitive& primitive = model.meshes[size_t(key.first)].primitives[size_t(key.second)];
        primitive.material = materialFor.at({primitive.material, a});
    }
    if (!lightmaps.empty() &&
        std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), kLightmapExtension) == model.extensionsUsed.end())
        model.extensionsUsed.push_back(kLightmapExtension);
    std::vector<std::string>& used = model.extensionsUsed;
    used.erase(std::remove(used.begin(), used.end(), kShadowmaskExtension), used.end());
    if (std::any_of(textureOf.shadowmask.begin(), textureOf.shadowmask.end(), [](int t) { return t >= 0; }))
        used.push_back(kShadowmaskExtension);
}

// tinygltf writes `zfar` always, and 0 (its "infinite projection") is invalid glTF: a camera
// without a far plane gets one far beyond any scene (10^7 × znear: 100 km at 1 cm).
void giveFarPlanes(tinygltf::Model& model) {
    for (tinygltf::Camera& camera : model.cameras)
        if (camera.type == "perspective" && !(camera.perspective.zfar > camera.perspective.znear))
            camera.perspective.zfar = camera.perspective.znear * 1e7;
}

// A glTF camera looks down its node's −Z with +Y up.
void addCameras(tinygltf::Model& model, const std::vector<Camera>& cameras) {
    if (cameras.empty()) return;
    if (model.scenes.empty()) model.scenes.emplace_back();
    tinygltf::Scene& scene = model.scenes[size_t(std::max(model.defaultScene, 0))];
    for (const Camera& camera : cameras) {
        tinygltf::Camera written;
        written.name = camera.name;
        written.type = "perspective";
        written.perspective.yfov = camera.yfov;
        written.perspective.aspectRatio = camera.aspectRatio;  // 0: not written (the viewport's)
        written.perspective.znear = 0.01;
        model.cameras.push_back(written);
        tinygltf::Node node;
        node.name = camera.name;
        node.camera = static_cast<int>(model.cameras.size() - 1);
        const vec3 right = glm::normalize(glm::cross(camera.forward, camera.up));
        const glm::quat rotation = glm::quat_cast(glm::mat3(right, glm::cross(right, camera.forward), -camera.forward));
        node.rotation = {rotation.x, rotation.y, rotation.z, rotation.w};
        node.translation = {camera.position.x, camera.position.y, camera.position.z};
        model.nodes.push_back(node);
        scene.nodes.push_back(static_cast<int>(model.nodes.size() - 1));
    }
}

constexpr const char* kLightBakeExtension = "VOXLIGHT_light_bake";

// A shadowmask without a channel (a light the bake did not place) is written as indirect: the
// engine draws it whole.
// A sun's disk (Light::angularDiameter > 0), which glTF cannot hold, goes with it: an engine
// softens the light's shadows by it.
tinygltf::Value lightBakeExtension(LightBake mode, int channel = -1, float angularDiameter = 0.0f) {
    if (mode == LightBake::Shadowmask && channel < 0) mode = LightBake::Indirect;
    tinygltf::Value::Object object;
    object["mode"] = tinygltf::Value(std::string(lightBakeName(mode)));
    if (mode == LightBake::Shadowmask) object["channel"] = tinygltf::Value(channel);
    if (angularDiameter > 0.0f) object["angularDiameter"] = tinygltf::Value(double(angularDiameter));
    return tinygltf::Value(object);
}

// A glTF light's direction is its node's −Z.
void addLightBakes(tinygltf::Model& model, const std::vector<Light>& addedLights, LightBake setting,
                   const std::vector<Light>& bakedLights) {
    for (size_t i = 0; i < model.lights.size(); ++i) {
        tinygltf::Light& light = model.lights[i];
        const auto baked = std::find_if(bakedLights.begin(), bakedLights.end(),
                                        [&](const Light& l) { return l.sourceLight == int(i); });
        if (baked != bakedLights.end())
            light.extensions[kLightBakeExtension] =
                lightBakeExtension(baked->bake, baked->maskChannel, baked->angularDiameter);
        else if (const auto own = light.extensions.find(kLightBakeExtension); own != light.extensions.end()) {
            LightBake mode = LightBake::All;
            const tinygltf::Value& name = own->second.Get("mode");
            if (name.IsString()) parseLightBake(name.Get<std::string>(), mode);
            const tinygltf::Value& disk = own->second.Get("angularDiameter");
            own->second = lightBakeExtension(mode, -1, disk.IsNumber() ? float(disk.GetNumberAsDouble()) : 0.0f);
        } else
            light.extensions[kLightBakeExtension] = lightBakeExtension(setting);
    }
    std::vector<const Light*> bakedAdded;  // a job file's lights as the bake resolved them, in order
    for (const Light& light : bakedLights)
        if (light.sourceLight < 0) bakedAdded.push_back(&light);
    if (!bakedLights.empty() && bakedAdded.size() != addedLights.size())
        throw Error("writeLightmappedGlb: " + std::to_string(addedLights.size()) + " added lights, the bake resolved " +
                    std::to_string(bakedAdded.size()));
    for (size_t k = 0; k < addedLights.size(); ++k) {
        const Light& light = addedLights[k];
        const Light* baked = bakedAdded.empty() ? nullptr : bakedAdded[k];
        const LightBake mode = baked ? baked->bake : light.bake == LightBake::Unset ? setting : light.bake;
        const int channel = baked ? baked->maskChannel : -1;
        if (mode != LightBake::Indirect && mode != LightBake::Shadowmask) continue;
        tinygltf::Light written;
        written.name = light.name;
        written.type = light.type == LightType::Point ? "point" : light.type == LightType::Spot ? "spot" : "directional";
        written.color = {light.color.x, light.color.y, light.color.z};
        written.intensity = double(light.intensity) * kLumensPerWatt;
        if (light.type != LightType::Directional) written.range = light.range;
        if (light.type == LightType::Spot) {
            written.spot.innerConeAngle = light.innerConeAngle;
            written.spot.outerConeAngle = light.outerConeAngle;
        }
        written.extensions[kLightBakeExtension] = lightBakeExtension(mode, channel, light.angularDiameter);
        model.lights.push_back(written);
        if (model.scenes.empty()) model.scenes.emplace_back();
        tinygltf::Node node;
        node.name = light.name;
        tinygltf::Value::Object reference;
        reference["light"] = tinygltf::Value(int(model.lights.size() - 1));
        node.extensions["KHR_lights_punctual"] = tinygltf::Value(reference);
        const vec3 back = -glm::normalize(light.direction);  // the node's +Z
        const vec3 helper = std::abs(back.y) < 0.9f ? vec3(0, 1, 0) : vec3(1, 0, 0);
        const vec3 right = glm::normalize(glm::cross(helper, back));
        const glm::quat rotation = glm::quat_cast(glm::mat3(right, glm::cross(back, right), back));
        node.rotation = {rotation.x, rotation.y, rotation.z, rotation.w};
        if (light.type != LightType::Directional) node.translation = {light.position.x, light.position.y, light.position.z};
        model.nodes.push_back(node);
        model.scenes[size_t(std::max(model.defaultScene, 0))].nodes.push_back(int(model.nodes.size() - 1));
    }
    if (!model.lights.empty() &&
        std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), kLightBakeExtension) == model.extensionsUsed.end())
        model.extensionsUsed.push_back(kLightBakeExtension);
}
constexpr const char* kVolumeExtension = "VOXLIGHT_irradiance_volume";

// The volume's images (PNG, no texture: a probe is not read through a sampler) and its extension.
void addIrradianceVolume(tinygltf::Model& model, BinaryBuffer& bin, const ExportedIrradianceVolume& volume) {
    const int width = volume.counts.x, height = volume.counts.y * volume.counts.z;
    const size_t probes = size_t(width) * size_t(height);
    if (volume.mean.width != width || volume.mean.height != height || volume.valid.size() != probes)
        throw Error("writeLightmappedGlb: the irradiance volume's images are not its probes' count");
    const auto addImage = [&](const std::string& name, const std::vector<uint8_t>& png) {
        tinygltf::Image image;
        image.name = name;
        image.mimeType = "image/png";
        image.bufferView = bin.addView(model, png.data(), png.size());
        model.images.push_back(image);
        return tinygltf::Value(int(model.images.size()) - 1);
    };
    const auto triple = [](const auto& v) {
        return tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(double(v.x)), tinygltf::Value(double(v.y)),
                                                      tinygltf::Value(double(v.z))});
    };
    tinygltf::Value::Object ext;
    ext["origin"] = triple(volume.origin);
    ext["spacing"] = triple(volume.spacing);
    ext["counts"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(volume.counts.x), tinygltf::Value(volume.counts.y),
                                                           tinygltf::Value(volume.counts.z)});
    ext["irradiance"] = addImage("irradiance volume: mean", rgbmPng(volume.mean));
    ext["range"] = tinygltf::Value(double(volume.mean.range));
    tinygltf::Value::Array gradient;
    const char* axes[] = {"x", "y", "z"};
    for (size_t axis = 0; axis < 3; ++axis) {
        if (volume.gradient[axis].size() != 3 * probes)
            throw Error("writeLightmappedGlb: the irradiance volume's gradient is not its probes' count");
        gradient.push_back(addImage(std::string("irradiance volume: gradient ") + axes[axis],
                                    encodePng8(width, height, 3, volume.gradient[axis])));
    }
    ext["gradient"] = tinygltf::Value(gradient);
    ext["valid"] = addImage("irradiance volume: valid", encodePng8(width, height, 1, volume.valid));
    if (!volume.suns.empty()) {
        if (volume.sunVisibility.size() != 4 * probes)
            throw Error("writeLightmappedGlb: the irradiance volume's sun visibility is not its probes' count");
        tinygltf::Value::Array suns;
        for (const ExportedIrradianceVolume::Sun& sun : volume.suns) {
            tinygltf::Value::Object entry;
            entry["direction"] = triple(sun.direction);
            entry["irradiance"] = triple(sun.irradiance);
            entry["drawnByEngine"] = tinygltf::Value(sun.drawnByEngine);
            suns.push_back(tinygltf::Value(entry));
        }
        ext["suns"] = tinygltf::Value(suns);
        ext["sunVisibility"] = addImage("irradiance volume: sun visibility", encodePng8(width, height, 4, volume.sunVisibility));
    }
    model.extensions[kVolumeExtension] = tinygltf::Value(ext);
    if (std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), kVolumeExtension) == model.extensionsUsed.end())
        model.extensionsUsed.push_back(kVolumeExtension);
}

}  // namespace

ExportedIrradianceVolume readIrradianceVolume(const std::string& path) {
    tinygltf::Model model;
    gltf::EncodedImages encoded;
    readGltfModel(path, model, encoded, true);
    const auto found = model.extensions.find(kVolumeExtension);
    if (found == model.extensions.end()) throw InputError(path + ": no " + kVolumeExtension);
    const tinygltf::Value& ext = found->second;
    const std::string where = path + ": " + kVolumeExtension;
    if (!ext.IsObject()) throw InputError(where + " is not an object");
    const auto number = [&](const tinygltf::Value& v, const std::string& key) {
        if (!v.IsNumber()) throw InputError(where + ": " + key + " is not a number");
        return v.GetNumberAsDouble();
    };
    const auto triple = [&](const std::string& key) {
        const tinygltf::Value& v = ext.Get(key);
        if (!v.IsArray() || v.ArrayLen() != 3) throw InputError(where + ": " + key + " is not three numbers");
        return glm::dvec3(number(v.Get(0), key), number(v.Get(1), key), number(v.Get(2), key));
    };
    ExportedIrradianceVolume volume;
    volume.origin = triple("origin");
    volume.spacing = triple("spacing");
    for (int axis = 0; axis < 3; ++axis)
        if (!std::isfinite(volume.origin[axis]) || !std::isfinite(volume.spacing[axis]) || !(volume.spacing[axis] > 0.0))
            throw InputError(where + ": origin is not finite, or spacing not finite and positive");
    const glm::dvec3 counts = triple("counts");
    double probes = 1.0;
    for (int axis = 0; axis < 3; ++axis) {
        if (!(counts[axis] >= 1.0) || counts[axis] != std::floor(counts[axis]) || (probes *= counts[axis]) > double(kMaxVolumeProbes))
            throw InputError(where + ": counts are not whole numbers of at least 1, or hold more than " +
                             std::to_string(kMaxVolumeProbes) + " probes");
        volume.counts[axis] = int(counts[axis]);
    }
    const int width = volume.counts.x, height = volume.counts.y * volume.counts.z;
    const auto image = [&](const tinygltf::Value& index, const std::string& key, int channels) {
        const double i = number(index, key);
        if (!(i >= 0.0) || i >= double(model.images.size()) || model.images[size_t(i)].bufferView < 0)
            throw InputError(where + ": " + key + " names no image stored in the file");
        const auto [bytes, size] = gltf::bufferViewBytes(model, model.images[size_t(i)].bufferView, where + ": " + key);
        if (const std::string problem = gltf::encodedImageProblem(bytes, size); !problem.empty())
            throw InputError(where + ": " + key + ": " + problem);
        int w = 0, h = 0, c = 0;
        std::vector<uint8_t> texels = decodeImage8(std::vector<uint8_t>(bytes, bytes + size), where + ": " + key, w, h, c);
        if (w != width || h != height || c < channels)
            throw InputError(where + ": " + key + " is " + std::to_string(w) + " x " + std::to_string(h) + " x " +
                             std::to_string(c) + ", not " + std::to_string(width) + " x " + std::to_string(height) +
                             " x " + std::to_string(channels));
        std::vector<uint8_t> out(size_t(width) * size_t(height) * size_t(channels));
        for (size_t p = 0; p < size_t(width) * size_t(height); ++p)
            for (int k = 0; k < channels; ++k) out[p * size_t(channels) + size_t(k)] = texels[p * size_t(c) + size_t(k)];
        return out;
    };
    volume.mean.width = width;
    volume.mean.height = height;
    volume.mean.range = float(number(ext.Get("range"), "range"));
    if (!std::isfinite(volume.mean.range) || !(volume.mean.range > 0.0f))
        throw InputError(where + ": range is not finite and positive");
    volume.mean.rgba = image(ext.Get("irradiance"), "irradiance", 4);
    const tinygltf::Value& gradient = ext.Get("gradient");
    if (!gradient.IsArray() || gradient.ArrayLen() != 3) throw InputError(where + ": gradient is not three images");
    for (int axis = 0; axis < 3; ++axis)
        volume.gradient[size_t(axis)] = image(gradient.Get(axis), "gradient[" + std::to_string(axis) + "]", 3);
    volume.valid = image(ext.Get("valid"), "valid", 1);
    if (ext.Has("suns")) {
        const tinygltf::Value& suns = ext.Get("suns");
        if (!suns.IsArray() || suns.ArrayLen() > 4) throw InputError(where + ": suns is not an array of at most four");
        for (size_t s = 0; s < suns.ArrayLen(); ++s) {
            const tinygltf::Value& sun = suns.Get(int(s));
            if (!sun.IsObject()) throw InputError(where + ": suns[" + std::to_string(s) + "] is not an object");
            const auto vector = [&](const std::string& key) {
                const tinygltf::Value& v = sun.Get(key);
                if (!v.IsArray() || v.ArrayLen() != 3) throw InputError(where + ": suns[" + std::to_string(s) + "]." + key + " is not three numbers");
                const std::string named = "suns[" + std::to_string(s) + "]." + key;
                return vec3(float(number(v.Get(0), named)), float(number(v.Get(1), named)), float(number(v.Get(2), named)));
            };
            const tinygltf::Value& drawn = sun.Get("drawnByEngine");
            if (sun.Has("drawnByEngine") && !drawn.IsBool())
                throw InputError(where + ": suns[" + std::to_string(s) + "].drawnByEngine is not true or false");
            volume.suns.push_back({vector("direction"), vector("irradiance"), drawn.IsBool() && drawn.Get<bool>()});
        }
        volume.sunVisibility = image(ext.Get("sunVisibility"), "sunVisibility", 4);
    }
    return volume;
}

void writeLightmappedGlb(const std::string& source, const std::vector<Mesh::Source>& meshes,
                         const std::vector<GeneratedLayout>& layouts, const std::vector<ExportedLightmap>& lightmaps,
                         const std::vector<Camera>& addedCameras, const std::string& path, Diagnostics& diagnostics,
                         const vec3& sky, const std::vector<Light>& addedLights, LightBake lightBake,
                         const std::vector<Light>& bakedLights, const ExportedIrradianceVolume* volume) {
    if (!layouts.empty() && layouts.size() != meshes.size())
        throw Error("writeLightmappedGlb: " + std::to_string(layouts.size()) + " layouts for " +
                    std::to_string(meshes.size()) + " meshes");
    tinygltf::Model model;
    gltf::EncodedImages encoded;
    readGltfModel(source, model, encoded, /*filesOutsideScene=*/true);  // the bake read it first, under its setting

    BinaryBuffer bin;
    packBuffers(model, encoded, bin, source, diagnostics);
    const WrittenLayouts written = writeLayouts(model, bin, meshes, layouts, source, diagnostics);
    const LightmapTextures textureOf = addLightmapTextures(model, bin, lightmaps);
    attachLightmaps(model, lightmapOfPrimitives(model, meshes, written, lightmaps, source, diagnostics), textureOf,
                    lightmaps);

    addCameras(model, addedCameras);
    addLightBakes(model, addedLights, lightBake, bakedLights);
    giveFarPlanes(model);
    // A scene.glb baked again: its old volume is not this bake's.
    model.extensions.erase(kVolumeExtension);
    model.extensionsUsed.erase(std::remove(model.extensionsUsed.begin(), model.extensionsUsed.end(), kVolumeExtension),
                               model.extensionsUsed.end());
    if (volume) addIrradianceVolume(model, bin, *volume);

    if (maxComponent(sky) > 0.0f && !model.scenes.empty()) {
        tinygltf::Scene& shown = model.scenes[size_t(std::max(model.defaultScene, 0))];
        tinygltf::Value::Object extras = shown.extras.IsObject() ? shown.extras.Get<tinygltf::Value::Object>()
                                                                   : tinygltf::Value::Object{};
        tinygltf::Value::Object voxlight;
        voxlight["sky"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(double(sky.x)), tinygltf::Value(double(sky.y)),
                                                                 tinygltf::Value(double(sky.z))});
        extras["voxlight"] = tinygltf::Value(voxlight);
        shown.extras = tinygltf::Value(extras);
    }
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
