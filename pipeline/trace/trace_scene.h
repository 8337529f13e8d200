// The Scene flattened for VL_HOSTDEV kernels: per-triangle vertices, shading normals, UVs,
// colours and material ids in the global triangle order of gatherTriangles (so a BVH hit's
// triangle id indexes them), a POD material table, textures as one float array, punctual
// lights, and the emissive triangles with a CDF for sampling them by power. TraceScene owns
// the arrays; TraceSceneView is plain pointers, what the CPU and CUDA kernels read (the CUDA
// issue copies each array to the device and fills a view with device pointers).
#pragma once

#include "core/math.h"
#include "trace/light_tree.h"
#include "trace/materials.h"
#include "trace/sky.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace vl {

struct Scene;
struct SkyImage;
struct SceneTriangles;

// RGBA float texels, row-major from the top row, starting at TraceSceneView::texels + offset.
struct TraceTexture {
    uint64_t offset = 0;
    int32_t width = 0;
    int32_t height = 0;
    uint32_t wrapS = 0;  // WrapMode as an integer: 0 repeat, 1 clamp, 2 mirrored repeat
    uint32_t wrapT = 0;
    uint32_t nearest = 0;
};

// A texture reference with KHR_texture_transform folded into uv' = (a·u + b·v + c, d·u + e·v + f).
struct TraceTextureRef {
    int32_t texture = -1;
    int32_t texCoord = 0;
    float m[6] = {1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f};
};

struct TraceMaterial {
    MaterialKind kind = MaterialKind::Lambert;
    vec3 baseColor{1.0f};
    TraceTextureRef baseColorTexture;
    vec3 emission{0.0f};  // radiance W/(m²·sr): emissiveFactor × strength
    TraceTextureRef emissiveTexture;
    float ior = 1.5f;
    float transmission = 0.0f;
    uint32_t doubleSided = 0;  // single-sided emitters emit from their front (counter-clockwise) face only
};

enum class TraceLightType : uint32_t { Point = 0, Spot = 1, Directional = 2 };

struct TraceLight {
    TraceLightType type = TraceLightType::Point;
    vec3 intensity{0.0f};      // colour × intensity: W/sr (point, spot), W/m² (directional)
    vec3 position{0.0f};
    vec3 direction{0.0f, 0.0f, -1.0f};  // unit, the direction light travels
    float range = 0.0f;        // 0 = infinite
    float spotScale = 0.0f;    // glTF smooth spot falloff: t = clamp(cos·scale + offset, 0, 1), factor t²
    float spotOffset = 1.0f;
    float cosHalfAngle = 1.0f;  // directional: its disk's half-angle (scene.h angularDiameter); 1 = a point
    uint32_t engineDrawn = 0;   // 1: the engine draws its direct light (LightBake::Indirect, Shadowmask); lightmaps leave it out
    int32_t maskChannel = -1;   // LightBake::Shadowmask: its channel of the shadowmask (Light::maskChannel)
};

struct TraceSceneView {
    const vec3* vertices = nullptr;      // 3 per triangle, world space
    const vec3* normals = nullptr;       // 3 per triangle, unit shading normals
    const vec2* uv0 = nullptr;           // 3 per triangle; null when no material samples a texture
    const vec2* uv1 = nullptr;           // 3 per triangle; null when no texture reads TEXCOORD_1
    const vec4* colors = nullptr;        // 3 per triangle; null when no mesh has COLOR_0
    const uint32_t* materialIds = nullptr;  // per triangle, into materials
    uint32_t triangleCount = 0;

    const TraceMaterial* materials = nullptr;
    uint32_t materialCount = 0;
    const TraceTexture* textures = nullptr;
    const float* texels = nullptr;
    uint32_t textureCount = 0;

    const TraceLight* lights = nullptr;
    uint32_t lightCount = 0;

    const uint32_t* emitters = nullptr;       // emissive triangle ids
    const float* emitterCdf = nullptr;        // per emitter, inclusive; the last is exactly 1
    const float* emitterSelectPdf = nullptr;  // per triangle: probability that light sampling picks it
    // Per emitter: kQuadSingle, kQuadSecondHalf, or (for the first half of a parallelogram
    // quad of one uniform emitter, the next emitter its other half) kQuadFirstHalf. The
    // receivers' direct term samples such a quad as one square grid (direct_light.h).
    const int8_t* emitterQuad = nullptr;
    uint32_t emitterCount = 0;

    // Past kLightTreeFrom: the point and spot lights (items: indices into lights), and the
    // emitters' patches (items: the emitter of a single triangle or of a quad's first half).
    // A directional light is never in a tree. Null nodes: every receiver visits each.
    LightTreeView pointLightTree;
    LightTreeView emitterTree;

    SkyView sky;  // Scene::sky: what a ray that leaves the scene sees
    // Some directional light has a disk (TraceLight::cosHalfAngle < 1): only then do paths
    // draw a point of it, so scenes without one keep their random sequences.
    int sunDisks = 0;
};

constexpr int8_t kQuadSingle = 0, kQuadFirstHalf = 1, kQuadSecondHalf = 2;

class TraceScene {
public:
    // Throws InputError naming the file, mesh and element for geometry that would produce NaN.
    // lightTrees false: no trees of many lights, every receiver visits every light.
    static TraceScene build(const Scene& scene, const SceneTriangles& triangles, bool lightTrees = true);

    TraceSceneView view() const;
    size_t memoryBytes() const;

    std::vector<vec3> vertices;
    std::vector<vec3> normals;
    std::vector<vec2> uv0;
    std::vector<vec2> uv1;
    std::vector<vec4> colors;
    std::vector<uint32_t> materialIds;
    std::vector<TraceMaterial> materials;
    std::vector<TraceTexture> textures;
    std::vector<float> texels;
    std::vector<TraceLight> lights;
    std::vector<uint32_t> emitters;
    std::vector<float> emitterCdf;
    std::vector<float> emitterSelectPdf;
    std::vector<int8_t> emitterQuad;
    std::vector<LightTreeNode> pointLightTree;
    std::vector<LightTreeNode> emitterTree;
    // Scene::sky: its uniform part, image (sky.h) and the image's sampling tables.
    vec3 skyUniform{0.0f};
    std::shared_ptr<const SkyImage> skyImage;
    float skyIntensity = 1.0f;
    glm::mat3 skyToImage{1.0f};  // local direction → the image's frame (SkyView::toImageRows)
    std::vector<float> skyRowCdf, skyColumnCdf;
};

// ---- Surface queries (VL_HOSTDEV) ------------------------------------------------------

struct SurfaceHit {
    vec3 position;
    vec3 geometricNormal;  // unit, from the winding (counter-clockwise = front)
    vec3 shadingNormal;    // unit, interpolated
    vec2 uv[2];
    vec4 color;
    uint32_t triangle;
    uint32_t material;
};

// The cross product of a triangle's edges: its winding normal (counter-clockwise = front),
// twice its area long.
VL_HOSTDEV inline vec3 windingCross(const TraceSceneView& s, uint32_t triangle) {
    const vec3* v = s.vertices + 3 * static_cast<size_t>(triangle);
    return glm::cross(v[1] - v[0], v[2] - v[0]);
}

VL_HOSTDEV inline float triangleArea(const TraceSceneView& s, uint32_t triangle) {
    return 0.5f * glm::length(windingCross(s, triangle));
}

VL_HOSTDEV inline SurfaceHit surfaceAt(const TraceSceneView& s, uint32_t triangle, float b1, float b2) {
    const size_t base = 3 * static_cast<size_t>(triangle);
    const float b0 = 1.0f - b1 - b2;
    const vec3* v = s.vertices + base;
    SurfaceHit h;
    h.triangle = triangle;
    h.material = s.materialIds[triangle];
    h.position = b0 * v[0] + b1 * v[1] + b2 * v[2];
    const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
    const float crossLength = glm::length(cross);
    h.geometricNormal = crossLength > 0.0f ? cross / crossLength : vec3(0.0f, 0.0f, 1.0f);
    const vec3* n = s.normals + base;
    const vec3 ns = b0 * n[0] + b1 * n[1] + b2 * n[2];
    const float nsLength = glm::length(ns);
    h.shadingNormal = nsLength > 1e-12f && isFinite(nsLength) ? ns / nsLength : h.geometricNormal;
    h.uv[0] = s.uv0 ? b0 * s.uv0[base] + b1 * s.uv0[base + 1] + b2 * s.uv0[base + 2] : vec2(0.0f);
    h.uv[1] = s.uv1 ? b0 * s.uv1[base] + b1 * s.uv1[base + 1] + b2 * s.uv1[base + 2] : vec2(0.0f);
    h.color = s.colors ? b0 * s.colors[base] + b1 * s.colors[base + 1] + b2 * s.colors[base + 2] : vec4(1.0f);
    return h;
}

VL_HOSTDEV inline int wrapTexel(int i, int size, uint32_t mode) {
    if (mode == 1) return glm::clamp(i, 0, size - 1);
    if (mode == 2) {
        const int period = 2 * size;
        int m = i % period;
        if (m < 0) m += period;
        return m < size ? m : period - 1 - m;
    }
    int m = i % size;
    return m < 0 ? m + size : m;
}

VL_HOSTDEV inline float reduceTexelCoordinate(float f, int size, uint32_t mode) {
    const float period = 2.0f * static_cast<float>(size);
    if (mode == 1) return glm::clamp(f, -1.0f, static_cast<float>(size));
    return f - period * glm::floor(f / period);
}

VL_HOSTDEV inline vec4 fetchTexel(const TraceSceneView& s, const TraceTexture& t, int x, int y) {
    const float* p = s.texels + t.offset + 4 * (static_cast<size_t>(wrapTexel(y, t.height, t.wrapT)) * t.width +
                                                static_cast<size_t>(wrapTexel(x, t.width, t.wrapS)));
    return vec4(p[0], p[1], p[2], p[3]);
}

// glTF texture lookup: uv (0, 0) is the top-left corner of the image; bilinear between
// texel centres unless the texture asks for nearest.
VL_HOSTDEV inline vec4 sampleTraceTexture(const TraceSceneView& s, const TraceTextureRef& ref, const vec2 uv[2]) {
    const TraceTexture& t = s.textures[ref.texture];
    const vec2 in = uv[ref.texCoord == 1 ? 1 : 0];
    const float u = ref.m[0] * in.x + ref.m[1] * in.y + ref.m[2];
    const float v = ref.m[3] * in.x + ref.m[4] * in.y + ref.m[5];
    if (!isFinite(u) || !isFinite(v)) return vec4(0.0f);
    // Bring far coordinates near the image first so the float → int conversion stays exact:
    // shift by whole periods of 2·size (a period of both repeat and mirrored repeat), or
    // clamp just outside the image for clamp-to-edge.
    const float px = reduceTexelCoordinate(u * static_cast<float>(t.width) - 0.5f, t.width, t.wrapS);
    const float py = reduceTexelCoordinate(v * static_cast<float>(t.height) - 0.5f, t.height, t.wrapT);
    if (t.nearest) return fetchTexel(s, t, static_cast<int>(glm::floor(px + 0.5f)), static_cast<int>(glm::floor(py + 0.5f)));
    const int x0 = static_cast<int>(glm::floor(px));
    const int y0 = static_cast<int>(glm::floor(py));
    const float ax = px - static_cast<float>(x0);
    const float ay = py - static_cast<float>(y0);
    const vec4 top = glm::mix(fetchTexel(s, t, x0, y0), fetchTexel(s, t, x0 + 1, y0), ax);
    const vec4 bottom = glm::mix(fetchTexel(s, t, x0, y0 + 1), fetchTexel(s, t, x0 + 1, y0 + 1), ax);
    return glm::mix(top, bottom, ay);
}

VL_HOSTDEV inline vec3 baseColorAt(const TraceSceneView& s, const SurfaceHit& h) {
    const TraceMaterial& m = s.materials[h.material];
    vec3 c = m.baseColor * vec3(h.color);
    if (m.baseColorTexture.texture >= 0) c *= vec3(sampleTraceTexture(s, m.baseColorTexture, h.uv));
    return glm::clamp(c, vec3(0.0f), vec3(1.0f));
}

// Emitted radiance toward a direction w (unit, away from the surface).
VL_HOSTDEV inline vec3 emissionAt(const TraceSceneView& s, const SurfaceHit& h, const vec3& w) {
    const TraceMaterial& m = s.materials[h.material];
    if (!(maxComponent(m.emission) > 0.0f)) return vec3(0.0f);
    if (!m.doubleSided && glm::dot(w, h.geometricNormal) <= 0.0f) return vec3(0.0f);
    vec3 e = m.emission;
    if (m.emissiveTexture.texture >= 0) e *= vec3(sampleTraceTexture(s, m.emissiveTexture, h.uv));
    return glm::max(e, vec3(0.0f));
}

VL_HOSTDEV inline ShadingMaterial shadingMaterialAt(const TraceSceneView& s, const SurfaceHit& h) {
    const TraceMaterial& m = s.materials[h.material];
    ShadingMaterial sm;
    sm.kind = m.kind;
    sm.baseColor = baseColorAt(s, h);
    sm.ior = m.ior;
    sm.transmission = m.transmission;
    return sm;
}

// Index of the emitter for uniform u in [0, 1): the first CDF entry above u.
VL_HOSTDEV inline uint32_t pickEmitter(const TraceSceneView& s, float u) {
    uint32_t lo = 0, hi = s.emitterCount - 1;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (u < s.emitterCdf[mid]) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

}  // namespace vl
