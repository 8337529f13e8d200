#include "scenes/gltf_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace vl::scenes {
namespace {

vec3 quadNormal(const Quad& q) { return glm::normalize(glm::cross(q[1] - q[0], q[3] - q[0])); }

// A quad's corners in its own plane, in metres, relative to the chart's lower corner.
struct Chart {
    size_t mesh = 0, quad = 0;
    std::array<vec2, 4> local{};
    vec2 size{0.0f};
    ivec3 placement{0};  // x, y in texels; z unused
};

Chart makeChart(const Quad& q) {
    const vec3 u = glm::normalize(q[1] - q[0]);
    const vec3 v = glm::cross(quadNormal(q), u);
    Chart chart;
    vec2 lower(kInfinity), upper(-kInfinity);
    for (int i = 0; i < 4; ++i) {
        chart.local[i] = vec2(glm::dot(q[i] - q[0], u), glm::dot(q[i] - q[0], v));
        lower = glm::min(lower, chart.local[i]);
        upper = glm::max(upper, chart.local[i]);
    }
    for (vec2& p : chart.local) p -= lower;
    chart.size = upper - lower;
    return chart;
}

// Shelf packing at `texelsPerMetre`; false when the charts do not fit the atlas.
bool packCharts(std::vector<Chart>& charts, float texelsPerMetre, int resolution, int padding) {
    int x = padding, y = padding, shelfHeight = 0;
    for (Chart& chart : charts) {
        const int w = static_cast<int>(std::ceil(chart.size.x * texelsPerMetre));
        const int h = static_cast<int>(std::ceil(chart.size.y * texelsPerMetre));
        if (x + w + padding > resolution) {
            x = padding;
            y += shelfHeight + padding;
            shelfHeight = 0;
        }
        if (x + w + padding > resolution || y + h + padding > resolution) return false;
        chart.placement = ivec3(x, y, 0);
        x += w + padding;
        shelfHeight = std::max(shelfHeight, h);
    }
    return true;
}

// Lightmap UVs for every lightmapped quad: one shared atlas, uniform texel density.
std::vector<std::vector<std::array<vec2, 4>>> layoutAtlas(const SceneDescription& scene) {
    std::vector<Chart> charts;
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        if (!scene.meshes[m].lightmapped) continue;
        for (size_t q = 0; q < scene.meshes[m].quads.size(); ++q) {
            Chart chart = makeChart(scene.meshes[m].quads[q]);
            chart.mesh = m;
            chart.quad = q;
            charts.push_back(chart);
        }
    }
    // Tallest first packs shelves tightly; ties broken by order so the layout is stable.
    std::stable_sort(charts.begin(), charts.end(),
                     [](const Chart& a, const Chart& b) { return a.size.y > b.size.y; });
    float lo = 1.0f, hi = 1e5f;
    if (!packCharts(charts, lo, scene.atlasResolution, scene.atlasPaddingTexels))
        throw std::runtime_error("atlas: charts do not fit even at 1 texel per metre");
    for (int i = 0; i < 40; ++i) {
        const float mid = 0.5f * (lo + hi);
        (packCharts(charts, mid, scene.atlasResolution, scene.atlasPaddingTexels) ? lo : hi) = mid;
    }
    packCharts(charts, lo, scene.atlasResolution, scene.atlasPaddingTexels);

    std::vector<std::vector<std::array<vec2, 4>>> uvs(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) uvs[m].resize(scene.meshes[m].quads.size());
    const float r = static_cast<float>(scene.atlasResolution);
    for (const Chart& chart : charts)
        for (int i = 0; i < 4; ++i) {
            const vec2 texel = vec2(chart.placement.x, chart.placement.y) + chart.local[i] * lo;
            uvs[chart.mesh][chart.quad][i] = texel / r;  // glTF v runs down from the image top
        }
    return uvs;
}

class BinaryBuffer {
public:
    // Appends raw floats or uints, 4-byte aligned; returns the byte offset.
    template <typename T>
    size_t append(const std::vector<T>& values) {
        const size_t offset = bytes_.size();
        bytes_.resize(offset + values.size() * sizeof(T));
        std::memcpy(bytes_.data() + offset, values.data(), values.size() * sizeof(T));
        return offset;
    }
    const std::vector<char>& bytes() const { return bytes_; }

private:
    std::vector<char> bytes_;
};

std::string jsonVec(const float* v, int n) {
    std::ostringstream out;
    out << std::setprecision(9) << '[';
    for (int i = 0; i < n; ++i) out << (i ? "," : "") << v[i];
    out << ']';
    return out.str();
}

std::string jsonString(const std::string& s) { return '"' + s + '"'; }

}  // namespace

void writeGltf(const SceneDescription& scene, const std::string& directory, const std::string& stem) {
    const auto atlas = layoutAtlas(scene);
    BinaryBuffer buffer;
    std::vector<std::string> bufferViews, accessors, meshes, nodes;

    auto addAccessor = [&](size_t offset, size_t bytes, int componentType, size_t count, const char* type,
                           const std::string& extra, int target) {
        bufferViews.push_back("{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) +
                              ",\"byteLength\":" + std::to_string(bytes) +
                              ",\"target\":" + std::to_string(target) + "}");
        accessors.push_back("{\"bufferView\":" + std::to_string(bufferViews.size() - 1) +
                            ",\"componentType\":" + std::to_string(componentType) +
                            ",\"count\":" + std::to_string(count) + ",\"type\":\"" + type + "\"" + extra + "}");
        return accessors.size() - 1;
    };
    constexpr int kFloat = 5126, kUint32 = 5125, kArray = 34962, kElements = 34963;

    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const SceneMesh& mesh = scene.meshes[m];
        std::vector<float> positions, normals, uv0, uv1;
        std::vector<uint32_t> indices;
        vec3 lower(kInfinity), upper(-kInfinity);
        for (size_t q = 0; q < mesh.quads.size(); ++q) {
            const Quad& quad = mesh.quads[q];
            const vec3 n = quadNormal(quad);
            const uint32_t base = static_cast<uint32_t>(positions.size() / 3);
            static const vec2 kCorners[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
            const SceneMaterial& material = scene.materials.at(size_t(mesh.material));
            const vec2 repeats = material.textureMetres > 0.0f
                                     ? vec2(glm::length(quad[1] - quad[0]), glm::length(quad[3] - quad[0])) /
                                           material.textureMetres
                                     : vec2(1.0f);
            for (int i = 0; i < 4; ++i) {
                positions.insert(positions.end(), {quad[i].x, quad[i].y, quad[i].z});
                normals.insert(normals.end(), {n.x, n.y, n.z});
                uv0.insert(uv0.end(), {kCorners[i].x * repeats.x, kCorners[i].y * repeats.y});
                if (mesh.lightmapped) uv1.insert(uv1.end(), {atlas[m][q][i].x, atlas[m][q][i].y});
                lower = glm::min(lower, quad[i]);
                upper = glm::max(upper, quad[i]);
            }
            indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        }
        const size_t vertexCount = positions.size() / 3;
        const std::string bounds = ",\"min\":" + jsonVec(&lower.x, 3) + ",\"max\":" + jsonVec(&upper.x, 3);
        const size_t pos = addAccessor(buffer.append(positions), positions.size() * 4, kFloat, vertexCount, "VEC3", bounds, kArray);
        const size_t nrm = addAccessor(buffer.append(normals), normals.size() * 4, kFloat, vertexCount, "VEC3", "", kArray);
        const size_t tc0 = addAccessor(buffer.append(uv0), uv0.size() * 4, kFloat, vertexCount, "VEC2", "", kArray);
        std::string attributes = "\"POSITION\":" + std::to_string(pos) + ",\"NORMAL\":" + std::to_string(nrm) +
                                 ",\"TEXCOORD_0\":" + std::to_string(tc0);
        if (mesh.lightmapped) {
            const size_t tc1 = addAccessor(buffer.append(uv1), uv1.size() * 4, kFloat, vertexCount, "VEC2", "", kArray);
            attributes += ",\"TEXCOORD_1\":" + std::to_string(tc1);
        }
        const size_t idx = addAccessor(buffer.append(indices), indices.size() * 4, kUint32, indices.size(), "SCALAR", "", kElements);
        meshes.push_back("{\"name\":" + jsonString(mesh.name) + ",\"primitives\":[{\"attributes\":{" + attributes +
                         "},\"indices\":" + std::to_string(idx) + ",\"material\":" + std::to_string(mesh.material) + "}]}");
        nodes.push_back("{\"name\":" + jsonString(mesh.name) + ",\"mesh\":" + std::to_string(m) + "}");
    }

    std::vector<std::string> materials, images, textures;
    bool usesEmissiveStrength = false;
    for (const SceneMaterial& material : scene.materials) {
        const float base[4] = {material.baseColor.x, material.baseColor.y, material.baseColor.z, 1.0f};
        std::string texture;
        if (!material.baseColorTexture.empty()) {
            images.push_back("{\"uri\":" + jsonString(material.baseColorTexture) + "}");
            textures.push_back("{\"source\":" + std::to_string(images.size() - 1) + ",\"sampler\":0}");
            texture = ",\"baseColorTexture\":{\"index\":" + std::to_string(textures.size() - 1) + "}";
        }
        std::string json = "{\"name\":" + jsonString(material.name) + ",\"pbrMetallicRoughness\":{\"baseColorFactor\":" +
                           jsonVec(base, 4) + texture + ",\"metallicFactor\":0,\"roughnessFactor\":1}";
        if (maxComponent(material.emissiveFactor) > 0.0f) {
            json += ",\"emissiveFactor\":" + jsonVec(&material.emissiveFactor.x, 3);
            if (material.emissiveStrength != 1.0f) {
                usesEmissiveStrength = true;
                std::ostringstream strength;
                strength << std::setprecision(9) << material.emissiveStrength;
                json += ",\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":" + strength.str() + "}}";
            }
        }
        materials.push_back(json + "}");
    }

    std::vector<std::string> lights;
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        const ScenePointLight& light = scene.lights[l];
        std::ostringstream json;
        json << std::setprecision(9) << "{\"name\":" << jsonString(light.name) << ",\"type\":\"point\",\"color\":"
             << jsonVec(&light.color.x, 3) << ",\"intensity\":" << light.intensityCandela << "}";
        lights.push_back(json.str());
        nodes.push_back("{\"name\":" + jsonString(light.name) + ",\"translation\":" + jsonVec(&light.position.x, 3) +
                        ",\"extensions\":{\"KHR_lights_punctual\":{\"light\":" + std::to_string(l) + "}}}");
    }
    {
        std::ostringstream camera;
        camera << std::setprecision(9) << "{\"type\":\"perspective\",\"perspective\":{\"yfov\":" << scene.camera.yfov
               << ",\"aspectRatio\":" << scene.camera.aspectRatio << ",\"znear\":0.01,\"zfar\":100}}";
        nodes.push_back("{\"name\":\"Camera\",\"camera\":0,\"translation\":" + jsonVec(&scene.camera.position.x, 3) + "}");
        std::vector<std::string> extensionsUsed;
        if (usesEmissiveStrength) extensionsUsed.push_back("\"KHR_materials_emissive_strength\"");
        if (!lights.empty()) extensionsUsed.push_back("\"KHR_lights_punctual\"");

        auto join = [](const std::vector<std::string>& items) {
            std::string out;
            for (size_t i = 0; i < items.size(); ++i) out += (i ? ",\n    " : "") + items[i];
            return out;
        };
        std::string sceneNodes;
        for (size_t i = 0; i < nodes.size(); ++i) sceneNodes += (i ? "," : "") + std::to_string(i);

        std::ostringstream json;
        json << "{\n  \"asset\":{\"version\":\"2.0\",\"generator\":\"voxlight scenes/make_scenes\"},\n";
        if (!extensionsUsed.empty()) json << "  \"extensionsUsed\":[" << join(extensionsUsed) << "],\n";
        if (!lights.empty()) json << "  \"extensions\":{\"KHR_lights_punctual\":{\"lights\":[" << join(lights) << "]}},\n";
        json << "  \"scene\":0,\n  \"scenes\":[{\"name\":" << jsonString(stem) << ",\"nodes\":[" << sceneNodes << "]}],\n"
             << "  \"nodes\":[\n    " << join(nodes) << "],\n"
             << "  \"meshes\":[\n    " << join(meshes) << "],\n"
             << "  \"materials\":[\n    " << join(materials) << "],\n";
        if (!textures.empty())  // linear filtering, repeat (glTF's defaults, stated)
            json << "  \"images\":[" << join(images) << "],\n  \"textures\":[" << join(textures)
                 << "],\n  \"samplers\":[{\"magFilter\":9729,\"minFilter\":9987,\"wrapS\":10497,\"wrapT\":10497}],\n";
        json
             << "  \"cameras\":[" << camera.str() << "],\n"
             << "  \"accessors\":[\n    " << join(accessors) << "],\n"
             << "  \"bufferViews\":[\n    " << join(bufferViews) << "],\n"
             << "  \"buffers\":[{\"uri\":" << jsonString(stem + ".bin") << ",\"byteLength\":" << buffer.bytes().size()
             << "}]\n}\n";

        std::ofstream gltf(directory + "/" + stem + ".gltf");
        gltf << json.str();
        std::ofstream bin(directory + "/" + stem + ".bin", std::ios::binary);
        bin.write(buffer.bytes().data(), static_cast<std::streamsize>(buffer.bytes().size()));
        if (!gltf || !bin) throw std::runtime_error("cannot write " + directory + "/" + stem + ".gltf");
    }
}

}  // namespace vl::scenes
