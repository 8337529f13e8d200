#include "scene/gltf_loader.h"

#include "core/error.h"
#include "scene/gltf_accessor.h"
#include "scene/gltf_images.h"
#include "scene/gltf_model.h"

#include <tiny_gltf.h>

#include <nlohmann/json.hpp>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>

namespace vl {
namespace {


const std::vector<std::string> kSupportedExtensions = {
    "KHR_lights_punctual",         "KHR_materials_emissive_strength", "KHR_materials_transmission",
    "KHR_materials_ior",           "KHR_texture_transform",
    // Blender writes it (specularColorFactor 0) to say "no specular"; the walls stay Lambert.
    "KHR_materials_specular",
    // A light's bake mode (scene.h LightBake; docs/light-bake-modes.md).
    "VOXLIGHT_light_bake",
};

bool parseVersion(const std::string& text, int& major, int& minor) {
    const size_t dot = text.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 >= text.size()) return false;
    for (size_t i = 0; i < text.size(); ++i)
        if (i != dot && !std::isdigit(static_cast<unsigned char>(text[i]))) return false;
    if (dot > 6 || text.size() - dot > 7) return false;  // keeps stoi in range
    major = std::stoi(text.substr(0, dot));
    minor = std::stoi(text.substr(dot + 1));
    return true;
}

bool allFinite(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

std::string shortNumber(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

std::string quoted(const std::string& name) { return name.empty() ? std::string() : " '" + name + "'"; }

// A 2.0 loader must refuse a file whose minVersion is newer than 2.0 or that requires an
// extension it does not implement (glTF 2.0 §3.12); version 2.1 without minVersion is
// declared backward compatible and loads.
void checkVersionAndExtensions(const std::string& path, const std::string& version, const std::string& minVersion,
                               const std::vector<std::string>& extensionsRequired) {
    int major = 0, minor = 0;
    if (!parseVersion(version, major, minor))
        throw InputError(path + ": asset.version '" + version + "' is not of the form MAJOR.MINOR");
    if (major != 2) throw InputError(path + ": asset.version " + version + ": only glTF 2.x files can be read");
    if (!minVersion.empty()) {
        if (!parseVersion(minVersion, major, minor))
            throw InputError(path + ": asset.minVersion '" + minVersion + "' is not of the form MAJOR.MINOR");
        if (major != 2 || minor > 0)
            throw InputError(path + ": asset.minVersion " + minVersion +
                             " is newer than glTF 2.0, the version this loader implements");
    }
    for (const std::string& extension : extensionsRequired)
        if (std::find(kSupportedExtensions.begin(), kSupportedExtensions.end(), extension) ==
            kSupportedExtensions.end()) {
            std::string list;
            for (const std::string& s : kSupportedExtensions) list += (list.empty() ? "" : ", ") + s;
            throw InputError(path + ": requires extension " + extension + ", which is not supported (supported: " +
                             list + ")");
        }
}

// Where a uri (of `element`, e.g. "buffer 0") may point: data: URIs, and files in the scene's
// folder or below it, where a link does not lead out; beyond that only when allowed. Other
// schemes are refused always: tinygltf would read "file:///x" as a relative path.
void checkUri(const std::string& path, const std::string& element, const std::string& uri, bool filesOutsideScene) {
    if (uri.rfind("data:", 0) == 0) return;
    const auto colon = uri.find(':');
    const auto firstSlash = uri.find('/');
    if (colon != std::string::npos && colon > 0 && (firstSlash == std::string::npos || colon < firstSlash) &&
        std::isalpha(static_cast<unsigned char>(uri[0])) &&
        uri.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789+-.") >= colon)
        throw InputError(path + ": " + element + " ('" + uri + "') is a '" + uri.substr(0, colon) +
                         ":' URI: only data: URIs and files beside the scene are read");
    namespace fs = std::filesystem;
    const fs::path relative = percentDecoded(uri);
    if (relative.is_absolute())  // tinygltf reads uris relative to the file's folder only
        throw InputError(path + ": " + element + " ('" + uri + "') is an absolute path, which is not read: " +
                         "give it relative to the scene's folder" +
                         (filesOutsideScene ? "" : " (one leading out of it needs files-outside-scene=true)"));
    if (filesOutsideScene) return;
    std::error_code ec;
    const fs::path folder = fs::weakly_canonical(fs::absolute(fs::path(path)).parent_path(), ec);
    const fs::path target = fs::weakly_canonical(folder / relative, ec);
    const auto [folderEnd, targetAt] = std::mismatch(folder.begin(), folder.end(), target.begin(), target.end());
    if (ec || folderEnd != folder.end())
        throw InputError(path + ": " + element + " ('" + uri + "') lies outside the scene's folder (" +
                         target.string() + "): refused, so a scene cannot read other files of the machine; "
                         "files-outside-scene=true reads it");
}

// The same checks on the raw JSON, before tinygltf parses the rest: a file that needs an
// unsupported extension is refused for that reason, not for the parts tinygltf cannot read
// because of it (a Draco-compressed accessor has no bufferView). Anything unreadable here is
// left for tinygltf to report.
void precheckJson(const std::string& path, bool filesOutsideScene) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const char* begin = bytes.data();
    const char* end = bytes.data() + bytes.size();
    if (bytes.size() >= 4 && std::equal(begin, begin + 4, "glTF")) {
        // GLB: 12-byte header, then the JSON chunk (length, type 'JSON', data).
        if (bytes.size() < 20) return;
        uint32_t length = 0, type = 0;
        std::memcpy(&length, begin + 12, 4);
        std::memcpy(&type, begin + 16, 4);
        if (type != 0x4E4F534Au || length > bytes.size() - 20) return;
        begin += 20;
        end = begin + length;
    }
    const nlohmann::json json = nlohmann::json::parse(begin, end, nullptr, /*allow_exceptions=*/false);
    if (json.is_discarded() || !json.is_object()) return;
    const auto asset = json.find("asset");
    if (asset == json.end() || !asset->is_object()) return;
    const auto version = asset->find("version");
    if (version == asset->end() || !version->is_string()) return;
    std::string minVersion;
    if (const auto it = asset->find("minVersion"); it != asset->end() && it->is_string())
        minVersion = it->get<std::string>();
    std::vector<std::string> required;
    if (const auto it = json.find("extensionsRequired"); it != json.end() && it->is_array())
        for (const auto& name : *it)
            if (name.is_string()) required.push_back(name.get<std::string>());
    checkVersionAndExtensions(path, version->get<std::string>(), minVersion, required);

    if (const auto images = json.find("images"); images != json.end() && images->is_array())
        for (size_t i = 0; i < images->size(); ++i) {
            const auto& image = (*images)[i];
            if (!image.is_object()) continue;
            const auto uri = image.find("uri");
            if (uri != image.end() && uri->is_string())
                checkUri(path, "image " + std::to_string(i), uri->get<std::string>(), filesOutsideScene);
        }
    // tinygltf reports a missing .bin as a bare "File not found"; say which buffer it is.
    const auto buffers = json.find("buffers");
    if (buffers == json.end() || !buffers->is_array()) return;
    for (size_t b = 0; b < buffers->size(); ++b) {
        const auto& buffer = (*buffers)[b];
        if (!buffer.is_object()) continue;
        const auto uri = buffer.find("uri");
        if (uri == buffer.end() || !uri->is_string()) continue;
        const std::string text = uri->get<std::string>();
        checkUri(path, "buffer " + std::to_string(b), text, filesOutsideScene);
        if (text.rfind("data:", 0) == 0) continue;
        const std::filesystem::path file = std::filesystem::path(path).parent_path() / percentDecoded(text);
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec))
            throw InputError(path + ": buffer " + std::to_string(b) + " ('" + text + "') is missing: no file " +
                             file.string());
    }
}

class Loader {
public:
    Loader(const std::string& path, const tinygltf::Model& model, const gltf::EncodedImages& encoded,
           Diagnostics& diagnostics, Scene& scene)
        : path_(path), model_(model), encoded_(encoded), diagnostics_(diagnostics), scene_(scene),
          textureSlots_(model.textures.size(), kNotYet) {}

    void run() {
        checkAsset();
        checkImagesPresent();
        for (size_t m = 0; m < model_.materials.size(); ++m) scene_.materials.push_back(material(static_cast<int>(m)));
        // The scene's local frame: its geometry's bounding box centred on the origin,
        // found in double before any position is rounded to float (scene.h).
        glm::dvec3 lower(std::numeric_limits<double>::infinity()), upper(-std::numeric_limits<double>::infinity());
        visited_.clear();
        for (int root : sceneRoots())
            visitHierarchy(root, [&](int index, const glm::dmat4& world) {
                const int meshIndex = model_.nodes[static_cast<size_t>(index)].mesh;
                if (meshIndex >= 0) growBounds(meshIndex, world, lower, upper);
            });
        if (lower.x <= upper.x) scene_.origin = 0.5 * (lower + upper);
        const glm::dmat4 toLocal = glm::translate(glm::dmat4(1.0), -scene_.origin);
        visited_.clear();
        for (int root : sceneRoots())
            visitHierarchy(root, [&](int index, const glm::dmat4& world) { visitNode(index, toLocal * world); });

        if (skippedPrimitives_ > 0)
            warn("skipped " + std::to_string(skippedPrimitives_) +
                 " point/line primitive(s), which have no surface (first: " + firstSkipped_ + ")");
        if (scene_.degenerateTrianglesDropped > 0)
            warn("dropped " + std::to_string(scene_.degenerateTrianglesDropped) + " degenerate (zero-area) triangle(s)");
    }

private:
    static constexpr int kNotYet = -2;

    [[noreturn]] void fail(const std::string& message) const { throw InputError(path_ + ": " + message); }
    void warn(const std::string& message) { diagnostics_.warn(path_ + ": " + message); }

    // ---- asset -------------------------------------------------------------------------

    void checkAsset() const {
        checkVersionAndExtensions(path_, model_.asset.version, model_.asset.minVersion, model_.extensionsRequired);
    }

    // Every texture's image must be there, used by a material or not: a missing file is worth
    // a warning even when only a normal map (which we do not read) refers to it.
    void checkImagesPresent() {
        for (size_t t = 0; t < model_.textures.size(); ++t) {
            const int source = model_.textures[t].source;
            if (source < 0 || static_cast<size_t>(source) >= model_.images.size()) {
                warn(textureName(static_cast<int>(t)) + " refers to image " + std::to_string(source) +
                     ", which does not exist");
                continue;
            }
            const tinygltf::Image& image = model_.images[static_cast<size_t>(source)];
            if (image.bufferView < 0 && encoded_.bytes.count(source) == 0 && !reportedImages_[source]) {
                reportedImages_[source] = true;
                warn(gltf::imageName(model_, source) + " is missing (" + textureName(static_cast<int>(t)) + " uses it)");
            }
        }
    }

    std::string textureName(int index) const {
        std::string name = "texture " + std::to_string(index);
        if (index >= 0 && static_cast<size_t>(index) < model_.textures.size())
            name += quoted(model_.textures[static_cast<size_t>(index)].name);
        return name;
    }

    // ---- materials ---------------------------------------------------------------------

    std::string materialName(int index) const {
        return "material " + std::to_string(index) + quoted(model_.materials[static_cast<size_t>(index)].name);
    }

    float factor(double value, double lo, double hi, const std::string& what) {
        if (!std::isfinite(value)) fail(what + " is not finite");
        if (value < lo || value > hi) {
            warn(what + " = " + shortNumber(value) + " is " + (value < lo ? "below " + shortNumber(lo) : "above " + shortNumber(hi)) +
                 "; clamped");
            value = std::clamp(value, lo, hi);
        }
        return static_cast<float>(value);
    }

    static const tinygltf::Value* member(const tinygltf::ExtensionMap& extensions, const std::string& extension,
                                         const std::string& key) {
        const auto it = extensions.find(extension);
        if (it == extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return nullptr;
        return &it->second.Get(key);
    }

    double number(const tinygltf::ExtensionMap& extensions, const std::string& extension, const std::string& key,
                  double fallback, const std::string& what) const {
        const tinygltf::Value* value = member(extensions, extension, key);
        if (!value) return fallback;
        if (!value->IsNumber()) fail(what + ": " + extension + "." + key + " is not a number");
        return value->GetNumberAsDouble();
    }

    Material material(int index) {
        const tinygltf::Material& source = model_.materials[static_cast<size_t>(index)];
        const std::string what = materialName(index);
        Material m;
        m.name = source.name;

        const auto& pbr = source.pbrMetallicRoughness;
        if (pbr.baseColorFactor.size() != 4) fail(what + ": baseColorFactor does not have 4 components");
        for (int c = 0; c < 4; ++c)
            m.baseColorFactor[c] = factor(pbr.baseColorFactor[static_cast<size_t>(c)], 0.0, 1.0, what + " baseColorFactor");
        m.metallic = factor(pbr.metallicFactor, 0.0, 1.0, what + " metallicFactor");
        m.roughness = factor(pbr.roughnessFactor, 0.0, 1.0, what + " roughnessFactor");
        m.baseColorTexture = textureRef(pbr.baseColorTexture, what + " baseColorTexture");

        if (!source.emissiveFactor.empty()) {
            if (source.emissiveFactor.size() != 3) fail(what + ": emissiveFactor does not have 3 components");
            bool aboveOne = false;
            for (int c = 0; c < 3; ++c) {
                const double e = source.emissiveFactor[static_cast<size_t>(c)];
                aboveOne = aboveOne || e > 1.0;
                // Above 1 is out of spec (core glTF caps it at 1) but common in exporters that mean
                // "bright": keep the value, say so.
                m.emissiveFactor[c] = factor(e, 0.0, kInfinity, what + " emissiveFactor");
            }
            if (aboveOne)
                warn(what + ": emissiveFactor above 1 is out of spec (use KHR_materials_emissive_strength); kept as is");
        }
        m.emissiveStrength = factor(number(source.extensions, "KHR_materials_emissive_strength", "emissiveStrength",
                                           1.0, what),
                                    0.0, kInfinity, what + " emissiveStrength");
        m.emissiveTexture = textureRef(source.emissiveTexture, what + " emissiveTexture");

        if (source.alphaMode == "OPAQUE")
            m.alphaMode = AlphaMode::Opaque;
        else if (source.alphaMode == "MASK")
            m.alphaMode = AlphaMode::Mask;
        else if (source.alphaMode == "BLEND")
            m.alphaMode = AlphaMode::Blend;
        else
            warn(what + ": alphaMode '" + source.alphaMode + "' is unknown; OPAQUE used");
        m.alphaCutoff = factor(source.alphaCutoff, 0.0, kInfinity, what + " alphaCutoff");
        m.doubleSided = source.doubleSided;

        m.transmission = factor(number(source.extensions, "KHR_materials_transmission", "transmissionFactor", 0.0, what),
                                0.0, 1.0, what + " transmissionFactor");
        const double ior = number(source.extensions, "KHR_materials_ior", "ior", 1.5, what);
        if (!std::isfinite(ior)) fail(what + ": ior is not finite");
        if (ior < 1.0)
            warn(what + ": ior " + std::to_string(ior) + " is below 1; 1.5 used");
        else
            m.ior = static_cast<float>(ior);
        return m;
    }

    TextureRef textureRef(const tinygltf::TextureInfo& info, const std::string& what) {
        TextureRef ref;
        if (info.index < 0) return ref;
        ref.texCoord = info.texCoord;
        const auto& ext = info.extensions;
        const std::string transform = "KHR_texture_transform";
        if (const tinygltf::Value* offset = member(ext, transform, "offset")) {
            if (offset->ArrayLen() != 2 || !offset->Get(0).IsNumber() || !offset->Get(1).IsNumber())
                fail(what + ": KHR_texture_transform.offset is not two numbers");
            ref.transform.offset = vec2(offset->Get(0).GetNumberAsDouble(), offset->Get(1).GetNumberAsDouble());
        }
        if (const tinygltf::Value* scale = member(ext, transform, "scale")) {
            if (scale->ArrayLen() != 2 || !scale->Get(0).IsNumber() || !scale->Get(1).IsNumber())
                fail(what + ": KHR_texture_transform.scale is not two numbers");
            ref.transform.scale = vec2(scale->Get(0).GetNumberAsDouble(), scale->Get(1).GetNumberAsDouble());
        }
        ref.transform.rotation = static_cast<float>(number(ext, transform, "rotation", 0.0, what));
        const double texCoord = number(ext, transform, "texCoord", ref.texCoord, what);
        ref.texCoord = texCoord >= 0.0 && texCoord <= 1.0 && texCoord == std::floor(texCoord) ? static_cast<int>(texCoord)
                                                                                                : -1;
        if (!isFinite(vec3(ref.transform.offset, ref.transform.rotation)) ||
            !isFinite(vec3(ref.transform.scale, 0.0f)))
            fail(what + ": KHR_texture_transform has a non-finite value");
        if (ref.texCoord < 0 || ref.texCoord > 1) {
            warn(what + " uses a TEXCOORD set other than 0 and 1; texture ignored");
            return TextureRef{};
        }
        ref.texture = sceneTexture(info.index, what);
        return ref;
    }

    // The Scene texture for glTF texture `index`, decoded on first use; -1 when unusable.
    int sceneTexture(int index, const std::string& what) {
        if (index < 0 || static_cast<size_t>(index) >= model_.textures.size()) {
            warn(what + " refers to texture " + std::to_string(index) + ", which does not exist; ignored");
            return -1;
        }
        int& slot = textureSlots_[static_cast<size_t>(index)];
        if (slot != kNotYet) return slot;
        slot = -1;
        const tinygltf::Texture& source = model_.textures[static_cast<size_t>(index)];
        if (source.source < 0 || static_cast<size_t>(source.source) >= model_.images.size())
            return slot;  // checkImagesPresent already warned
        std::string problem;
        Texture texture;
        texture.image = gltf::decodeColorImage(model_, source.source, encoded_, path_, problem);
        if (texture.image.empty()) {
            if (!reportedImages_[source.source]) {
                reportedImages_[source.source] = true;
                warn(gltf::imageName(model_, source.source) + " " + problem + "; " + textureName(index) + " ignored");
            }
            return slot;
        }
        const tinygltf::Image& image = model_.images[static_cast<size_t>(source.source)];
        texture.name = !image.name.empty() ? image.name
                       : (!image.uri.empty() && image.uri.rfind("data:", 0) != 0) ? image.uri
                                                                                  : gltf::imageName(model_, source.source);
        if (source.sampler >= 0) {
            if (static_cast<size_t>(source.sampler) >= model_.samplers.size())
                fail(textureName(index) + " refers to sampler " + std::to_string(source.sampler) +
                     ", which does not exist");
            const tinygltf::Sampler& sampler = model_.samplers[static_cast<size_t>(source.sampler)];
            texture.wrapS = wrapMode(sampler.wrapS);
            texture.wrapT = wrapMode(sampler.wrapT);
            texture.nearest = sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
        }
        scene_.textures.push_back(std::move(texture));
        slot = static_cast<int>(scene_.textures.size()) - 1;
        return slot;
    }

    static WrapMode wrapMode(int mode) {
        switch (mode) {
        case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return WrapMode::ClampToEdge;
        case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return WrapMode::MirroredRepeat;
        default: return WrapMode::Repeat;
        }
    }

    // ---- hierarchy ---------------------------------------------------------------------

    std::vector<int> sceneRoots() const {
        if (!model_.scenes.empty()) {
            int index = model_.defaultScene >= 0 ? model_.defaultScene : 0;
            if (static_cast<size_t>(index) >= model_.scenes.size())
                fail("the default scene " + std::to_string(index) + " does not exist (the file has " +
                     std::to_string(model_.scenes.size()) + " scenes)");
            return model_.scenes[static_cast<size_t>(index)].nodes;
        }
        // No scenes: every node that is nobody's child is a root.
        std::vector<char> isChild(model_.nodes.size(), 0);
        for (const tinygltf::Node& node : model_.nodes)
            for (int child : node.children)
                if (child >= 0 && static_cast<size_t>(child) < model_.nodes.size()) isChild[static_cast<size_t>(child)] = 1;
        std::vector<int> roots;
        for (size_t n = 0; n < model_.nodes.size(); ++n)
            if (!isChild[n]) roots.push_back(static_cast<int>(n));
        return roots;
    }

    std::string nodeName(int index) const {
        return "node " + std::to_string(index) + quoted(model_.nodes[static_cast<size_t>(index)].name);
    }

    // A rotation's matrix with the entries that lie within rounding of 0 or ±1 made exact. A
    // quarter turn written as a quaternion of √½ components comes out of it with 2·10⁻¹⁶ where
    // 0 belongs, which moves a wall lying on a voxel boundary into the voxel beside it
    // (docs/decisions.md, "Exact quarter turns"). Entries of any other rotation are farther
    // than 10⁻¹² from 0 and ±1 (a turn of 10⁻⁶ rad has 10⁻⁶ there).
    static glm::dmat4 exactQuarterTurns(glm::dmat4 m) {
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) {
                double& v = m[c][r];
                if (std::fabs(v) < 1e-12) v = 0.0;
                else if (std::fabs(std::fabs(v) - 1.0) < 1e-12) v = v > 0.0 ? 1.0 : -1.0;
            }
        return m;
    }

    glm::dmat4 localTransform(int index) const {
        const tinygltf::Node& node = model_.nodes[static_cast<size_t>(index)];
        if (!node.matrix.empty()) {
            if (node.matrix.size() != 16) fail(nodeName(index) + ": matrix does not have 16 elements");
            return glm::make_mat4(node.matrix.data());  // both column-major
        }
        glm::dmat4 m(1.0);
        if (!node.translation.empty()) {
            if (node.translation.size() != 3) fail(nodeName(index) + ": translation does not have 3 elements");
            m[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
        }
        if (!node.rotation.empty()) {
            if (node.rotation.size() != 4) fail(nodeName(index) + ": rotation does not have 4 elements");
            glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // (w, x, y, z)
            const double length = glm::length(q);
            if (!(length > 0.0) || !std::isfinite(length))
                fail(nodeName(index) + ": rotation is not a unit quaternion");
            m = m * exactQuarterTurns(glm::mat4_cast(q / length));
        }
        if (!node.scale.empty()) {
            if (node.scale.size() != 3) fail(nodeName(index) + ": scale does not have 3 elements");
            m = m * glm::dmat4(glm::dvec4(node.scale[0], 0, 0, 0), glm::dvec4(0, node.scale[1], 0, 0),
                               glm::dvec4(0, 0, node.scale[2], 0), glm::dvec4(0, 0, 0, 1));
        }
        return m;
    }

    // Depth-first, children in order, without recursion (a deep chain must not overflow the
    // stack); a node reached twice in one pass over the roots (visited_ cleared before it)
    // means a cycle or a shared child, both invalid glTF. visit(node index, its world
    // transform) for every node.
    template <typename Visit>
    void visitHierarchy(int root, Visit&& visit) {
        std::vector<std::pair<int, glm::dmat4>> stack{{root, glm::dmat4(1.0)}};
        while (!stack.empty()) {
            const auto [index, parent] = stack.back();
            stack.pop_back();
            if (index < 0 || static_cast<size_t>(index) >= model_.nodes.size())
                fail("node " + std::to_string(index) + " does not exist (the file has " +
                     std::to_string(model_.nodes.size()) + " nodes)");
            if (visited_.empty()) visited_.assign(model_.nodes.size(), 0);
            if (visited_[static_cast<size_t>(index)])
                fail(nodeName(index) + " is reached twice: the node hierarchy has a cycle or a node with two parents");
            visited_[static_cast<size_t>(index)] = 1;

            const tinygltf::Node& node = model_.nodes[static_cast<size_t>(index)];
            const glm::dmat4 world = parent * localTransform(index);
            if (!allFinite(world)) fail(nodeName(index) + " has a non-finite transform");
            visit(index, world);
            for (auto child = node.children.rbegin(); child != node.children.rend(); ++child)
                stack.emplace_back(*child, world);
        }
    }

    // A node's mesh, camera and light into the scene; `world` is already in the local frame.
    void visitNode(int index, const glm::dmat4& world) {
        const tinygltf::Node& node = model_.nodes[static_cast<size_t>(index)];
        if (node.mesh >= 0) {
            addMeshInstance(node.mesh, index, world);
            if (node.skin >= 0 && skinnedNodes_++ == 0)
                warn(nodeName(index) + " is skinned; skins are not applied, the mesh stays in its bind pose");
        }
        if (node.camera >= 0) addCamera(node.camera, index, world);
        if (const tinygltf::Value* light = member(node.extensions, "KHR_lights_punctual", "light")) {
            if (!light->IsInt()) fail(nodeName(index) + ": KHR_lights_punctual.light is not an index");
            addLight(light->GetNumberAsInt(), index, world);
        }
    }

    // The world box of a mesh instance's triangle positions, in double. Errors are left to
    // the main pass (addMeshInstance), which reads the same accessors and reports them.
    void growBounds(int meshIndex, const glm::dmat4& world, glm::dvec3& lower, glm::dvec3& upper) const {
        if (static_cast<size_t>(meshIndex) >= model_.meshes.size()) return;
        for (const tinygltf::Primitive& prim : model_.meshes[static_cast<size_t>(meshIndex)].primitives) {
            const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
                continue;
            const auto it = prim.attributes.find("POSITION");
            if (it == prim.attributes.end()) continue;
            gltf::FloatArray positions;
            try {
                positions = gltf::readFloatAccessor(model_, it->second, {3}, path_ + " POSITION");
            } catch (const InputError&) {
                continue;
            }
            for (size_t i = 0; i < positions.count; ++i) {
                const float* p = &positions.values[3 * i];
                const glm::dvec3 w(world * glm::dvec4(p[0], p[1], p[2], 1.0));
                if (!std::isfinite(w.x) || !std::isfinite(w.y) || !std::isfinite(w.z)) continue;
                lower = glm::min(lower, w);
                upper = glm::max(upper, w);
            }
        }
    }

    // ---- cameras and lights ------------------------------------------------------------

    void addCamera(int index, int nodeIndex, const glm::dmat4& world) {
        if (static_cast<size_t>(index) >= model_.cameras.size())
            fail(nodeName(nodeIndex) + " refers to camera " + std::to_string(index) + ", which does not exist");
        const tinygltf::Camera& source = model_.cameras[static_cast<size_t>(index)];
        const std::string what = "camera " + std::to_string(index) + quoted(source.name);
        if (source.type != "perspective") {
            warn(what + " is " + (source.type.empty() ? std::string("untyped") : source.type) +
                 "; only perspective cameras are used, skipped");
            return;
        }
        const double yfov = source.perspective.yfov;
        if (!(yfov > 0.0 && yfov < kPi)) fail(what + ": yfov " + std::to_string(yfov) + " is not in (0, pi)");
        const glm::dmat3 basis(world);
        const glm::dvec3 forward = basis * glm::dvec3(0, 0, -1);
        const glm::dvec3 upRaw = basis * glm::dvec3(0, 1, 0);
        const glm::dvec3 up = upRaw - glm::dot(upRaw, forward) / glm::dot(forward, forward) * forward;
        if (!(glm::length(forward) > 0.0) || !(glm::length(up) > 0.0))
            fail(what + " on " + nodeName(nodeIndex) + " has a singular transform");
        Camera camera;
        camera.name = !source.name.empty() ? source.name : model_.nodes[static_cast<size_t>(nodeIndex)].name;
        camera.position = vec3(world[3]);
        camera.forward = vec3(glm::normalize(forward));
        camera.up = vec3(glm::normalize(up));
        camera.yfov = static_cast<float>(yfov);
        const double aspect = source.perspective.aspectRatio;
        camera.aspectRatio = std::isfinite(aspect) && aspect > 0.0 ? static_cast<float>(aspect) : 0.0f;
        scene_.cameras.push_back(camera);
    }

    void addLight(int index, int nodeIndex, const glm::dmat4& world) {
        if (index < 0 || static_cast<size_t>(index) >= model_.lights.size())
            fail(nodeName(nodeIndex) + " refers to KHR_lights_punctual light " + std::to_string(index) +
                 ", which does not exist (the file declares " + std::to_string(model_.lights.size()) + ")");
        const tinygltf::Light& source = model_.lights[static_cast<size_t>(index)];
        const std::string what = "light " + std::to_string(index) + quoted(source.name);
        Light light;
        light.name = !source.name.empty() ? source.name : model_.nodes[static_cast<size_t>(nodeIndex)].name;
        if (source.type == "point")
            light.type = LightType::Point;
        else if (source.type == "spot")
            light.type = LightType::Spot;
        else if (source.type == "directional")
            light.type = LightType::Directional;
        else
            fail(what + " has unknown type '" + source.type + "'");
        if (!source.color.empty()) {
            if (source.color.size() != 3) fail(what + ": color does not have 3 components");
            for (int c = 0; c < 3; ++c)
                light.color[c] = factor(source.color[static_cast<size_t>(c)], 0.0, 1.0, what + " color");
        }
        light.intensity = factor(source.intensity / kLumensPerWatt, 0.0, kInfinity, what + " intensity");
        if (!std::isfinite(source.range) || source.range < 0.0) fail(what + ": range must be a positive number");
        light.range = static_cast<float>(source.range);
        if (light.type == LightType::Spot) {
            light.outerConeAngle = factor(source.spot.outerConeAngle, 1e-6, kPi / 2, what + " outerConeAngle");
            light.innerConeAngle = factor(source.spot.innerConeAngle, 0.0, light.outerConeAngle, what + " innerConeAngle");
        }
        const glm::dvec3 direction = glm::dmat3(world) * glm::dvec3(0, 0, -1);
        if (!(glm::length(direction) > 0.0)) fail(what + " on " + nodeName(nodeIndex) + " has a singular transform");
        light.position = vec3(world[3]);
        light.direction = vec3(glm::normalize(direction));
        if (const auto bake = source.extensions.find("VOXLIGHT_light_bake"); bake != source.extensions.end()) {
            const tinygltf::Value& mode = bake->second.Get("mode");
            if (!mode.IsString() || !parseLightBake(mode.Get<std::string>(), light.bake))
                fail(what + ": VOXLIGHT_light_bake.mode must be \"all\", \"indirect\" or \"shadowmask\"");
            const tinygltf::Value& disk = bake->second.Get("angularDiameter");
            if (disk.Type() != tinygltf::NULL_TYPE) {
                if (light.type != LightType::Directional)
                    fail(what + ": VOXLIGHT_light_bake.angularDiameter is for directional lights");
                if (!disk.IsNumber()) fail(what + ": VOXLIGHT_light_bake.angularDiameter must be a number (radians)");
                light.angularDiameter =
                    factor(disk.GetNumberAsDouble(), 0.0, kPi / 2, what + " VOXLIGHT_light_bake.angularDiameter");
            }
        }
        light.sourceLight = index;
        scene_.lights.push_back(light);
    }

    // ---- meshes ------------------------------------------------------------------------

    void addMeshInstance(int meshIndex, int nodeIndex, const glm::dmat4& world) {
        if (static_cast<size_t>(meshIndex) >= model_.meshes.size())
            fail(nodeName(nodeIndex) + " refers to mesh " + std::to_string(meshIndex) + ", which does not exist");
        const glm::dmat3 linear(world);
        const double det = glm::determinant(linear);
        const double scale = glm::length(linear[0]) * glm::length(linear[1]) * glm::length(linear[2]);
        // Relative to the column lengths, so a tiny but well-shaped scale is still accepted.
        if (!std::isfinite(det) || !(std::abs(det) > 1e-12 * scale))
            fail(nodeName(nodeIndex) + " has a singular transform (determinant " + std::to_string(det) +
                 ") and carries mesh " + std::to_string(meshIndex));

        const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(meshIndex)];
        const std::string baseName = !mesh.name.empty() ? mesh.name
                                     : !model_.nodes[static_cast<size_t>(nodeIndex)].name.empty()
                                         ? model_.nodes[static_cast<size_t>(nodeIndex)].name
                                         : "mesh" + std::to_string(meshIndex);
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const std::string where = path_ + ": mesh " + std::to_string(meshIndex) + quoted(mesh.name) +
                                      " primitive " + std::to_string(p);
            Mesh out = primitive(mesh.primitives[p], where, world, det < 0.0);
            if (out.indices.empty()) continue;
            out.name = baseName + "/" + std::to_string(p);
            out.node = model_.nodes[static_cast<size_t>(nodeIndex)].name;
            out.source.mesh = meshIndex;
            out.source.primitive = static_cast<int>(p);
            out.source.node = nodeIndex;
            out.source.mirrored = det < 0.0;
            scene_.meshes.push_back(std::move(out));
        }
    }

    static std::vector<uint32_t> triangulate(const std::vector<uint32_t>& v, int mode) {
        std::vector<uint32_t> out;
        const size_t n = v.size();
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            out.assign(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n - n % 3));
        } else if (n >= 3) {
            out.reserve((n - 2) * 3);
            for (size_t i = 0; i + 2 < n; ++i) {
                if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {  // spec 3.7.2.1: keeps every triangle CCW
                    const size_t odd = i % 2;
                    out.insert(out.end(), {v[i], v[i + 1 + odd], v[i + 2 - odd]});
                } else {  // fan
                    out.insert(out.end(), {v[i + 1], v[i + 2], v[0]});
                }
            }
        }
        return out;
    }

    Mesh primitive(const tinygltf::Primitive& prim, const std::string& where, const glm::dmat4& world, bool mirrored) {
        Mesh mesh;
        const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
            mode == TINYGLTF_MODE_LINE_STRIP) {
            if (skippedPrimitives_++ == 0) firstSkipped_ = where.substr(path_.size() + 2);
            return mesh;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
            throw InputError(where + ": mode " + std::to_string(mode) + " is not a glTF primitive mode");
        if (prim.material >= 0 && static_cast<size_t>(prim.material) >= model_.materials.size())
            throw InputError(where + ": material " + std::to_string(prim.material) + " does not exist");
        mesh.material = prim.material;

        const auto attribute = [&](const char* name) {
            const auto it = prim.attributes.find(name);
            return it == prim.attributes.end() ? -1 : it->second;
        };
        const int positionAccessor = attribute("POSITION");
        if (positionAccessor < 0) {
            warn(where.substr(path_.size() + 2) + " has no POSITION attribute; skipped");
            return mesh;
        }
        const gltf::FloatArray positions = gltf::readFloatAccessor(model_, positionAccessor, {3}, where + " POSITION");
        const size_t vertexCount = positions.count;
        const auto read = [&](const char* name, std::initializer_list<int> sizes) {
            gltf::FloatArray array;
            const int accessor = attribute(name);
            if (accessor < 0) return array;
            array = gltf::readFloatAccessor(model_, accessor, sizes, where + " " + name);
            if (array.count != vertexCount)
                throw InputError(where + " " + name + ": accessor " + std::to_string(accessor) + " has " +
                                 std::to_string(array.count) + " elements but POSITION has " +
                                 std::to_string(vertexCount));
            for (size_t i = 0; i < array.values.size(); ++i)
                if (!std::isfinite(array.values[i]) && std::string(name) != "NORMAL")
                    throw InputError(where + " " + name + ": accessor " + std::to_string(accessor) +
                                     " has a non-finite value (NaN or Inf) at element " +
                                     std::to_string(i / static_cast<size_t>(array.components)));
            return array;
        };

        // Positions to world space, in double so a large translation loses no more than float.
        mesh.positions.resize(vertexCount);
        for (size_t i = 0; i < vertexCount; ++i) {
            const float* p = &positions.values[3 * i];
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
                throw InputError(where + " POSITION: accessor " + std::to_string(positionAccessor) +
                                 " has a non-finite value (NaN or Inf) at vertex " + std::to_string(i));
            const glm::dvec4 w = world * glm::dvec4(p[0], p[1], p[2], 1.0);
            mesh.positions[i] = vec3(w);
            if (!isFinite(mesh.positions[i]))
                throw InputError(where + " POSITION: vertex " + std::to_string(i) +
                                 " overflows single precision after the node transform");
        }

        std::vector<uint32_t> vertices;
        if (prim.indices >= 0) {
            vertices = gltf::readIndexAccessor(model_, prim.indices, where + " indices");
            for (size_t k = 0; k < vertices.size(); ++k)
                if (vertices[k] >= vertexCount)
                    throw InputError(where + " indices: accessor " + std::to_string(prim.indices) + " index " +
                                     std::to_string(vertices[k]) + " at position " + std::to_string(k) +
                                     " is out of range (POSITION has " + std::to_string(vertexCount) + " vertices)");
        } else {
            vertices.resize(vertexCount);
            for (size_t i = 0; i < vertexCount; ++i) vertices[i] = static_cast<uint32_t>(i);
        }
        if (mode == TINYGLTF_MODE_TRIANGLES && vertices.size() % 3 != 0)
            warn(where.substr(path_.size() + 2) + ": " + std::to_string(vertices.size()) +
                 " triangle vertices is not a multiple of 3; the last " + std::to_string(vertices.size() % 3) +
                 " ignored");
        std::vector<uint32_t> triangles = triangulate(vertices, mode);
        if (mirrored)  // a mirroring transform turns CCW into CW: swap two corners back
            for (size_t t = 0; t + 2 < triangles.size(); t += 3) std::swap(triangles[t + 1], triangles[t + 2]);

        // Zero-area triangles (after the transform, in the float precision every consumer
        // uses) have no normal and no surface: drop them, count them.
        mesh.indices.reserve(triangles.size());
        for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
            const vec3& a = mesh.positions[triangles[t]];
            const vec3 n = glm::cross(mesh.positions[triangles[t + 1]] - a, mesh.positions[triangles[t + 2]] - a);
            const float n2 = glm::dot(n, n);
            if (n2 > 0.0f && std::isfinite(n2))
                mesh.indices.insert(mesh.indices.end(), {triangles[t], triangles[t + 1], triangles[t + 2]});
            else
                ++scene_.degenerateTrianglesDropped;
        }
        if (mesh.indices.empty()) return mesh;

        normals(mesh, read("NORMAL", {3}), world);
        const gltf::FloatArray uv0 = read("TEXCOORD_0", {2});
        const gltf::FloatArray uv1 = read("TEXCOORD_1", {2});
        const gltf::FloatArray color = read("COLOR_0", {3, 4});
        for (size_t i = 0; i < uv0.count; ++i) mesh.uv0.emplace_back(uv0.values[2 * i], uv0.values[2 * i + 1]);
        for (size_t i = 0; i < uv1.count; ++i) mesh.uv1.emplace_back(uv1.values[2 * i], uv1.values[2 * i + 1]);
        for (size_t i = 0; i < color.count; ++i) {
            const float* c = &color.values[i * static_cast<size_t>(color.components)];
            mesh.colors.emplace_back(c[0], c[1], c[2], color.components == 4 ? c[3] : 1.0f);
        }
        return mesh;
    }

    // File normals through the inverse transpose; where the file has none, or one that is
    // zero or not finite, the area-weighted average of the adjacent faces.
    static void normals(Mesh& mesh, const gltf::FloatArray& file, const glm::dmat4& world) {
        const size_t count = mesh.positions.size();
        mesh.normals.assign(count, vec3(0.0f));
        std::vector<char> valid(count, 0);
        if (file.count == count) {
            const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(glm::dmat3(world)));
            for (size_t i = 0; i < count; ++i) {
                const glm::dvec3 n = normalMatrix * glm::dvec3(file.values[3 * i], file.values[3 * i + 1],
                                                                file.values[3 * i + 2]);
                const double length = glm::length(n);
                if (length > 0.0 && std::isfinite(length)) {
                    mesh.normals[i] = vec3(n / length);
                    valid[i] = isFinite(mesh.normals[i]);
                }
            }
        }
        if (std::all_of(valid.begin(), valid.end(), [](char v) { return v != 0; })) return;

        std::vector<vec3> sum(count, vec3(0.0f));
        std::vector<vec3> first(count, vec3(0.0f));
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
            const uint32_t i0 = mesh.indices[t], i1 = mesh.indices[t + 1], i2 = mesh.indices[t + 2];
            const vec3& a = mesh.positions[i0];
            const vec3 n = glm::cross(mesh.positions[i1] - a, mesh.positions[i2] - a);  // 2 × area × unit normal
            for (uint32_t v : {i0, i1, i2}) {
                if (first[v] == vec3(0.0f)) first[v] = glm::normalize(n);
                sum[v] += n;
            }
        }
        for (size_t i = 0; i < count; ++i) {
            if (valid[i]) continue;
            const float length = glm::length(sum[i]);
            // Faces that cancel (both sides of a sheet sharing vertices) keep the first face's
            // normal; a vertex no triangle uses gets an arbitrary unit vector.
            mesh.normals[i] = length > 0.0f && std::isfinite(length) ? sum[i] / length
                              : first[i] != vec3(0.0f)                ? first[i]
                                                                      : vec3(0.0f, 1.0f, 0.0f);
        }
    }

    const std::string& path_;
    const tinygltf::Model& model_;
    const gltf::EncodedImages& encoded_;
    Diagnostics& diagnostics_;
    Scene& scene_;
    std::vector<int> textureSlots_;
    std::map<int, bool> reportedImages_;
    std::vector<char> visited_;
    size_t skippedPrimitives_ = 0;
    size_t skinnedNodes_ = 0;
    std::string firstSkipped_;
};

bool startsWithGlbMagic(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    return in.gcount() == 4 && std::equal(magic, magic + 4, "glTF");
}

}  // namespace

std::string percentDecoded(const std::string& uri) {
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
            out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}


const std::vector<std::string>& supportedGltfExtensions() { return kSupportedExtensions; }

void readGltfModel(const std::string& path, tinygltf::Model& model, gltf::EncodedImages& encoded,
                   bool filesOutsideScene) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": no such file");

    precheckJson(path, filesOutsideScene);

    std::string err, warn;
    bool ok = false;
    try {
        tinygltf::TinyGLTF reader;
        reader.SetImageLoader(&gltf::keepEncodedImage, &encoded);
        ok = startsWithGlbMagic(path) ? reader.LoadBinaryFromFile(&model, &err, &warn, path)
                                      : reader.LoadASCIIFromFile(&model, &err, &warn, path);
    } catch (const std::exception& e) {  // tinygltf throws on some malformed input (e.g. bad_alloc)
        throw InputError(path + ": cannot be parsed as glTF (" + e.what() + ")");
    }
    if (!ok) {
        while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
        for (char& c : err)
            if (c == '\n') c = ';';
        throw InputError(path + ": cannot be parsed as glTF: " + (err.empty() ? std::string("unknown error") : err));
    }
}

Scene loadGltf(const std::string& path, const LoadOptions& options) {
    tinygltf::Model model;
    gltf::EncodedImages encoded;
    readGltfModel(path, model, encoded, options.filesOutsideScene);

    Scene scene;
    scene.sourcePath = path;
    scene.name = std::filesystem::path(path).stem().string();
    Diagnostics diagnostics(options.strict, options.echoWarnings);
    Loader(path, model, encoded, diagnostics, scene).run();
    scene.warnings = diagnostics.warnings();
    return scene;
}

}  // namespace vl
