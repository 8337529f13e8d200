// The flat TraceScene against the Scene it came from: textured base colour and emission
// looked up by the VL_HOSTDEV code equal scene/surface.h's (an independent implementation),
// the default material fills in for meshes without one, and light sampling's probabilities
// add up to one and follow area × emission.
#include "pt_scenes.h"

#include "core/rng.h"
#include "scene/surface.h"

#include <catch2/catch.hpp>

using namespace vl;
using namespace vl::test;

namespace {

Texture checker(int w, int h, WrapMode wrapS, WrapMode wrapT, bool nearest) {
    Texture t;
    t.name = "checker";
    t.image = Image(w, h, 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            t.image.at(x, y, 0) = 0.1f + 0.8f * float((x + y) % 2);
            t.image.at(x, y, 1) = float(x) / w;
            t.image.at(x, y, 2) = float(y) / h;
            t.image.at(x, y, 3) = 1.0f;
        }
    t.wrapS = wrapS;
    t.wrapT = wrapT;
    t.nearest = nearest;
    return t;
}

}  // namespace

TEST_CASE("TraceScene texture lookups equal the scene's surface sampling", "[trace]") {
    Scene scene;
    scene.sourcePath = "textured";
    scene.textures.push_back(checker(5, 3, WrapMode::Repeat, WrapMode::MirroredRepeat, false));
    scene.textures.push_back(checker(4, 4, WrapMode::ClampToEdge, WrapMode::Repeat, true));
    Material m = lambert("textured", vec3(0.9f, 0.8f, 0.7f), vec3(2.0f, 1.0f, 0.5f));
    m.baseColorTexture.texture = 0;
    m.baseColorTexture.transform.offset = vec2(0.3f, -0.2f);
    m.baseColorTexture.transform.scale = vec2(2.5f, 1.5f);
    m.baseColorTexture.transform.rotation = 0.4f;
    m.emissiveTexture.texture = 1;
    m.emissiveTexture.texCoord = 1;
    m.emissiveStrength = 3.0f;
    scene.materials.push_back(m);
    Mesh mesh = makeFloor("floor", -1, 1, -1, 1, 0, 0);
    mesh.uv0 = {{-0.7f, 0.2f}, {1.9f, -0.4f}, {2.2f, 1.7f}, {-0.3f, 2.4f}};
    mesh.colors = {{1, 0.5f, 0.25f, 1}, {0.5f, 1, 1, 1}, {1, 1, 0.5f, 1}, {0.25f, 0.75f, 1, 1}};
    scene.meshes.push_back(mesh);
    Mesh plain = makeFloor("plain", 2, 3, 2, 3, 0, -1);  // the glTF default material
    scene.meshes.push_back(plain);
    TraceFixture f(std::move(scene));
    const TraceSceneView v = f.trace.view();
    REQUIRE(v.uv0 != nullptr);
    REQUIRE(v.uv1 != nullptr);
    REQUIRE(v.colors != nullptr);

    Pcg32 rng(11, 12);
    for (int i = 0; i < 2000; ++i) {
        const uint32_t triangle = rng.nextU32() % 2;
        vec2 b(rng.next1D(), rng.next1D());
        if (b.x + b.y > 1.0f) b = vec2(1.0f) - b;
        const SurfaceHit h = surfaceAt(v, triangle, b.x, b.y);
        const Mesh& source = f.scene.meshes[0];
        const vec3 expectedBase = glm::clamp(vec3(baseColorAt(f.scene, source, triangle, b)), vec3(0.0f), vec3(1.0f));
        const vec3 base = baseColorAt(v, h);
        const vec3 expectedEmission = emissionAt(f.scene, source, triangle, b);
        const vec3 emission = emissionAt(v, h, h.geometricNormal);
        for (int c = 0; c < 3; ++c) {
            REQUIRE(base[c] == Approx(expectedBase[c]).margin(1e-5));
            REQUIRE(emission[c] == Approx(expectedEmission[c]).margin(1e-5));
        }
        REQUIRE(glm::length(h.position - interpolateSurface(source, triangle, b).position) < 1e-6f);
    }
    // The default material: white, Lambert, not emissive.
    const SurfaceHit plainHit = surfaceAt(v, 2, 0.2f, 0.3f);
    REQUIRE(baseColorAt(v, plainHit) == vec3(1.0f));
    REQUIRE(emissionAt(v, plainHit, vec3(0, 1, 0)) == vec3(0.0f));
    REQUIRE(v.materials[plainHit.material].kind == MaterialKind::Lambert);
}

TEST_CASE("Emitter selection probabilities sum to one and follow area times emission", "[trace]") {
    Scene scene;
    scene.sourcePath = "emitters";
    scene.materials.push_back(lambert("dim", vec3(0.5f), vec3(1.0f)));
    scene.materials.push_back(lambert("bright", vec3(0.5f), vec3(3.0f)));
    scene.materials.push_back(lambert("dark", vec3(0.5f)));
    scene.meshes.push_back(makeFloor("a", 0, 1, 0, 1, 0, 0));    // area 1, emission 1
    scene.meshes.push_back(makeFloor("b", 0, 2, 0, 1, 1, 1));    // area 2, emission 3
    scene.meshes.push_back(makeFloor("c", 0, 5, 0, 5, 2, 2));    // not an emitter
    TraceFixture f(std::move(scene));
    const TraceSceneView v = f.trace.view();
    REQUIRE(v.emitterCount == 4);
    REQUIRE(v.emitterCdf[3] == 1.0f);
    double sum = 0.0;
    for (uint32_t t = 0; t < v.triangleCount; ++t) sum += v.emitterSelectPdf[t];
    REQUIRE(sum == Approx(1.0));
    // Power 1 : 6 between the meshes, split evenly between each mesh's two triangles.
    REQUIRE(v.emitterSelectPdf[0] == Approx(1.0 / 14.0));
    REQUIRE(v.emitterSelectPdf[2] == Approx(3.0 / 7.0));
    REQUIRE(v.emitterSelectPdf[4] == 0.0f);
    // pickEmitter inverts the CDF.
    int counts[4] = {0, 0, 0, 0};
    Pcg32 rng(1, 1);
    for (int i = 0; i < 70000; ++i) ++counts[pickEmitter(v, rng.next1D())];
    REQUIRE(counts[0] == Approx(5000).margin(300));
    REQUIRE(counts[2] == Approx(30000).margin(600));
}
