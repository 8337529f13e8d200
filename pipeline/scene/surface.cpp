#include "scene/surface.h"

#include <algorithm>
#include <cmath>

namespace vl {
namespace {

// Reduces a coordinate to a bounded range first, so huge uvs never overflow the int texel
// index; the wrap of the final index then handles the bilinear neighbours.
float reduce(float u, WrapMode mode) {
    if (!std::isfinite(u)) return 0.0f;
    switch (mode) {
    case WrapMode::Repeat: return u - std::floor(u);
    case WrapMode::MirroredRepeat: return u - 2.0f * std::floor(0.5f * u);
    default: return std::clamp(u, -1.0f, 2.0f);
    }
}

int wrapIndex(int i, int size, WrapMode mode) {
    switch (mode) {
    case WrapMode::Repeat: return ((i % size) + size) % size;
    case WrapMode::MirroredRepeat: {
        const int period = 2 * size;
        const int m = ((i % period) + period) % period;
        return m < size ? m : period - 1 - m;
    }
    default: return std::clamp(i, 0, size - 1);
    }
}

vec4 texel(const Image& image, int x, int y) {
    const float* p = &image.pixels[image.index(x, y)];
    switch (image.channels) {
    case 1: return vec4(p[0], p[0], p[0], 1.0f);
    case 2: return vec4(p[0], p[0], p[0], p[1]);
    case 3: return vec4(p[0], p[1], p[2], 1.0f);
    default: return vec4(p[0], p[1], p[2], p[3]);
    }
}

template <class T>
T interpolate(const std::vector<T>& values, const Mesh& mesh, size_t triangle, vec2 b) {
    const uint32_t* v = &mesh.indices[3 * triangle];
    return (1.0f - b.x - b.y) * values[v[0]] + b.x * values[v[1]] + b.y * values[v[2]];
}

}  // namespace

vec4 sampleTexture(const Texture& texture, vec2 uv) {
    const Image& image = texture.image;
    if (image.empty() || image.width <= 0 || image.height <= 0 || image.channels <= 0) return vec4(1.0f);
    const float u = reduce(uv.x, texture.wrapS) * static_cast<float>(image.width);
    const float v = reduce(uv.y, texture.wrapT) * static_cast<float>(image.height);
    if (texture.nearest) {
        const int x = wrapIndex(static_cast<int>(std::floor(u)), image.width, texture.wrapS);
        const int y = wrapIndex(static_cast<int>(std::floor(v)), image.height, texture.wrapT);
        return texel(image, x, y);
    }
    const float fx = u - 0.5f, fy = v - 0.5f;
    const float x0f = std::floor(fx), y0f = std::floor(fy);
    const float tx = fx - x0f, ty = fy - y0f;
    const int x0 = static_cast<int>(x0f), y0 = static_cast<int>(y0f);
    const int xa = wrapIndex(x0, image.width, texture.wrapS), xb = wrapIndex(x0 + 1, image.width, texture.wrapS);
    const int ya = wrapIndex(y0, image.height, texture.wrapT), yb = wrapIndex(y0 + 1, image.height, texture.wrapT);
    const vec4 top = glm::mix(texel(image, xa, ya), texel(image, xb, ya), tx);
    const vec4 bottom = glm::mix(texel(image, xa, yb), texel(image, xb, yb), tx);
    return glm::mix(top, bottom, ty);
}

vec2 transformUv(const TextureTransform& t, vec2 uv) {
    const float c = std::cos(t.rotation), s = std::sin(t.rotation);
    const vec2 scaled = uv * t.scale;
    return vec2(c * scaled.x + s * scaled.y, -s * scaled.x + c * scaled.y) + t.offset;
}

SurfacePoint interpolateSurface(const Mesh& mesh, size_t triangle, vec2 barycentric) {
    SurfacePoint point;
    point.position = interpolate(mesh.positions, mesh, triangle, barycentric);
    vec3 n = mesh.normals.empty() ? vec3(0.0f) : interpolate(mesh.normals, mesh, triangle, barycentric);
    float length = glm::length(n);
    if (!(length > 0.0f) || !std::isfinite(length)) {  // opposite vertex normals cancel: use the face's
        const uint32_t* v = &mesh.indices[3 * triangle];
        n = glm::cross(mesh.positions[v[1]] - mesh.positions[v[0]], mesh.positions[v[2]] - mesh.positions[v[0]]);
        length = glm::length(n);
    }
    point.normal = length > 0.0f && std::isfinite(length) ? n / length : vec3(0.0f, 1.0f, 0.0f);
    point.uv0 = mesh.uv0.empty() ? vec2(0.0f) : interpolate(mesh.uv0, mesh, triangle, barycentric);
    point.uv1 = mesh.uv1.empty() ? vec2(0.0f) : interpolate(mesh.uv1, mesh, triangle, barycentric);
    return point;
}

vec4 sampleTextureRef(const Scene& scene, const TextureRef& ref, const Mesh& mesh, size_t triangle,
                      vec2 barycentric) {
    if (!ref.valid() || static_cast<size_t>(ref.texture) >= scene.textures.size()) return vec4(1.0f);
    const std::vector<vec2>& uvs = ref.texCoord == 1 ? mesh.uv1 : mesh.uv0;
    const vec2 uv = uvs.empty() ? vec2(0.0f) : interpolate(uvs, mesh, triangle, barycentric);
    return sampleTexture(scene.textures[static_cast<size_t>(ref.texture)], transformUv(ref.transform, uv));
}

vec4 baseColorAt(const Scene& scene, const Mesh& mesh, size_t triangle, vec2 barycentric) {
    const Material& material = scene.materialOf(mesh);
    vec4 color = material.baseColorFactor * sampleTextureRef(scene, material.baseColorTexture, mesh, triangle,
                                                              barycentric);
    if (!mesh.colors.empty()) color *= interpolate(mesh.colors, mesh, triangle, barycentric);
    return color;
}

vec3 emissionAt(const Scene& scene, const Mesh& mesh, size_t triangle, vec2 barycentric) {
    const Material& material = scene.materialOf(mesh);
    if (!material.emissive()) return vec3(0.0f);
    return material.emission() *
           vec3(sampleTextureRef(scene, material.emissiveTexture, mesh, triangle, barycentric));
}

}  // namespace vl
