#include "trace/trace_scene.h"

#include "core/error.h"
#include "core/shared_edge.h"
#include "scene/scene.h"
#include "trace/bvh.h"

#include <glm/gtc/matrix_access.hpp>

#include <cmath>
#include <string>

namespace vl {
namespace {

TraceTextureRef convertTextureRef(const TextureRef& ref, size_t textureCount) {
    TraceTextureRef out;
    if (!ref.valid() || static_cast<size_t>(ref.texture) >= textureCount) return out;
    out.texture = ref.texture;
    out.texCoord = ref.texCoord == 1 ? 1 : 0;
    // KHR_texture_transform: uv' = T · R · S · uv with R = [cos sin; −sin cos].
    const float c = std::cos(ref.transform.rotation), s = std::sin(ref.transform.rotation);
    const vec2 sc = ref.transform.scale;
    out.m[0] = c * sc.x;
    out.m[1] = s * sc.y;
    out.m[2] = ref.transform.offset.x;
    out.m[3] = -s * sc.x;
    out.m[4] = c * sc.y;
    out.m[5] = ref.transform.offset.y;
    return out;
}

TraceMaterial convertMaterial(const Material& m, size_t textureCount) {
    TraceMaterial out;
    if (m.transmission > 0.0f) out.kind = MaterialKind::Dielectric;
    else if (m.metallic >= 1.0f && m.roughness <= 0.0f) out.kind = MaterialKind::Mirror;
    else out.kind = MaterialKind::Lambert;
    out.baseColor = glm::clamp(vec3(m.baseColorFactor), vec3(0.0f), vec3(1.0f));
    out.baseColorTexture = convertTextureRef(m.baseColorTexture, textureCount);
    out.emission = glm::max(m.emission(), vec3(0.0f));
    out.emissiveTexture = convertTextureRef(m.emissiveTexture, textureCount);
    out.ior = m.ior;
    out.transmission = glm::clamp(m.transmission, 0.0f, 1.0f);
    out.doubleSided = m.doubleSided ? 1u : 0u;
    return out;
}

TraceLight convertLight(const Light& light) {
    TraceLight out;
    out.type = light.type == LightType::Point ? TraceLightType::Point
               : light.type == LightType::Spot ? TraceLightType::Spot
                                                : TraceLightType::Directional;
    out.intensity = glm::max(light.radiantIntensity(), vec3(0.0f));
    out.position = light.position;
    out.direction = glm::normalize(light.direction);
    out.range = light.range > 0.0f ? light.range : 0.0f;
    if (light.type == LightType::Directional) out.cosHalfAngle = std::cos(0.5f * light.angularDiameter);
    out.engineDrawn = light.bake == LightBake::Indirect || light.bake == LightBake::Shadowmask ? 1u : 0u;
    out.maskChannel = light.bake == LightBake::Shadowmask ? light.maskChannel : -1;
    if (light.type == LightType::Spot) {
        // glTF KHR_lights_punctual's recommended smooth falloff between the cones.
        const float cosOuter = std::cos(light.outerConeAngle);
        const float cosInner = std::cos(light.innerConeAngle);
        out.spotScale = 1.0f / glm::max(0.001f, cosInner - cosOuter);
        out.spotOffset = -cosOuter * out.spotScale;
    }
    return out;
}

uint32_t wrapCode(WrapMode mode) {
    return mode == WrapMode::ClampToEdge ? 1u : mode == WrapMode::MirroredRepeat ? 2u : 0u;
}

std::string where(const Scene& scene, const Mesh& mesh) {
    return scene.sourcePath + ": mesh '" + mesh.name + "'";
}

// The trees of many lights (light_tree.h). A point light's power is its intensity summed over
// RGB; an emitter patch's, its radiance summed over RGB times its area, its cone the normal
// (every way when two-sided).
void buildLightTrees(TraceScene& out) {
    std::vector<LightBounds> points;
    for (size_t i = 0; i < out.lights.size(); ++i) {
        const TraceLight& light = out.lights[i];
        if (light.type == TraceLightType::Directional) continue;
        LightBounds b;
        b.boundsMin = b.boundsMax = light.position;
        b.power = light.intensity.x + light.intensity.y + light.intensity.z;
        b.item = uint32_t(i);
        points.push_back(b);
    }
    if (points.size() > kLightTreeFrom) out.pointLightTree = buildLightTree(std::move(points));
    if (out.emitters.size() <= kLightTreeFrom) return;
    std::vector<LightBounds> patches;
    for (size_t k = 0; k < out.emitters.size(); ++k) {
        if (out.emitterQuad[k] == kQuadSecondHalf) continue;
        const uint32_t first = out.emitters[k];
        const TraceMaterial& m = out.materials[out.materialIds[first]];
        LightBounds b;
        const vec3* v = &out.vertices[3 * size_t(first)];
        b.boundsMin = glm::min(v[0], glm::min(v[1], v[2]));
        b.boundsMax = glm::max(v[0], glm::max(v[1], v[2]));
        const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
        float area = 0.5f * glm::length(cross);
        if (out.emitterQuad[k] == kQuadFirstHalf) {
            const vec3* w = &out.vertices[3 * size_t(out.emitters[k + 1])];
            b.boundsMin = glm::min(b.boundsMin, glm::min(w[0], glm::min(w[1], w[2])));
            b.boundsMax = glm::max(b.boundsMax, glm::max(w[0], glm::max(w[1], w[2])));
            area += 0.5f * glm::length(glm::cross(w[1] - w[0], w[2] - w[0]));
        }
        b.axis = glm::normalize(cross);
        b.cosSpread = m.doubleSided ? -1.0f : 1.0f;
        // A textured emitter's power by its factor: the tree only weighs, the leaf is exact.
        b.power = area * (m.emission.x + m.emission.y + m.emission.z);
        b.item = uint32_t(k);
        patches.push_back(b);
    }
    out.emitterTree = buildLightTree(std::move(patches));
}

}  // namespace

TraceScene TraceScene::build(const Scene& scene, const SceneTriangles& triangles, bool lightTrees) {
    TraceScene out;
    const size_t triangleCount = triangles.meshIndex.size();

    // Materials: the scene's, then the glTF default material for meshes without one.
    for (const Material& m : scene.materials) out.materials.push_back(convertMaterial(m, scene.textures.size()));
    const uint32_t defaultMaterial = static_cast<uint32_t>(out.materials.size());
    out.materials.push_back(convertMaterial(Material{}, scene.textures.size()));
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        if (!(m.ior > 0.0f) || !std::isfinite(m.ior))
            throw InputError(scene.sourcePath + ": material '" + m.name + "': index of refraction " +
                             std::to_string(m.ior) + " is not a positive number");
        if (!isFinite(m.emission()) || !isFinite(vec3(m.baseColorFactor)))
            throw InputError(scene.sourcePath + ": material '" + m.name + "': colour or emission is not finite");
    }

    bool needUv[2] = {false, false};
    for (const TraceMaterial& m : out.materials)
        for (const TraceTextureRef* ref : {&m.baseColorTexture, &m.emissiveTexture})
            if (ref->texture >= 0) needUv[ref->texCoord] = true;
    bool needColors = false;
    for (const Mesh& mesh : scene.meshes) needColors = needColors || !mesh.colors.empty();

    out.vertices = triangles.vertices;
    out.normals.resize(3 * triangleCount);
    out.materialIds.resize(triangleCount);
    if (needUv[0]) out.uv0.assign(3 * triangleCount, vec2(0.0f));
    if (needUv[1]) out.uv1.assign(3 * triangleCount, vec2(0.0f));
    if (needColors) out.colors.assign(3 * triangleCount, vec4(1.0f));

    for (size_t t = 0; t < triangleCount; ++t) {
        const Mesh& mesh = scene.meshes[triangles.meshIndex[t]];
        const size_t local = triangles.localIndex[t];
        out.materialIds[t] = mesh.material >= 0 ? static_cast<uint32_t>(mesh.material) : defaultMaterial;
        const vec3* v = &out.vertices[3 * t];
        const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
        if (!isFinite(v[0]) || !isFinite(v[1]) || !isFinite(v[2]) || !isFinite(cross))
            throw InputError(where(scene, mesh) + ": triangle " + std::to_string(local) +
                             " has a position that is not finite (or too large to square)");
        const float crossLength = glm::length(cross);
        const vec3 flat = crossLength > 0.0f ? cross / crossLength : vec3(0.0f, 0.0f, 1.0f);
        for (int k = 0; k < 3; ++k) {
            const uint32_t index = mesh.indices[3 * local + k];
            vec3 n = index < mesh.normals.size() ? mesh.normals[index] : flat;
            const float length = glm::length(n);
            if (!isFinite(n) || !(length > 0.0f))
                throw InputError(where(scene, mesh) + ": normal of vertex " + std::to_string(index) +
                                 " is zero or not finite");
            out.normals[3 * t + k] = n / length;
            if (needUv[0] && index < mesh.uv0.size()) out.uv0[3 * t + k] = mesh.uv0[index];
            if (needUv[1] && index < mesh.uv1.size()) out.uv1[3 * t + k] = mesh.uv1[index];
            if (needColors && index < mesh.colors.size()) out.colors[3 * t + k] = mesh.colors[index];
        }
    }

    // Textures: RGBA floats one after another.
    for (const Texture& texture : scene.textures) {
        TraceTexture t;
        t.offset = out.texels.size();
        const Image& image = texture.image;
        t.width = image.width;
        t.height = image.height;
        t.wrapS = wrapCode(texture.wrapS);
        t.wrapT = wrapCode(texture.wrapT);
        t.nearest = texture.nearest ? 1u : 0u;
        if (image.width <= 0 || image.height <= 0 || image.channels <= 0) {
            // An unreadable image: one white texel, so the factor alone shades.
            t.width = t.height = 1;
            out.texels.insert(out.texels.end(), {1.0f, 1.0f, 1.0f, 1.0f});
        } else {
            for (int y = 0; y < image.height; ++y)
                for (int x = 0; x < image.width; ++x) {
                    vec4 c(0.0f, 0.0f, 0.0f, 1.0f);
                    for (int ch = 0; ch < glm::min(image.channels, 4); ++ch) c[ch] = image.at(x, y, ch);
                    if (image.channels < 3) c = vec4(c.x, c.x, c.x, image.channels == 2 ? c.y : 1.0f);
                    for (int ch = 0; ch < 4; ++ch) out.texels.push_back(std::isfinite(c[ch]) ? c[ch] : 0.0f);
                }
        }
        out.textures.push_back(t);
    }

    for (const Light& light : scene.lights) {
        if (!isFinite(light.radiantIntensity()) || !isFinite(light.position) || !isFinite(light.direction))
            throw InputError(scene.sourcePath + ": light '" + light.name + "' has a value that is not finite");
        if (!(light.angularDiameter >= 0.0f && light.angularDiameter <= 0.5f * kPi))
            throw InputError(scene.sourcePath + ": light '" + light.name + "' has an angular diameter outside 0..90°");
        out.lights.push_back(convertLight(light));
    }

    if (!isFinite(scene.sky.radiance) || glm::min(scene.sky.radiance.x, glm::min(scene.sky.radiance.y, scene.sky.radiance.z)) < 0.0f)
        throw InputError(scene.sourcePath + ": the sky's radiance is negative or not finite");
    out.skyUniform = scene.sky.radiance;
    if (scene.sky.image && scene.sky.intensity > 0.0f) {
        if (!(std::isfinite(scene.sky.intensity) && std::isfinite(scene.sky.rotationDegrees)))
            throw InputError(scene.sourcePath + ": the sky's intensity or rotation is not finite");
        const SkyImage& image = *scene.sky.image;
        if (image.width < 1 || image.height < 1 || image.texels.size() != size_t(image.width) * size_t(image.height))
            throw Error(image.path + ": the sky image holds " + std::to_string(image.texels.size()) + " texels for " +
                        std::to_string(image.width) + " x " + std::to_string(image.height));
        out.skyImage = scene.sky.image;
        out.skyIntensity = scene.sky.intensity;
        const double turn = glm::radians(double(scene.sky.rotationDegrees)), c = std::cos(turn), s = std::sin(turn);
        const glm::dmat3 worldToImage(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c);  // R_y(−θ), columns
        out.skyToImage = glm::mat3(worldToImage * scene.frame);
        // Pixels in proportion to luminance × sin θ (their solid angle), summed in double. A
        // pixel's luminance is the most the bilinear lookup shows anywhere inside it: at its
        // centre, its edges' middles or its corners, where it blends its neighbours. Drawn by
        // its own value, a pixel next to the sun was drawn as seldom as the sky around it
        // while it shows up to half the sun, and a receiver's cosine rays that hit it came out
        // far too high (docs/decisions.md, "Sky sampling").
        const size_t w = size_t(image.width), h = size_t(image.height);
        std::vector<float> lum(w * h);
        for (size_t k = 0; k < w * h; ++k) lum[k] = glm::max(0.0f, luminance(image.texels[k]));
        const auto at = [&](long x, long y) { return lum[size_t(glm::clamp(y, 0l, long(h) - 1)) * w + size_t((x + long(w)) % long(w))]; };
        const auto brightest = [&](size_t px, size_t py) {
            const long x = long(px), y = long(py);
            const float own = at(x, y);
            float m = own;
            for (int d : {-1, 1}) m = glm::max(m, glm::max(0.5f * (own + at(x + d, y)), 0.5f * (own + at(x, y + d))));
            for (int dy : {-1, 1})
                for (int dx : {-1, 1})
                    m = glm::max(m, 0.25f * (own + at(x + dx, y) + at(x, y + dy) + at(x + dx, y + dy)));
            return m;
        };
        std::vector<double> rowSums(h, 0.0);
        std::vector<float> columnCdf(w * h, 0.0f);
        for (size_t y = 0; y < h; ++y) {
            const double sinTheta = std::sin(kPi * (double(y) + 0.5) / double(h));
            double sum = 0.0;
            std::vector<double> running(w);
            for (size_t x = 0; x < w; ++x) {
                sum += double(brightest(x, y)) * sinTheta;
                running[x] = sum;
            }
            rowSums[y] = sum;
            for (size_t x = 0; x < w; ++x) columnCdf[y * w + x] = sum > 0.0 ? float(running[x] / sum) : float(x + 1) / float(w);
            columnCdf[y * w + w - 1] = 1.0f;
        }
        double total = 0.0;
        for (double r : rowSums) total += r;
        if (total > 0.0) {
            out.skyRowCdf.resize(h);
            double running = 0.0;
            for (size_t y = 0; y < h; ++y) {
                running += rowSums[y];
                out.skyRowCdf[y] = float(running / total);
            }
            out.skyRowCdf[h - 1] = 1.0f;
            out.skyColumnCdf = std::move(columnCdf);
        }
    }

    // Emissive triangles, picked in proportion to area × mean emission (their power up to
    // the emissive texture).
    std::vector<double> weights;
    for (size_t t = 0; t < triangleCount; ++t) {
        const TraceMaterial& m = out.materials[out.materialIds[t]];
        if (!(maxComponent(m.emission) > 0.0f)) continue;
        const vec3* v = &out.vertices[3 * t];
        const double area = 0.5 * glm::length(glm::cross(v[1] - v[0], v[2] - v[0]));
        if (!(area > 0.0)) continue;
        out.emitters.push_back(static_cast<uint32_t>(t));
        weights.push_back(area * (m.emission.x + m.emission.y + m.emission.z) * (m.doubleSided ? 2.0 : 1.0));
    }
    // Parallelogram quads: emitters k and k + 1 of one uniform material sharing an edge, the
    // two corners they do not share summing to the two they do.
    out.emitterQuad.assign(out.emitters.size(), kQuadSingle);
    for (size_t k = 0; k + 1 < out.emitters.size(); ++k) {
        if (out.emitterQuad[k] != kQuadSingle) continue;
        const uint32_t a = out.emitters[k], b = out.emitters[k + 1];
        const TraceMaterial& m = out.materials[out.materialIds[a]];
        if (out.materialIds[b] != out.materialIds[a] || m.emissiveTexture.texture >= 0) continue;
        const vec3* va = &out.vertices[3 * size_t(a)];
        const vec3* vb = &out.vertices[3 * size_t(b)];
        const SharedEdge e = sharedEdge(va, vb);
        if (e.shared != 2) continue;
        const vec3 sharedSum = va[(e.ownA + 1) % 3] + va[(e.ownA + 2) % 3];
        const float size = glm::length(va[1] - va[0]) + glm::length(va[2] - va[0]);
        const vec3 na = glm::normalize(glm::cross(va[1] - va[0], va[2] - va[0]));
        const vec3 nb = glm::normalize(glm::cross(vb[1] - vb[0], vb[2] - vb[0]));
        if (glm::dot(na, nb) > 0.9999f && glm::length(va[e.ownA] + vb[e.ownB] - sharedSum) < 1e-5f * size) {
            out.emitterQuad[k] = kQuadFirstHalf;
            out.emitterQuad[k + 1] = kQuadSecondHalf;
        }
    }
    if (!out.emitters.empty()) {
        double total = 0.0;
        for (double w : weights) total += w;
        out.emitterCdf.resize(out.emitters.size());
        out.emitterSelectPdf.assign(triangleCount, 0.0f);
        double running = 0.0;
        float previous = 0.0f;
        for (size_t i = 0; i < out.emitters.size(); ++i) {
            running += weights[i];
            const float cdf = i + 1 == out.emitters.size() ? 1.0f : static_cast<float>(running / total);
            out.emitterCdf[i] = cdf;
            // The probability pickEmitter really gives this triangle (float interval width),
            // so light sampling and its MIS weights agree exactly.
            out.emitterSelectPdf[out.emitters[i]] = cdf - previous;
            previous = cdf;
        }
    }
    if (lightTrees) buildLightTrees(out);
    return out;
}

TraceSceneView TraceScene::view() const {
    TraceSceneView v;
    v.vertices = vertices.data();
    v.normals = normals.data();
    v.uv0 = uv0.empty() ? nullptr : uv0.data();
    v.uv1 = uv1.empty() ? nullptr : uv1.data();
    v.colors = colors.empty() ? nullptr : colors.data();
    v.materialIds = materialIds.data();
    v.triangleCount = static_cast<uint32_t>(materialIds.size());
    v.materials = materials.data();
    v.materialCount = static_cast<uint32_t>(materials.size());
    v.textures = textures.empty() ? nullptr : textures.data();
    v.texels = texels.empty() ? nullptr : texels.data();
    v.textureCount = static_cast<uint32_t>(textures.size());
    v.lights = lights.empty() ? nullptr : lights.data();
    v.lightCount = static_cast<uint32_t>(lights.size());
    v.emitters = emitters.empty() ? nullptr : emitters.data();
    v.emitterCdf = emitterCdf.empty() ? nullptr : emitterCdf.data();
    v.emitterSelectPdf = emitterSelectPdf.empty() ? nullptr : emitterSelectPdf.data();
    v.emitterQuad = emitterQuad.empty() ? nullptr : emitterQuad.data();
    v.emitterCount = static_cast<uint32_t>(emitters.size());
    v.pointLightTree = {pointLightTree.empty() ? nullptr : pointLightTree.data(), uint32_t(pointLightTree.size())};
    v.emitterTree = {emitterTree.empty() ? nullptr : emitterTree.data(), uint32_t(emitterTree.size())};
    v.sky.uniform = skyUniform;
    if (skyImage) {
        v.sky.texels = skyImage->texels.data();
        v.sky.width = skyImage->width;
        v.sky.height = skyImage->height;
        v.sky.intensity = skyIntensity;
        for (int r = 0; r < 3; ++r) v.sky.toImageRows[r] = glm::row(skyToImage, r);
        v.sky.rowCdf = skyRowCdf.empty() ? nullptr : skyRowCdf.data();
        v.sky.columnCdf = skyColumnCdf.empty() ? nullptr : skyColumnCdf.data();
    }
    for (const TraceLight& light : lights) v.sunDisks += light.cosHalfAngle < 1.0f ? 1 : 0;
    return v;
}

size_t TraceScene::memoryBytes() const {
    return vertices.size() * sizeof(vec3) + normals.size() * sizeof(vec3) + uv0.size() * sizeof(vec2) +
           uv1.size() * sizeof(vec2) + colors.size() * sizeof(vec4) + materialIds.size() * sizeof(uint32_t) +
           materials.size() * sizeof(TraceMaterial) + textures.size() * sizeof(TraceTexture) +
           texels.size() * sizeof(float) + lights.size() * sizeof(TraceLight) + emitters.size() * sizeof(uint32_t) +
           emitterCdf.size() * sizeof(float) + emitterSelectPdf.size() * sizeof(float) + emitterQuad.size() +
           (pointLightTree.size() + emitterTree.size()) * sizeof(LightTreeNode) +
           (skyImage ? skyImage->texels.size() * sizeof(vec3) : 0) + (skyRowCdf.size() + skyColumnCdf.size()) * sizeof(float);
}

}  // namespace vl
