// Punctual lights over a plane: the direct light at a receiver is exact (no noise for a
// point light), so each texel's E/π must equal I cos θ/(π r²) (spot: times the glTF smooth
// cone falloff; directional: E cos θ/π) to 1e-3 relative, and be exactly 0 in a shadow.
// Receivers here are texel centres computed by hand; the rasteriser's are tested in bake/.
#include "pt_scenes.h"

#include "trace/path_tracer.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

constexpr int kRes = 32;
constexpr float kX0 = -1.0f, kX1 = 1.0f, kZ0 = -1.0f, kZ1 = 1.0f;

vec3 texelCentre(int x, int y) {
    return vec3(kX0 + (x + 0.5f) / kRes * (kX1 - kX0), 0.0f, kZ0 + (y + 0.5f) / kRes * (kZ1 - kZ0));
}

SurfaceSampleSet planeTexels() {
    SurfaceSampleSet set;
    set.width = set.height = kRes;
    set.begin.resize(kRes * kRes + 1);
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            SurfaceSample s;
            s.position = texelCentre(x, y);
            s.normal = vec3(0, 1, 0);
            s.albedo = vec3(0.5f);
            s.triangle = 0;
            set.begin[set.samples.size() + 1] = static_cast<uint32_t>(set.samples.size() + 1);
            set.samples.push_back(s);
        }
    return set;
}

// The plane, plus a black square at height 0.25 facing down that shadows part of it.
Scene planeScene(const Light& light) {
    Scene scene;
    scene.sourcePath = "plane";
    scene.materials.push_back(lambert("grey", vec3(0.5f)));
    scene.materials.push_back(lambert("black", vec3(0.0f)));
    scene.meshes.push_back(makeFloor("plane", kX0, kX1, kZ0, kZ1, 0.0f, 0));
    Mesh blocker = makeFloor("blocker", -0.2f, 0.1f, -0.1f, 0.2f, 0.25f, 1);
    blocker.uv1.clear();
    scene.meshes.push_back(blocker);
    scene.lights.push_back(light);
    return scene;
}

// Whether the segment p → q passes the blocker square (−1 blocked, 1 clear, 0 too close to call).
int blockerTest(vec3 p, vec3 towardLight) {
    const float s = 0.25f / towardLight.y;
    const vec3 q = p + s * towardLight;
    const float margin = 1e-3f;
    const bool inside = q.x > -0.2f + margin && q.x < 0.1f - margin && q.z > -0.1f + margin && q.z < 0.2f - margin;
    const bool outside = q.x < -0.2f - margin || q.x > 0.1f + margin || q.z < -0.1f - margin || q.z > 0.2f + margin;
    return inside ? -1 : outside ? 1 : 0;
}

struct Counts {
    int lit = 0, shadowed = 0;
};

// expectedEOverPi(p) gives the unshadowed E/π; towardLight(p) the (unnormalised) direction to it.
template <class Expected, class Toward>
Counts checkPlane(const Light& light, Expected expectedEOverPi, Toward towardLight) {
    TraceFixture f(planeScene(light));
    PathTracerSettings settings;
    settings.samplesPerPixel = 1;
    settings.quiet = true;
    const TraceResult r = traceIrradiance(f.trace, f.bvh, planeTexels(), settings);
    Counts counts;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            const vec3 p = texelCentre(x, y);
            const int blocked = blockerTest(p, towardLight(p));
            for (int c = 0; c < 3; ++c) {
                INFO("texel " << x << ", " << y << " channel " << c);
                REQUIRE(r.indirect.at(x, y, c) == 0.0f);  // the plane cannot see itself; the blocker is black
                if (blocked < 0) REQUIRE(r.direct.at(x, y, c) == 0.0f);
                if (blocked > 0) {
                    const float expected = expectedEOverPi(p)[c];
                    if (expected == 0.0f) REQUIRE(r.direct.at(x, y, c) == 0.0f);  // outside a spot's cone
                    else REQUIRE(r.direct.at(x, y, c) == Approx(expected).epsilon(1e-3));
                }
            }
            counts.lit += blocked > 0;
            counts.shadowed += blocked < 0;
        }
    return counts;
}

}  // namespace

TEST_CASE("Point light over a plane: texel E over pi is I cos theta over pi r squared", "[trace]") {
    Light light;
    light.type = LightType::Point;
    light.position = vec3(0.3f, 0.5f, -0.2f);
    light.color = vec3(1.0f, 0.5f, 0.25f);
    light.intensity = 2.0f;
    const Counts counts = checkPlane(
        light,
        [&](vec3 p) {
            const vec3 d = light.position - p;
            const float r2 = glm::dot(d, d);
            const float cosTheta = d.y / std::sqrt(r2);
            return light.radiantIntensity() * cosTheta / (kPi * r2);
        },
        [&](vec3 p) { return light.position - p; });
    REQUIRE(counts.lit > 500);
    REQUIRE(counts.shadowed > 20);
}

TEST_CASE("Spot light over a plane follows the glTF smooth cone falloff", "[trace]") {
    Light light;
    light.type = LightType::Spot;
    light.position = vec3(-0.1f, 0.6f, 0.1f);
    light.direction = glm::normalize(vec3(0.3f, -1.0f, 0.1f));
    light.intensity = 3.0f;
    light.innerConeAngle = 0.5f;
    light.outerConeAngle = 0.9f;
    const float cosOuter = std::cos(0.9f), cosInner = std::cos(0.5f);
    int inPenumbra = 0;
    const Counts counts = checkPlane(
        light,
        [&](vec3 p) {
            const vec3 d = light.position - p;
            const float r2 = glm::dot(d, d);
            const float cosTheta = d.y / std::sqrt(r2);
            const float cd = glm::dot(light.direction, -d / std::sqrt(r2));
            const float t = glm::clamp((cd - cosOuter) / (cosInner - cosOuter), 0.0f, 1.0f);
            inPenumbra += t > 0.0f && t < 1.0f;
            return light.radiantIntensity() * (t * t * cosTheta / (kPi * r2));
        },
        [&](vec3 p) { return light.position - p; });
    REQUIRE(counts.lit > 500);
    REQUIRE(inPenumbra > 50);
}

TEST_CASE("Directional light over a plane gives E cos theta over pi", "[trace]") {
    Light light;
    light.type = LightType::Directional;
    light.direction = glm::normalize(vec3(0.4f, -1.0f, -0.3f));
    light.intensity = 1.5f;
    const Counts counts = checkPlane(
        light, [&](vec3) { return light.radiantIntensity() * (-light.direction.y / kPi); },
        [&](vec3) { return -light.direction; });
    REQUIRE(counts.lit > 500);
    REQUIRE(counts.shadowed > 20);
}
