// The gather by rays (gather/ray_gather.h): what a ray reads where it hits, and when the bake
// chooses rays over cones.
#include "gather/gather_scene.h"
#include "gather/gather_visibility.h"
#include "gather/fan_rays.h"
#include "gather/ray_gather.h"
#include "gather/shade_element.h"
#include "gather/bounces.h"
#include "core/error.h"
#include "support/room_scenes.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"
#include "voxel/voxelize.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <glm/gtc/quaternion.hpp>

using namespace vl;
using namespace vl::test;

namespace {

struct Traced {
    SceneTriangles triangles;
    Bvh bvh;
    TraceScene scene;
};

Traced traced(const Scene& scene) {
    Traced t;
    t.triangles = gatherTriangles(scene);
    t.bvh = Bvh::build(t.triangles);
    t.scene = TraceScene::build(scene, t.triangles);
    return t;
}

VoxelScene voxels(const Scene& scene, double voxelSize) {
    VoxelSettings settings;
    settings.voxelSize = voxelSize;
    return voxelize(scene, settings);
}

// A closed room of white walls (albedo rho) spanning [0, size], turned by `turn` so that its
// walls cross the voxel axes at a slant.
Scene turnedRoom(const vec3& size, const glm::quat& turn, float rho = 0.5f) {
    Scene scene;
    scene.sourcePath = "room (test)";
    const int white = addLambert(scene, vec3(rho));
    addRoom(scene, "room/", white, vec3(0.0f), size);
    for (Mesh& mesh : scene.meshes)
        for (vec3& p : mesh.positions) p = turn * p;
    return scene;
}

}  // namespace

TEST_CASE("Rays in a closed room whose every wall shows radiance L gather π·L at every point", "[bake]") {
    // Every ray from inside a closed room hits a wall, and each wall's voxels show L to it:
    // E = π·L exactly, whatever the point, the ray count or how the walls cut the voxels. A ray
    // that read a voxel holding no surface on its side (a wall's edge, a corner) would read
    // black and pull its point under π·L. (Corner voxels of the turned room also have sides
    // facing out of it, from faces whose direction opposes the voxel's mean normal
    // (voxel_scene.h voxelSides); their points look at nothing and are left out here.)
    const vec3 size(1.0f, 0.7f, 0.8f);
    const glm::quat turn = glm::angleAxis(0.4f, glm::normalize(vec3(1.0f, 2.0f, 0.5f)));
    const Scene scene = turnedRoom(size, turn);
    VoxelScene lit = voxels(scene, 1.0 / 29.0);
    const vec3 L(0.2f, 0.5f, 1.0f);
    lit.faceRadiance.assign(lit.size(), FaceRadiance{});
    lit.radiance.assign(lit.size(), L);
    for (size_t i = 0; i < lit.size(); ++i)
        for (size_t f = 0; f < 6; ++f) lit.faceRadiance[i][f] = lit.axisWeights[i][f] > 0.0f ? L : vec3(0.0f);
    const RadianceMips mips = buildRadianceMips(lit, lit.radiance, lit.faceRadiance);
    const IrradianceCache cache(lit, 2);
    const Traced t = traced(scene);
    REQUIRE(cache.points().size() > 20);
    for (int raysPerAxis : {4, 16}) {
        const std::vector<vec3> E = gatherByRays(cache.points(), mips.view(), lit.faceRadiance, t.bvh.view(), t.scene.view(), raysPerAxis);
        size_t inside = 0;
        for (size_t q = 0; q < E.size(); ++q) {
            const GatherPoint& point = cache.points()[q];
            const vec3 local = glm::inverse(turn) * liftOffSurface(point.position, point.normal, float(lit.voxelSize));
            if (glm::any(glm::lessThan(local, vec3(0.0f))) || glm::any(glm::greaterThan(local, size))) continue;
            ++inside;
            INFO(raysPerAxis << "² rays, point " << q << " at " << cache.points()[q].position.x << ", "
                             << cache.points()[q].position.y << ", " << cache.points()[q].position.z);
            // Within half a percent: a ray in 256 may pass the seam where two walls' meshes meet.
            for (int c = 0; c < 3; ++c) CHECK(E[q][c] == Approx(kPi * L[c]).epsilon(0.005));
        }
        CHECK(inside > E.size() / 2);
    }
    // A receiver sample that no gather point applies to gathers so too, from level 0 alone
    // (rayGatherAtSample, reading the texels through their index grid): on the walls, at
    // points that lie anywhere in their voxels.
    const RadianceMips levelZero = buildLevelZeroMips(lit, lit.radiance, lit.faceRadiance);
    REQUIRE(levelZero.levelCount() == 1);
    const MipView view = levelZero.view();
    int samples = 0;
    for (const Mesh& wall : scene.meshes)
        for (float u : {0.13f, 0.5f, 0.91f})
            for (float v : {0.07f, 0.42f, 0.77f}) {
                const vec3 p = wall.positions[0] + u * (wall.positions[1] - wall.positions[0]) +
                               v * (wall.positions[3] - wall.positions[0]);
                const vec3 n = wall.normals[0];
                vec3 tangent;
                float turnOfFan;
                gatherFrame(p, n, view.centre(), view.voxelSize, tangent, turnOfFan);
                const vec3 E = rayGatherAtSample(t.scene.view(), t.bvh.view(), view, p, n, tangent, 0.3f, 16);
                INFO(wall.name << " at u = " << u << ", v = " << v);
                for (int c = 0; c < 3; ++c) CHECK(E[c] == Approx(kPi * L[c]).epsilon(0.005));
                ++samples;
            }
    CHECK(samples == 54);
}

TEST_CASE("A near field traces a hit's light on as albedo times what its next ray brings, then reads the voxels", "[bake]") {
    // A closed room whose walls' voxels all show radiance L, with no lights and no emission:
    // a hit's light traced on is its albedo ρ times the light its next ray brings back, so a
    // path that meets only near hits (nearField larger than the room) reads the voxels after
    // kNearFieldBounces reflections, E = π·L·ρ^kNearFieldBounces, and π·L where ρ = 1 (white
    // walls keep all of it, as the voxels' L says). With the near field under every hit's
    // distance, nothing is traced on: π·L.
    const vec3 size(1.0f, 0.7f, 0.8f);
    const vec3 L(0.2f, 0.5f, 1.0f);
    for (float rho : {1.0f, 0.5f}) {
        const Scene scene = turnedRoom(size, glm::quat(1.0f, 0.0f, 0.0f, 0.0f), rho);
        VoxelScene lit = voxels(scene, 1.0 / 29.0);
        lit.faceRadiance.assign(lit.size(), FaceRadiance{});
        lit.radiance.assign(lit.size(), L);
        for (size_t i = 0; i < lit.size(); ++i)
            for (size_t f = 0; f < 6; ++f) lit.faceRadiance[i][f] = lit.axisWeights[i][f] > 0.0f ? L : vec3(0.0f);
        const RadianceMips mips = buildRadianceMips(lit, lit.radiance, lit.faceRadiance);
        const Traced t = traced(scene);
        std::vector<FanStart> fans;
        for (const vec3& at : {vec3(0.5f, 0.35f, 0.4f), vec3(0.2f, 0.1f, 0.7f), vec3(0.9f, 0.6f, 0.1f)})
            for (const vec3& normal : {vec3(0, 1, 0), vec3(0, -1, 0), glm::normalize(vec3(1, 1, -1))}) {
                FanStart fan;
                fan.origin = at;
                vec3 tangent, bitangent;
                orthonormalBasis(normal, tangent, bitangent);
                fan.frame = fanFrame(normal, tangent, 0.3f);
                fan.seed = fans.size();
                fans.push_back(fan);
            }
        const int raysPerAxis = 8;
        const size_t rays = fans.size() * size_t(raysPerAxis * raysPerAxis);
        for (float nearField : {10.0f, 0.01f}) {
            FanExtras extras;
            extras.readSky = false;
            extras.nearField = nearField;
            const std::vector<vec3> E = gatherFans(fans, mips.view(), lit.faceRadiance, t.bvh.view(), t.scene.view(),
                                                   raysPerAxis, nullptr, &extras);
            const bool traces = nearField > 1.0f;
            const float expected = traces ? std::pow(rho, float(kNearFieldBounces)) : 1.0f;
            INFO("albedo " << rho << ", near field " << nearField << " m");
            CHECK(extras.nearHits == (traces ? rays : 0u));
            // Each near hit's path goes kNearFieldBounces rays on (a ray in hundreds may leave
            // by the seam where two walls meet).
            if (traces) CHECK(double(extras.nearRays) >= 0.99 * double(rays * kNearFieldBounces));
            else CHECK(extras.nearRays == 0u);
            for (size_t q = 0; q < E.size(); ++q)
                for (int c = 0; c < 3; ++c) CHECK(E[q][c] == Approx(kPi * L[c] * expected).epsilon(0.01));
        }
    }
}

TEST_CASE("Rays read nothing behind the surface they hit", "[bake]") {
    // A lit wall (radiance L on its +X side) 1.5 voxels behind a dark one (no light) facing the
    // same way: rays from in front of the dark wall hit it and must read its black, not the
    // lit wall one and a half voxels behind (a trilinear read of the level around the hit
    // would reach it).
    Scene scene;
    scene.sourcePath = "walls (test)";
    const int white = addLambert(scene, vec3(0.5f));
    const float h = 0.05f;
    addQuad(scene, "dark", white, vec3(0.0f, -1.0f, -1.0f), vec3(0.0f, 1.0f, -1.0f), vec3(0.0f, 1.0f, 1.0f),
            vec3(0.0f, -1.0f, 1.0f));
    addQuad(scene, "lit", white, vec3(-1.5f * h, -1.0f, -1.0f), vec3(-1.5f * h, 1.0f, -1.0f),
            vec3(-1.5f * h, 1.0f, 1.0f), vec3(-1.5f * h, -1.0f, 1.0f));
    // A floor facing the walls from x = 0.5, so its points look at the dark wall.
    addQuad(scene, "facing", white, vec3(0.5f, -1.0f, -1.0f), vec3(0.5f, -1.0f, 1.0f), vec3(0.5f, 1.0f, 1.0f),
            vec3(0.5f, 1.0f, -1.0f));
    REQUIRE(glm::dot(scene.meshes[0].normals[0], vec3(1.0f, 0.0f, 0.0f)) > 0.99f);
    REQUIRE(glm::dot(scene.meshes[2].normals[0], vec3(-1.0f, 0.0f, 0.0f)) > 0.99f);
    VoxelScene lit = voxels(scene, h);
    lit.faceRadiance.assign(lit.size(), FaceRadiance{});
    lit.radiance.assign(lit.size(), vec3(0.0f));
    for (size_t i = 0; i < lit.size(); ++i)
        if (lit.centre(i).x < -h) lit.faceRadiance[i][0] = vec3(1.0f);  // the lit wall's +X face
    for (size_t i = 0; i < lit.size(); ++i) lit.radiance[i] = faceWeightedMean(lit.faceRadiance[i].data(), lit.axisWeights[i].data());
    const RadianceMips mips = buildRadianceMips(lit, lit.radiance, lit.faceRadiance);
    const IrradianceCache cache(lit, 2);
    const Traced t = traced(scene);
    const std::vector<vec3> E = gatherByRays(cache.points(), mips.view(), lit.faceRadiance, t.bvh.view(), t.scene.view(), 8);
    int facingPoints = 0;
    for (size_t q = 0; q < E.size(); ++q) {
        if (!(cache.points()[q].normal.x < -0.9f)) continue;
        ++facingPoints;
        INFO("point " << q << " at x = " << cache.points()[q].position.x);
        CHECK(E[q].x == 0.0f);
    }
    CHECK(facingPoints > 0);
}

TEST_CASE("A gather point sits on the open floor of a cell a block's foot crosses", "[bake]") {
    // A floor, and a closed block (five outward faces) standing on it whose wall runs through
    // the middle of a cell of 8³ voxels, at x = 4 voxels: the cell's floor is open at voxels
    // x = 0 … 3 and under the block at 5 … 7, where no light reaches. The mean of the whole
    // layer lies at x = 3.5 voxels, on the wall's line, and the receivers on the open floor
    // took that point's darkness. Probed, the point lies at the mean of the open voxels, and
    // the points of open cells do not move.
    Scene scene;
    scene.sourcePath = "block on a floor (test)";
    const int white = addLambert(scene, vec3(0.5f));
    const float h = 1.0f / 64.0f;
    addQuad(scene, "floor", white, vec3(-0.5f, 0.0f, -0.5f), vec3(-0.5f, 0.0f, 0.5f), vec3(0.5f, 0.0f, 0.5f),
            vec3(0.5f, 0.0f, -0.5f));
    Scene block;
    addRoom(block, "block/", white, vec3(4.0f * h, 0.0f, -0.3f), vec3(0.3f, 0.2f, 0.3f));
    for (Mesh& face : block.meshes) {
        if (face.name == "block/floor") continue;  // the block stands on the floor, open below
        for (size_t t = 0; t < face.indices.size(); t += 3) std::swap(face.indices[t + 1], face.indices[t + 2]);
        for (vec3& n : face.normals) n = -n;
        scene.meshes.push_back(face);
    }
    REQUIRE(glm::dot(scene.meshes[0].normals[0], vec3(0.0f, 1.0f, 0.0f)) > 0.99f);
    const VoxelScene v = voxels(scene, h);
    const Traced t = traced(scene);
    const GatherScene enclosed{t.bvh.view(), t.scene.view()};
    const IrradianceCache plain(v, 3), probed(v, 3, &enclosed);
    REQUIRE(plain.points().size() == probed.points().size());
    // The floor's point of the cell holding voxels x, z = 0 … 7 (cell 0), and of the open cell
    // before it along x (cell −1).
    const auto floorPoint = [&](const IrradianceCache& cache, int cellX) {
        for (const GatherPoint& p : cache.points())
            if (p.normal.y > 0.9f && std::abs(p.position.y) < 0.5f * h && p.position.x > (8.0f * cellX - 0.5f) * h &&
                p.position.x < (8.0f * cellX + 7.5f) * h && p.position.z > -0.5f * h && p.position.z < 7.5f * h)
                return p.position;
        FAIL("no floor point in cell " << cellX);
        return vec3(0.0f);
    };
    const vec3 across = floorPoint(plain, 0), open = floorPoint(probed, 0);
    INFO("the whole layer's mean at x = " << across.x / h << " voxels, the open part's at " << open.x / h);
    CHECK(std::abs(across.x - 3.5f * h) < 0.01f * h);
    CHECK(open.x < 2.1f * h);
    CHECK(open.x > 1.4f * h);
    CHECK(floorPoint(probed, -1) == floorPoint(plain, -1));
}

TEST_CASE("The bake gathers by cones where rays see the backs of single-sided surfaces", "[bake]") {
    // A floor under a shelf that faces up as the floor does: the floor's rays hit the shelf's
    // underside, the back of a single-sided surface, which the voxels do not show (they hold a
    // surface's front, and a double-sided surface's two sides).
    for (bool doubleSided : {false, true}) {
        Scene scene;
        scene.sourcePath = "shelf (test)";
        const int white = addLambert(scene, vec3(0.5f));
        scene.materials[size_t(white)].doubleSided = doubleSided;
        addQuad(scene, "floor", white, vec3(0.0f), vec3(0.0f, 0.0f, 1.0f), vec3(1.0f, 0.0f, 1.0f), vec3(1.0f, 0.0f, 0.0f));
        addQuad(scene, "shelf", white, vec3(0.0f, 0.3f, 0.0f), vec3(0.0f, 0.3f, 1.0f), vec3(1.0f, 0.3f, 1.0f),
                vec3(1.0f, 0.3f, 0.0f));
        const VoxelScene v = voxels(scene, 1.0 / 31.0);
        const Traced t = traced(scene);
        const GatherVisibilityChoice choice =
            chooseGatherVisibility(GatherVisibility::Auto, IrradianceCache(v, 3), t.bvh.view(), t.scene.view());
        INFO((doubleSided ? "double-sided: " : "single-sided: ") << describeGatherVisibility(choice));
        REQUIRE(choice.probe.hits > 0);
        if (doubleSided) {
            CHECK(choice.probe.singleSidedBacks == 0);
            CHECK(choice.visibility == GatherVisibility::Rays);
        } else {
            // The floor's rays that hit anything hit the shelf's underside; the shelf's go up.
            CHECK(choice.probe.share() > 0.9);
            CHECK(choice.visibility == GatherVisibility::Cones);
        }
        CHECK_THAT(choice.setBy, Catch::Contains("probe rays hit the back of a single-sided surface"));
        // A setting wins, and says so.
        const GatherVisibilityChoice forced = chooseGatherVisibility(GatherVisibility::Rays, IrradianceCache(v, 3), t.bvh.view(), t.scene.view());
        CHECK(forced.visibility == GatherVisibility::Rays);
        CHECK(forced.setBy == "the gather-visibility setting");
    }
}

TEST_CASE("The bounces' ray transport is the gather by rays, traced once", "[bake]") {
    // rayTransport records which faces a point's rays read and how much; applied to any light
    // it must give what gatherByRays reads from that light directly (up to the order floats
    // are summed in), and its weights at a point inside a closed room, where every ray reads
    // a wall, must sum to π (E = π·L for light L on every face).
    const vec3 size(1.0f, 0.7f, 0.8f);
    const glm::quat turn = glm::angleAxis(0.7f, glm::normalize(vec3(-1.0f, 0.5f, 2.0f)));
    const Scene scene = turnedRoom(size, turn);
    VoxelScene lit = voxels(scene, 1.0 / 23.0);
    // Light that differs from face to face and voxel to voxel.
    lit.faceRadiance.assign(lit.size(), FaceRadiance{});
    lit.radiance.assign(lit.size(), vec3(0.0f));
    for (size_t i = 0; i < lit.size(); ++i) {
        const vec3 c = lit.centre(i);
        for (size_t f = 0; f < 6; ++f)
            if (lit.axisWeights[i][f] > 0.0f)
                lit.faceRadiance[i][f] = vec3(1.0f + std::sin(7.0f * c.x + float(f)), 1.0f + c.y, 0.5f + float(f) / 6.0f);
        lit.radiance[i] = faceWeightedMean(lit.faceRadiance[i].data(), lit.axisWeights[i].data());
    }
    const RadianceMips mips = buildRadianceMips(lit, lit.radiance, lit.faceRadiance);
    const IrradianceCache cache(lit, 2);
    const Traced t = traced(scene);
    const FaceTransport transport = rayTransport(cache.points(), mips.view(), lit.size(), t.bvh.view(), t.scene.view(), 8);
    REQUIRE(transport.pointCount() == cache.points().size());
    const std::vector<vec3> direct = gatherByRays(cache.points(), mips.view(), lit.faceRadiance, t.bvh.view(), t.scene.view(), 8);
    const std::vector<vec3> mapped = applyTransport(transport, lit.faceRadiance);
    size_t inside = 0;
    for (size_t q = 0; q < direct.size(); ++q) {
        INFO("point " << q);
        for (int c = 0; c < 3; ++c) CHECK(mapped[q][c] == Approx(direct[q][c]).epsilon(1e-5).margin(1e-6));
        const GatherPoint& point = cache.points()[q];
        const vec3 local = glm::inverse(turn) * liftOffSurface(point.position, point.normal, float(lit.voxelSize));
        if (glm::any(glm::lessThan(local, vec3(0.0f))) || glm::any(glm::greaterThan(local, size))) continue;
        ++inside;
        double sum = 0.0;
        for (uint32_t k = transport.begin[q]; k < transport.begin[q + 1]; ++k) sum += transport.entries[k].weight;
        CHECK(sum == Approx(kPi).epsilon(0.02));  // a ray in 64 may pass the seam where two walls meet
    }
    CHECK(inside > direct.size() / 2);
    // One entry per face a point reads.
    for (size_t q = 0; q < transport.pointCount(); ++q)
        for (uint32_t k = transport.begin[q] + 1; k < transport.begin[q + 1]; ++k)
            CHECK(transport.entries[k - 1].slot < transport.entries[k].slot);
    // Light for fewer voxels than the transport reads is refused.
    const std::vector<FaceRadiance> tooFew(lit.size() / 2);
    CHECK_THROWS_WITH(applyTransport(transport, tooFew), Catch::Contains("lies past"));
}

TEST_CASE("Bounces by the ray transport in a closed white room follow the series L0·(1 + ρ + ρ²)", "[bake]") {
    // Every ray from inside a closed room hits a wall, so with light L0 on every wall face the
    // first gather is π·L0 and each bounce adds ρ times the last: two bounces give
    // L0·(1 + ρ + ρ²) on every face that looks into the room, the faces of a wall voxel's
    // outward sides (corners of the turned room: voxel_scene.h voxelSides) excepted. No face
    // may exceed the series (a ray reads at most the L of a wall it hits).
    const float rho = 0.5f;
    const Scene scene =
        turnedRoom(vec3(1.0f, 0.7f, 0.8f), glm::angleAxis(0.4f, glm::normalize(vec3(1.0f, 2.0f, 0.5f))), rho);
    VoxelScene room = voxels(scene, 1.0 / 29.0);
    const vec3 l0(1.0f, 0.8f, 0.6f);
    room.faceRadiance.assign(room.size(), FaceRadiance{});
    for (size_t i = 0; i < room.size(); ++i)
        for (size_t f = 0; f < 6; ++f) room.faceRadiance[i][f] = room.axisWeights[i][f] > 0.0f ? l0 : vec3(0.0f);
    room.radiance.assign(room.size(), l0);
    const Traced t = traced(scene);
    BounceSettings bounce{2, 2, BounceTail::None, ConeSettings{}};
    bounce.byRays = true;
    bounce.raysPerAxis = 8;
    const GatherScene rays{t.bvh.view(), t.scene.view()};
    const FaceTransport transport = propagateBounces(room, bounce, &rays).transport;
    REQUIRE(transport.pointCount() > 20);
    const float series = 1.0f + rho + rho * rho;
    size_t faces = 0, onSeries = 0;
    for (size_t i = 0; i < room.size(); ++i)
        for (size_t f = 0; f < 6; ++f) {
            if (!(room.axisWeights[i][f] > 0.0f)) continue;
            ++faces;
            const vec3 ratio = room.faceRadiance[i][f] / l0;
            INFO("voxel " << i << " face " << f << ": L / L0 = " << ratio.x << ", " << ratio.y << ", " << ratio.z);
            for (int c = 0; c < 3; ++c) CHECK(ratio[c] <= series * 1.005f);
            if (glm::abs(ratio.x - series) < 0.01f * series) ++onSeries;
        }
    INFO(onSeries << " of " << faces << " faces within 1% of the series");
    CHECK(onSeries > faces * 9 / 10);
}

TEST_CASE("A gather fan's rays are unit, in the hemisphere, and stand for the cosine distribution", "[bake]") {
    // Each of the n² rays stands for one equal-area stratum of the cosine-weighted hemisphere,
    // so the fan's mean of cos θ is the distribution's, ∫cos θ · cos θ/π dω = 2/3, up to the
    // quadrature's error; and a stratum around the disk's centre (n odd) has no azimuth of its
    // own: its ray is the normal.
    for (int n : {1, 3, 7, 14, 15}) {
        double meanCosine = 0.0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const vec3 d = fanDirection(i, j, n);
                INFO("n " << n << ", ray (" << i << ", " << j << ")");
                CHECK(glm::length(d) == Approx(1.0f).margin(1e-5f));
                CHECK(d.z > 0.0f);
                meanCosine += d.z;
            }
        meanCosine /= double(n * n);
        INFO("n " << n << ": mean cos " << meanCosine);
        if (n % 2 == 1) CHECK(fanDirection(n / 2, n / 2, n).z == Approx(1.0f).margin(1e-6f));
        // Measured: +1.3% at n = 7, +0.4% at 14 and +0.3% at 15.
        if (n >= 7) CHECK(meanCosine == Approx(2.0 / 3.0).epsilon(n >= 14 ? 0.005 : 0.02));
    }
}

namespace {

// A black wall in the plane x = 0, `height` high and 400 m long, under a uniform sky L, with
// no floor (rays below the horizon see the sky).
struct WallFans {
    Traced t;
    VoxelScene voxels;
    RadianceMips mips;
};

WallFans blackWall(float height, const vec3& L) {
    Scene scene;
    scene.sourcePath = "wall (test)";
    scene.sky.radiance = L;
    const int black = addLambert(scene, vec3(0.0f));
    addQuad(scene, "wall", black, {0.0f, -200.0f, 0.0f}, {0.0f, -200.0f, height}, {0.0f, 200.0f, height},
            {0.0f, 200.0f, 0.0f});
    WallFans w{traced(scene), voxels(scene, 0.05), {}};
    w.voxels.faceRadiance.assign(w.voxels.size(), FaceRadiance{});
    w.voxels.radiance.assign(w.voxels.size(), vec3(0.0f));
    w.mips = buildRadianceMips(w.voxels, w.voxels.radiance, w.voxels.faceRadiance);
    return w;
}

// `count` jittered fans at one point, each its own jitter and turn.
std::vector<FanStart> fansAt(const vec3& at, const vec3& normal, size_t count) {
    std::vector<FanStart> fans;
    vec3 tangent, bitangent;
    orthonormalBasis(normal, tangent, bitangent);
    for (size_t k = 0; k < count; ++k) {
        FanStart fan;
        fan.origin = at;
        fan.frame = fanFrame(normal, tangent, float(k) * 0.618034f - std::floor(float(k) * 0.618034f));
        fan.seed = k;
        fan.jitter = vec2((float(k) + 0.5f) / float(count), float(k) * 0.754878f - std::floor(float(k) * 0.754878f));
        fans.push_back(fan);
    }
    return fans;
}

}  // namespace

TEST_CASE("A fan's rotation gradient is the change of its irradiance as its normal turns", "[bake]") {
    // A point 0.3 m from the wall's foot, its normal up: turning the normal by α towards the
    // wall (+X) changes E by α times the rotation gradient's X column. The reference is E
    // itself gathered about normals turned by ±α (a central difference), 64 fans each; E
    // upright must first hold the analytic view factor: the wall fills F = ½ (1 − h / √(h² +
    // H²)) of the point's cosine-weighted sky, E = π L (1 − F). Strata weighted by their mean
    // direction instead of their mean of ω_t / cos θ gave 16% too little.
    const float H = 1.0f, h = 0.3f, alpha = 0.05f;
    const vec3 L(1.0f, 0.5f, 0.25f);
    const WallFans wall = blackWall(H, L);
    const vec3 at(-h, 0.0f, 0.0f);
    const auto gathered = [&](float turn, vec3* rotationX) {
        const std::vector<FanStart> fans = fansAt(at, vec3(std::sin(turn), 0.0f, std::cos(turn)), 64);
        FanExtras extras;
        extras.rotationGradients = true;
        gatherFans(fans, wall.mips.view(), wall.voxels.faceRadiance, wall.t.bvh.view(), wall.t.scene.view(), 16, nullptr,
                   &extras);
        vec3 sky(0.0f), dn(0.0f);
        for (size_t q = 0; q < fans.size(); ++q) {
            sky += extras.sky[q] / float(fans.size());
            dn += extras.rotation[q].sky[0] / float(fans.size());
            CHECK(extras.rotation[q].light == glm::mat3(0.0f));  // the wall reads black
        }
        if (rotationX) *rotationX = dn;
        return sky;
    };
    vec3 rotation(0.0f);
    const vec3 upright = gathered(0.0f, &rotation);
    const float F = 0.5f * (1.0f - h / std::sqrt(h * h + H * H));
    for (int c = 0; c < 3; ++c) CHECK(upright[c] == Approx(kPi * L[c] * (1.0f - F)).epsilon(0.01));
    const vec3 difference = (gathered(alpha, nullptr) - gathered(-alpha, nullptr)) / (2.0f * alpha);
    INFO("dE/dα " << rotation.x << " against the central difference " << difference.x);
    CHECK(difference.x < -0.1f);  // turning towards the black wall darkens
    for (int c = 0; c < 3; ++c) CHECK(rotation[c] == Approx(difference[c]).epsilon(0.05));
}
