// Lighting against closed forms: planes under point, directional and spot lights, both
// attenuation models, the range window, the r clamp, and an emissive quad against the exact
// form factor of a parallel rectangle.
#include "lighting/lighting.h"
#include "tests/lighting/synthetic.h"
#include "tests/support/form_factor.h"

#include "core/error.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;
using namespace vl::test;

namespace {

constexpr double kH = 0.1;  // voxel size, metres

// A square plane of voxels facing `axisSign`·e_axis through layer `layer`, ±half voxels wide.
VoxelScene plane(int axis, float axisSign, int layer, int half, bool solid = true) {
    VoxelBuilder builder(kH);
    vec3 n(0.0f);
    n[axis] = axisSign;
    for (int u = -half; u <= half; ++u)
        for (int v = -half; v <= half; ++v) {
            ivec3 c(0);
            c[axis] = layer;
            c[(axis + 1) % 3] = u;
            c[(axis + 2) % 3] = v;
            builder.set(c, surfaceVoxel(n, 0.5f, solid));
        }
    return builder.build();
}

bool near(const vec3& got, const vec3& expected, float relative) {
    for (int a = 0; a < 3; ++a)
        if (std::abs(got[a] - expected[a]) > relative * std::abs(expected[a])) return false;
    return true;
}

const NormalWeighting kModes[] = {NormalWeighting::Lambert, NormalWeighting::Villegas, NormalWeighting::SixAxis};
const VisibilityTraversal kTraversals[] = {VisibilityTraversal::Hdda, VisibilityTraversal::Dda};

}  // namespace

TEST_CASE("A plane under a low point light gets albedo over pi times I cos over r squared everywhere", "[lighting]") {
    // The light hangs 3.5 voxels over a plane 81 voxels wide: the far voxels see it at ~5°,
    // where a ray from the voxel centre would cross its neighbours. Every voxel is solid, so
    // any self-shadowing would show as an exact zero.
    struct Case { int axis; float sign; int layer; vec3 light; };
    const Case cases[] = {
        {2, 1.0f, 0, vec3(0.03f, -0.02f, 0.35f)},
        {2, 1.0f, 7, vec3(-0.11f, 0.23f, 0.7f + 0.35f)},
        {1, -1.0f, -3, vec3(0.17f, -0.3f - 0.42f, 0.05f)},
        {0, 1.0f, 2, vec3(0.2f + 0.5f, 0.1f, -0.3f)},
    };
    for (const Case& c : cases) {
        for (NormalWeighting mode : kModes) {
            for (VisibilityTraversal traversal : kTraversals) {
                VoxelScene voxels = plane(c.axis, c.sign, c.layer, 40);
                const Scene scene = lightsOnly({pointLight(c.light, 2.5f)});
                LightingSettings settings;
                settings.normalWeights = mode;
                settings.traversal = traversal;
                lightVoxels(scene, voxels, settings);
                size_t bad = 0;
                for (size_t i = 0; i < voxels.size(); ++i) {
                    const vec3 p = voxels.centre(i);
                    const vec3 d = c.light - p;
                    const float r = glm::length(d);
                    const float cosTheta = c.sign * d[c.axis] / r;
                    const vec3 expected = vec3(0.5f * kInvPi * 2.5f * cosTheta / (r * r));
                    if (!near(voxels.radiance[i], expected, 1e-4f) || voxels.occlusion[i] != 0.0f) ++bad;
                }
                INFO("axis " << c.axis << " mode " << toString(mode) << " hdda " << (traversal == VisibilityTraversal::Hdda));
                CHECK(bad == 0);
            }
        }
    }
}

TEST_CASE("A plane under a directional light gets albedo over pi times E cos theta", "[lighting]") {
    for (NormalWeighting mode : kModes) {
        VoxelScene voxels = plane(2, 1.0f, 3, 30);
        const vec3 travel = glm::normalize(vec3(0.3f, -0.4f, -1.0f));
        const Scene scene = lightsOnly({directionalLight(travel, 3.0f)});
        LightingSettings settings;
        settings.normalWeights = mode;
        lightVoxels(scene, voxels, settings);
        const vec3 expected(0.5f * kInvPi * 3.0f * -travel.z);
        size_t bad = 0;
        for (size_t i = 0; i < voxels.size(); ++i) bad += near(voxels.radiance[i], expected, 1e-5f) ? 0 : 1;
        CHECK(bad == 0);

        // From below, the one-sided plane gets nothing.
        const Scene below = lightsOnly({directionalLight(vec3(0.3f, -0.4f, 1.0f), 3.0f)});
        lightVoxels(below, voxels, settings);
        for (size_t i = 0; i < voxels.size(); ++i) bad += voxels.radiance[i] == vec3(0.0f) ? 0 : 1;
        CHECK(bad == 0);
    }
}

TEST_CASE("A spot light is zero outside its outer cone and follows the smooth falloff between the cones", "[lighting]") {
    VoxelScene voxels = plane(2, 1.0f, 0, 40);
    Light spot = pointLight(vec3(0.05f, -0.03f, 1.0f), 4.0f, "spot");
    spot.type = LightType::Spot;
    spot.direction = glm::normalize(vec3(0.2f, 0.1f, -1.0f));
    spot.innerConeAngle = 0.25f;
    spot.outerConeAngle = 0.6f;
    lightVoxels(lightsOnly({spot}), voxels, LightingSettings{});
    const float cosInner = std::cos(spot.innerConeAngle), cosOuter = std::cos(spot.outerConeAngle);
    size_t outside = 0, between = 0, inside = 0, bad = 0;
    for (size_t i = 0; i < voxels.size(); ++i) {
        const vec3 d = spot.position - voxels.centre(i);
        const float r = glm::length(d);
        const float cd = glm::dot(spot.direction, -d / r);
        const float unattenuated = 0.5f * kInvPi * 4.0f * (d.z / r) / (r * r);
        if (cd < cosOuter - 1e-4f) {
            ++outside;
            bad += voxels.radiance[i] == vec3(0.0f) ? 0 : 1;
            continue;
        }
        const float t = glm::clamp((cd - cosOuter) / (cosInner - cosOuter), 0.0f, 1.0f);
        if (t > 0.0f && t < 1.0f) ++between;
        if (t >= 1.0f) ++inside;
        const float expected = unattenuated * t * t;
        bad += std::abs(voxels.radiance[i].x - expected) <= 1e-4f * unattenuated ? 0 : 1;
    }
    CHECK(bad == 0);
    CHECK(outside > 100);
    CHECK(between > 100);
    CHECK(inside > 10);
}

TEST_CASE("Eq 18 attenuation set globally or per light by name replaces the inverse square", "[lighting]") {
    VoxelScene voxels = plane(2, 1.0f, 0, 20);
    const Light a = pointLight(vec3(0.2f, 0.1f, 0.6f), 2.0f, "a");
    const Light b = pointLight(vec3(-0.4f, 0.3f, 0.9f), 3.0f, "b");
    const AttenuationCoefficients k{1.0f, 0.5f, 0.25f};
    auto paper = [&](const Light& light, const vec3& p) {
        const vec3 d = light.position - p;
        const float r = glm::length(d);
        return light.intensity * (d.z / r) / (k.constant + k.linear * r + k.quadratic * r * r);
    };
    auto physical = [&](const Light& light, const vec3& p) {
        const vec3 d = light.position - p;
        const float r = glm::length(d);
        return light.intensity * (d.z / r) / (r * r);
    };
    LightingSettings global;
    global.attenuation = k;
    lightVoxels(lightsOnly({a, b}), voxels, global);
    size_t bad = 0;
    for (size_t i = 0; i < voxels.size(); ++i) {
        const vec3 p = voxels.centre(i);
        const float expected = 0.5f * kInvPi * (paper(a, p) + paper(b, p));
        bad += std::abs(voxels.radiance[i].y - expected) <= 1e-5f * expected ? 0 : 1;
    }
    CHECK(bad == 0);

    LightingSettings perLight;
    perLight.lightAttenuation["a"] = k;
    lightVoxels(lightsOnly({a, b}), voxels, perLight);
    for (size_t i = 0; i < voxels.size(); ++i) {
        const vec3 p = voxels.centre(i);
        const float expected = 0.5f * kInvPi * (paper(a, p) + physical(b, p));
        bad += std::abs(voxels.radiance[i].y - expected) <= 1e-5f * expected ? 0 : 1;
    }
    CHECK(bad == 0);
}

TEST_CASE("The range window of KHR_lights_punctual cuts light off at the range", "[lighting]") {
    VoxelScene voxels = plane(2, 1.0f, 0, 40);
    Light light = pointLight(vec3(0.0f, 0.0f, 0.5f), 2.0f);
    light.range = 1.5f;
    lightVoxels(lightsOnly({light}), voxels, LightingSettings{});
    size_t beyond = 0, bad = 0;
    for (size_t i = 0; i < voxels.size(); ++i) {
        const vec3 d = light.position - voxels.centre(i);
        const float r = glm::length(d);
        const float q = r / light.range;
        const float window = glm::clamp(1.0f - q * q * q * q, 0.0f, 1.0f);
        const float expected = 0.5f * kInvPi * 2.0f * window * (d.z / r) / (r * r);
        if (r >= light.range) {
            ++beyond;
            bad += voxels.radiance[i] == vec3(0.0f) ? 0 : 1;
        } else {
            bad += std::abs(voxels.radiance[i].z - expected) <= 1e-4f * 0.5f * kInvPi * 2.0f / (r * r) ? 0 : 1;
        }
    }
    CHECK(beyond > 100);
    CHECK(bad == 0);
}

TEST_CASE("A light inside a voxel is attenuated with r clamped to half a voxel", "[lighting]") {
    VoxelScene voxels = plane(2, 1.0f, 0, 2);
    const Light light = pointLight(vec3(0.0f, 0.0f, 0.01f), 1.5f);  // 0.1 voxel over (0, 0, 0)
    lightVoxels(lightsOnly({light}), voxels, LightingSettings{});
    const size_t centre = indexOf(voxels, ivec3(0));
    const float r = 0.5f * static_cast<float>(kH);
    CHECK(voxels.radiance[centre].x == Approx(0.5f * kInvPi * 1.5f / (r * r)).epsilon(1e-5));
}

namespace {

// An emissive square [x0, x1]×[y0, y1] at height z facing −Z (two triangles).
Scene emissiveSquare(float x0, float x1, float y0, float y1, float z, float Le, bool doubleSided) {
    Scene scene = lightsOnly({});
    Material material;
    material.name = "emitter";
    material.baseColorFactor = vec4(0.0f, 0.0f, 0.0f, 1.0f);
    material.emissiveFactor = vec3(1.0f);
    material.emissiveStrength = Le;
    material.doubleSided = doubleSided;
    scene.materials.push_back(material);
    Mesh mesh;
    mesh.name = "emitter/0";
    mesh.material = 0;
    mesh.positions = {vec3(x0, y0, z), vec3(x1, y0, z), vec3(x1, y1, z), vec3(x0, y1, z)};
    mesh.normals.assign(4, vec3(0.0f, 0.0f, -1.0f));
    mesh.indices = {0, 2, 1, 0, 3, 2};  // clockwise from above: the front faces −Z
    scene.meshes.push_back(mesh);
    return scene;
}

}  // namespace

TEST_CASE("An emissive square over a plane gives the exact parallel-rectangle form factor", "[lighting]") {
    const float z = 1.0f, Le = 2.0f;
    const float x0 = -0.2f, x1 = 0.2f, y0 = -0.15f, y1 = 0.25f;
    const Scene scene = emissiveSquare(x0, x1, y0, y1, z, Le, false);
    // Nothing shadows the plane, so the ratio estimator (Lambert's polygon formula times the
    // samples' visible fraction, here 1) is exact at any number of strata: only float
    // rounding remains. (The plain n×n stratified sum it replaced erred by about 0.25/n².)
    for (int strata : {1, 2, 3, 8}) {
        VoxelScene voxels = plane(2, 1.0f, 0, 12);
        LightingSettings settings;
        settings.emitterStrata = strata;
        lightVoxels(scene, voxels, settings);
        double worst = 0.0;
        for (size_t i = 0; i < voxels.size(); ++i) {
            const vec3 p = voxels.centre(i);
            const double F = rectangleFormFactor(x0 - p.x, x1 - p.x, y0 - p.y, y1 - p.y, z - p.z);
            const double expected = 0.5 / M_PI * Le * M_PI * F;
            worst = std::max(worst, std::abs(voxels.radiance[i].x - expected) / expected);
        }
        INFO("strata " << strata);
        CHECK(worst < 1e-4);
    }
}

TEST_CASE("An emitter's own voxels do not shadow its light and a one-sided emitter lights nothing behind it", "[lighting]") {
    const Scene oneSided = emissiveSquare(-0.2f, 0.2f, -0.2f, 0.2f, 1.0f, 2.0f, false);
    VoxelScene bare = plane(2, 1.0f, 0, 10);
    lightVoxels(oneSided, bare, LightingSettings{});

    // The same plane plus the emitter's own solid voxels (layer 10 = 1 m) and a plane above
    // it facing down.
    VoxelBuilder builder(kH);
    for (int u = -10; u <= 10; ++u)
        for (int v = -10; v <= 10; ++v) {
            builder.set(ivec3(u, v, 0), surfaceVoxel(vec3(0, 0, 1)));
            builder.set(ivec3(u, v, 20), surfaceVoxel(vec3(0, 0, -1)));
        }
    for (int u = -2; u <= 2; ++u)
        for (int v = -2; v <= 2; ++v) builder.set(ivec3(u, v, 10), surfaceVoxel(vec3(0, 0, -1)));
    VoxelScene full = builder.build();
    lightVoxels(oneSided, full, LightingSettings{});
    size_t mismatched = 0, litAbove = 0;
    for (size_t i = 0; i < bare.size(); ++i)
        mismatched += full.radiance[indexOf(full, bare.coords[i])] == bare.radiance[i] ? 0 : 1;
    for (int u = -10; u <= 10; ++u)
        for (int v = -10; v <= 10; ++v) litAbove += full.radiance[indexOf(full, ivec3(u, v, 20))] == vec3(0.0f) ? 0 : 1;
    CHECK(mismatched == 0);
    CHECK(litAbove == 0);

    // Double-sided, the plane above is lit too.
    const Scene twoSided = emissiveSquare(-0.2f, 0.2f, -0.2f, 0.2f, 1.0f, 2.0f, true);
    lightVoxels(twoSided, full, LightingSettings{});
    CHECK(full.radiance[indexOf(full, ivec3(0, 0, 20))].x > 0.0f);
    CHECK(full.radiance[indexOf(full, ivec3(0, 0, 0))].x > 0.0f);
}

TEST_CASE("An emitter flush under a surface does not light the surface it covers; a surface a layer away is lit exactly",
          "[lighting]") {
    // A double-sided square light 0.05 voxel under a ceiling (a lamp panel mounted on it):
    // its back lights the ceiling, but only the part it covers, where nothing can see it, and
    // the voxels there hold the emitter's side too. Were it lit, cones would see the ceiling
    // glow through the light's voxels (the Cycles Cornell box floor took 14 % of its first
    // bounce from that glow, the path tracer none). The same light two layers under the
    // ceiling lights it with the exact parallel-rectangle form factor.
    const float Le = 2.0f, half = 0.2f;
    for (int gapLayers : {0, 2}) {
        const float ceiling = 1.0f + gapLayers * float(kH);
        const Scene twoSided = emissiveSquare(-half, half, -half, half, 1.0f - 0.05f * float(kH), Le, true);
        VoxelBuilder builder(kH);
        for (int u = -10; u <= 10; ++u)
            for (int v = -10; v <= 10; ++v) builder.set(ivec3(u, v, 10 + gapLayers), surfaceVoxel(vec3(0, 0, -1)));
        VoxelScene voxels = builder.build();
        lightVoxels(twoSided, voxels, LightingSettings{});
        double worst = 0.0;
        for (size_t i = 0; i < voxels.size(); ++i) {
            const vec3 p = voxels.centre(i);
            const double c = ceiling - (1.0 - 0.05 * kH);
            const double F = rectangleFormFactor(-half - p.x, half - p.x, -half - p.y, half - p.y, c);
            const double expected = gapLayers == 0 ? 0.0 : 0.5 / M_PI * Le * M_PI * F;
            worst = std::max(worst, std::abs(voxels.radiance[i].x - expected) / (0.5 * Le));
        }
        INFO("ceiling " << gapLayers << " layers above the light's own; worst error / (albedo Le) " << worst);
        CHECK(worst < 1e-4);
    }
}

TEST_CASE("A voxel's light is evaluated where its surface lies inside it, not at its centre", "[lighting]") {
    // The plane of the first case above, its surface 0.37 voxel above the voxels' centres
    // (voxelize() records where: VoxelScene::surfaceOffset). Under a light 3.5 voxels over
    // the centres the centre is 12 % farther from the light than the surface straight below
    // it, (3.5 / 3.13)² − 1 in irradiance: the closed form at the surface point holds to float
    // rounding, the one at the centre does not.
    const vec3 light(0.03f, -0.02f, 0.35f);
    const float offset = 0.37f;
    VoxelScene voxels = plane(2, 1.0f, 0, 40);
    voxels.surfaceOffset.assign(voxels.size(), vec3(0.0f, 0.0f, offset));
    lightVoxels(lightsOnly({pointLight(light, 2.5f)}), voxels, LightingSettings{});
    size_t atSurface = 0, atCentre = 0;
    for (size_t i = 0; i < voxels.size(); ++i) {
        for (float along : {offset, 0.0f}) {
            const vec3 p = voxels.centre(i) + vec3(0.0f, 0.0f, along * float(kH));
            const vec3 d = light - p;
            const float r = glm::length(d);
            const vec3 expected = vec3(0.5f * kInvPi * 2.5f * (d.z / r) / (r * r));
            if (near(voxels.radiance[i], expected, 1e-4f)) ++(along == 0.0f ? atCentre : atSurface);
        }
    }
    CHECK(atSurface == voxels.size());
    CHECK(atCentre == 0);
}

TEST_CASE("A quad light's penumbra in the voxel light is the exact one on average, each voxel sampling its own points",
          "[lighting]") {
    // A strip light 1 m over a floor, a solid ledge half way up covering x < −0.05 m: the
    // floor's penumbra runs across x. Each floor voxel's exact light is the ratio estimator's
    // limit: Lambert's polygon formula times the visible share of ∫ cos θ cos θ' / r² over the
    // light, visibility along the kernel's own ray (from the top of the voxel to the point on
    // the light; the ledge's voxels are solid cells). At one point per quad and voxel the
    // points are the voxel's own, so a column of 81 floor voxels across the penumbra
    // averages to the exact light within the points' noise (one standard deviation is 12% of
    // a column's mean where half the light is seen, 22% where a fifth is: hence the bounds);
    // points shared by every voxel made the penumbra the hard shadow of one point of the
    // light: a column 0 or 1 where the truth is ½, errors of 100%.
    const float Le = 2.0f, halfX = 0.3f, halfY = 4.5f;
    const Scene scene = emissiveSquare(-halfX, halfX, -halfY, halfY, 1.0f, Le, false);
    const int rows = 40;
    VoxelBuilder builder(kH);
    for (int u = -12; u <= 12; ++u)
        for (int v = -rows; v <= rows; ++v) builder.set(ivec3(u, v, 0), surfaceVoxel(vec3(0, 0, 1)));
    for (int u = -10; u <= -1; ++u)
        for (int v = -46; v <= 46; ++v) builder.set(ivec3(u, v, 5), surfaceVoxel(vec3(0, 0, 1)));
    VoxelScene voxels = builder.build();
    LightingSettings settings;
    REQUIRE(settings.emitterStrata == 1);
    lightVoxels(scene, voxels, settings);

    // Index space: the ledge's cells span x ≤ −0.5, z ∈ [4.5, 5.5]; a ray is blocked when it
    // is at x < −0.5 where it enters or leaves that slab (x is monotone along it).
    const int nx = 60, ny = 300;
    double worstColumn = 0.0, squares = 0.0, got = 0.0, expected = 0.0;
    int penumbraColumns = 0;
    for (int u = -12; u <= 12; ++u) {
        double columnGot = 0.0, columnExpected = 0.0, unshadowed = 0.0;
        for (int v = -rows; v <= rows; ++v) {
            const vec3 p(float(u), float(v), 0.0f);
            const vec3 origin = p + vec3(0.0f, 0.0f, 0.5f + 1e-3f);
            double all = 0.0, seen = 0.0;
            for (int i = 0; i < nx; ++i)
                for (int j = 0; j < ny; ++j) {
                    const vec3 e((-halfX + 2.0f * halfX * (i + 0.5f) / nx) / float(kH),
                                 (-halfY + 2.0f * halfY * (j + 0.5f) / ny) / float(kH), 10.0f);
                    const vec3 d = e - p;
                    const double r2 = glm::dot(d, d);
                    const double f = double(d.z) * double(d.z) / (r2 * r2);  // cos θ cos θ' / r²
                    const vec3 ray = e - origin;
                    const float xIn = origin.x + ray.x * (4.5f - origin.z) / ray.z;
                    const float xOut = origin.x + ray.x * (5.5f - origin.z) / ray.z;
                    all += f;
                    if (!(std::min(xIn, xOut) < -0.5f)) seen += f;
                }
            const double F = rectangleFormFactor(-halfX - p.x * kH, halfX - p.x * kH, -halfY - p.y * kH,
                                                 halfY - p.y * kH, 1.0);
            unshadowed += 0.5 * Le * F;
            columnExpected += 0.5 * Le * F * (seen / all);
            columnGot += voxels.radiance[indexOf(voxels, ivec3(u, v, 0))].x;
        }
        got += columnGot;
        expected += columnExpected;
        const double share = columnExpected / unshadowed;
        if (share > 0.05 && share < 0.95) {
            const double relative = (columnGot - columnExpected) / columnExpected;
            worstColumn = std::max(worstColumn, std::abs(relative));
            squares += relative * relative;
            ++penumbraColumns;
        }
    }
    const double rms = std::sqrt(squares / std::max(penumbraColumns, 1));
    INFO("penumbra columns " << penumbraColumns << ", column means' RMS error " << rms << ", worst " << worstColumn
                             << ", whole floor " << got / expected);
    REQUIRE(penumbraColumns >= 4);
    CHECK(rms < 0.25);
    CHECK(worstColumn < 0.5);
    CHECK(std::abs(got / expected - 1.0) < 0.02);
}
