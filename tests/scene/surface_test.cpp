// Texture lookup and surface interpolation against values worked out by hand.
#include "scene_checks.h"

#include "scene/surface.h"

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

// 2×1 texture: left texel (0, 0.2, 1, 1), right texel (1, 0.6, 0, 0.5).
Texture twoTexels(WrapMode wrap, bool nearest = false) {
    Texture t;
    t.image = Image(2, 1, 4);
    const float values[8] = {0, 0.2f, 1, 1, 1, 0.6f, 0, 0.5f};
    std::copy(values, values + 8, t.image.pixels.begin());
    t.wrapS = t.wrapT = wrap;
    t.nearest = nearest;
    return t;
}

const vec4 kLeft(0, 0.2f, 1, 1);
const vec4 kRight(1, 0.6f, 0, 0.5f);

}  // namespace

TEST_CASE("Bilinear lookup interpolates between texel centres", "[scene]") {
    const Texture t = twoTexels(WrapMode::ClampToEdge);
    CHECK_NEAR(sampleTexture(t, vec2(0.25f, 0.5f)), kLeft);
    CHECK_NEAR(sampleTexture(t, vec2(0.75f, 0.5f)), kRight);
    CHECK_NEAR(sampleTexture(t, vec2(0.5f, 0.5f)), 0.5f * (kLeft + kRight));
    CHECK_NEAR(sampleTexture(t, vec2(0.375f, 0.5f)), 0.75f * kLeft + 0.25f * kRight);
    // Clamped: beyond the last centre the edge texel holds.
    CHECK_NEAR(sampleTexture(t, vec2(0.0f, 0.5f)), kLeft);
    CHECK_NEAR(sampleTexture(t, vec2(7.0f, -3.0f)), kRight);
}

TEST_CASE("Repeat and mirrored repeat wrap as the glTF sampler says", "[scene]") {
    const Texture repeat = twoTexels(WrapMode::Repeat);
    // u = 0 sits halfway between the right texel (wrapped) and the left one.
    CHECK_NEAR(sampleTexture(repeat, vec2(0.0f, 0.5f)), 0.5f * (kLeft + kRight));
    CHECK_NEAR(sampleTexture(repeat, vec2(3.25f, 0.5f)), kLeft);
    CHECK_NEAR(sampleTexture(repeat, vec2(-0.25f, 0.5f)), kRight);

    const Texture mirrored = twoTexels(WrapMode::MirroredRepeat);
    // [1, 2) is the mirror image: u = 1.25 reads the right texel, 1.75 the left one.
    CHECK_NEAR(sampleTexture(mirrored, vec2(1.25f, 0.5f)), kRight);
    CHECK_NEAR(sampleTexture(mirrored, vec2(1.75f, 0.5f)), kLeft);
    // At u = 0 and u = 1 the mirror meets itself: the edge texel, not a blend.
    CHECK_NEAR(sampleTexture(mirrored, vec2(0.0f, 0.5f)), kLeft);
    CHECK_NEAR(sampleTexture(mirrored, vec2(1.0f, 0.5f)), kRight);
}

TEST_CASE("Nearest lookup picks the texel containing uv", "[scene]") {
    const Texture t = twoTexels(WrapMode::Repeat, /*nearest=*/true);
    CHECK_NEAR(sampleTexture(t, vec2(0.49f, 0.5f)), kLeft);
    CHECK_NEAR(sampleTexture(t, vec2(0.51f, 0.5f)), kRight);
    CHECK_NEAR(sampleTexture(t, vec2(1.01f, 0.5f)), kLeft);
}

TEST_CASE("Huge and non-finite uvs stay finite", "[scene]") {
    const Texture t = twoTexels(WrapMode::Repeat);
    for (const float u : {1e30f, -1e30f, NAN, INFINITY}) {
        const vec4 v = sampleTexture(t, vec2(u, u));
        CHECK(isFinite(vec3(v)));
        CHECK(std::isfinite(v.w));
    }
    CHECK_NEAR(sampleTexture(Texture{}, vec2(0.3f)), vec4(1.0f));
}

TEST_CASE("KHR_texture_transform follows the extension's worked example", "[scene]") {
    // The extension's example (offset (0, 1), rotation π/2, scale 0.5) maps the unit square
    // onto the lower-left quadrant of the image, rotated: corners land as below.
    TextureTransform t;
    t.offset = vec2(0, 1);
    t.rotation = 1.57079632679f;
    t.scale = vec2(0.5f);
    CHECK_NEAR(transformUv(t, vec2(0, 0)), vec2(0, 1), 1e-6f);
    CHECK_NEAR(transformUv(t, vec2(1, 0)), vec2(0, 0.5f), 1e-6f);
    CHECK_NEAR(transformUv(t, vec2(0, 1)), vec2(0.5f, 1), 1e-6f);
    CHECK_NEAR(transformUv(t, vec2(1, 1)), vec2(0.5f, 0.5f), 1e-6f);
    CHECK_NEAR(transformUv(TextureTransform{}, vec2(0.3f, 0.7f)), vec2(0.3f, 0.7f));
}

TEST_CASE("interpolateSurface blends by barycentrics and keeps normals unit", "[scene]") {
    Mesh mesh;
    mesh.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
    mesh.normals = {{0, 0, 1}, {1, 0, 0}, {0, 0, 1}};
    mesh.uv0 = {{0, 0}, {1, 0}, {0, 1}};
    mesh.indices = {0, 1, 2};
    const SurfacePoint p = interpolateSurface(mesh, 0, vec2(0.5f, 0.25f));
    CHECK_NEAR(p.position, vec3(1.0f, 0.5f, 0.0f));
    CHECK_NEAR(p.uv0, vec2(0.5f, 0.25f));
    CHECK_NEAR(p.uv1, vec2(0.0f));
    // 0.25·(0,0,1) + 0.5·(1,0,0) + 0.25·(0,0,1) = (0.5, 0, 0.5) → (1, 0, 1)/√2.
    CHECK_NEAR(p.normal, vec3(1, 0, 1) / std::sqrt(2.0f), 1e-6f);

    // Opposite vertex normals that cancel fall back to the face normal.
    mesh.normals = {{0, 0, 1}, {0, 0, -1}, {0, 0, 1}};
    CHECK_NEAR(interpolateSurface(mesh, 0, vec2(0.5f, 0.0f)).normal, vec3(0, 0, 1), 1e-6f);
}

TEST_CASE("baseColorAt multiplies factor texture and vertex colour", "[scene]") {
    Scene scene;
    Material material;
    material.baseColorFactor = vec4(0.5f, 1.0f, 1.0f, 0.8f);
    material.baseColorTexture.texture = 0;
    material.baseColorTexture.texCoord = 1;
    scene.materials.push_back(material);
    scene.textures.push_back(twoTexels(WrapMode::ClampToEdge, true));
    Mesh mesh;
    mesh.material = 0;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    mesh.uv0 = {{0.1f, 0}, {0.1f, 0}, {0.1f, 0}};  // left texel: must not be used
    mesh.uv1 = {{0.9f, 0}, {0.9f, 0}, {0.9f, 0}};  // right texel
    mesh.colors = {{1, 0.5f, 2, 1}, {1, 0.5f, 2, 1}, {1, 0.5f, 2, 1}};
    mesh.indices = {0, 1, 2};
    CHECK_NEAR(baseColorAt(scene, mesh, 0, vec2(0.2f, 0.2f)), vec4(0.5f, 0.3f, 0.0f, 0.4f), 1e-6f);
    // Emission is zero without an emissive factor, whatever the textures say.
    CHECK_NEAR(emissionAt(scene, mesh, 0, vec2(0.2f, 0.2f)), vec3(0.0f));
}
