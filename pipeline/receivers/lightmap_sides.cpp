#include "receivers/lightmap_sides.h"

#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh_traverse.h"
#include "trace/ray_offset.h"

#include <tbb/parallel_for.h>

#include <array>
#include <limits>
#include <vector>

namespace vl {

LightmapSide parseLightmapSide(const std::string& text) {
    if (text == "front") return LightmapSide::Front;
    if (text == "inside") return LightmapSide::Inside;
    throw SettingsError("setting lightmap-side = '" + text + "' is not one of front, inside");
}

const char* toString(LightmapSide side) { return side == LightmapSide::Front ? "front" : "inside"; }

namespace {

constexpr int kSideRays = 16;     // 4 points × 2 × 2
constexpr int kClearlyFewer = 4;  // of them
// Where the sky does not tell the sides apart: a side whose rays meet something four times
// nearer than the other side's is the one against a wall (a picture frame's back, a panel's
// face on the plaster), and the other side is the one the room sees. Distances are capped at
// a twentieth of the scene's size, so that the open room, not its far walls, counts. Taken
// before the sky, it turned the grey-white room's window jambs and walls to their outer
// faces (docs/accuracy.md).
constexpr float kMuchNearer = 0.25f;
constexpr float kReachCapOfScene = 0.05f;

// What 2 × 2 jittered cosine rays about `normal` from each of a triangle's lookout points find: rays that leave the scene, rays that meet a triangle
// of the side's own material from behind (a closed solid is one material, as a block is), and
// rays that meet any triangle from behind.
// A triangle's centroid and the points halfway from it to each corner: a big floor triangle's
// centroid may lie under a block standing on it.
std::array<vec3, 4> lookoutPoints(const vec3* corner) {
    const vec3 centroid = (corner[0] + corner[1] + corner[2]) / 3.0f;
    return {centroid, 0.5f * (centroid + corner[0]), 0.5f * (centroid + corner[1]), 0.5f * (centroid + corner[2])};
}

struct SideView {
    int open = 0, behindOwn = 0, behind = 0;
    float reach = 0.0f;  // the rays' mean distance to what they meet, each at most kReachCap
};

SideView lookFrom(const BvhView& bvh, const TraceSceneView& scene, const vec3* corner, const vec3& normal, Pcg32& rng,
                  uint32_t material, float reachCap) {
    vec3 t, b;
    orthonormalBasis(normal, t, b);
    const std::array<vec3, 4> points = lookoutPoints(corner);
    SideView view;
    for (const vec3& point : points)
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 2; ++j) {
                vec2 u;
                rng.next2D(u.x, u.y);
                const vec3 d = sampleCosineHemisphere(vec2((float(i) + u.x) / 2.0f, (float(j) + u.y) / 2.0f));
                Ray ray;
                ray.origin = offsetRayOrigin(point, normal, bvh.extent);
                ray.direction = glm::normalize(d.x * t + d.y * b + d.z * normal);
                Hit hit;
                if (!intersectClosest(bvh, ray, hit)) {
                    ++view.open;
                    view.reach += reachCap / float(kSideRays);
                    continue;
                }
                view.reach += std::min(hit.t, reachCap) / float(kSideRays);
                if (glm::dot(windingCross(scene, hit.triangle), ray.direction) > 0.0f) {
                    ++view.behind;
                    view.behindOwn += scene.materialIds[hit.triangle] == material;
                }
            }
    return view;
}

// Whether open space lies on the side `normal` faces of `point`: probed two cells out, or
// halfway to a surface nearer than that (a gap too thin to stand in, which the grid marks
// crossed). Two cells clear the point's own cells.
bool facesOpenSpace(const OpenSpace& space, const BvhView& bvh, const vec3& point, const vec3& normal) {
    const float reach = 2.0f * space.cellSize();
    Ray ray;
    ray.origin = offsetRayOrigin(point, normal, bvh.extent);
    ray.direction = normal;
    ray.tMax = reach;
    Hit hit;
    const float distance = intersectClosest(bvh, ray, hit) ? 0.5f * hit.t : reach;
    return space.open(ray.origin + distance * normal);
}

// How many of a triangle's lookout points face open space on the side `normal` faces.
int openPoints(const OpenSpace& space, const BvhView& bvh, const vec3* corner, const vec3& normal) {
    int open = 0;
    for (const vec3& point : lookoutPoints(corner)) open += facesOpenSpace(space, bvh, point, normal);
    return open;
}

// What a triangle's samples hold: its decision, or, where one side was sealed at the lookout
// points and the other sees outdoors, the sealed side at each sample that faces open space.
enum SideChoice : uint8_t {
    kKeepFront = 0,
    kTurn = 1,
    kTurnUnlessFrontOpen = 2,  // the front sealed at the lookouts, the back outdoors
    kKeepUnlessBackOpen = 3,   // the back sealed at the lookouts, the front outdoors
};

}  // namespace

size_t orientLightmapSamples(SurfaceSampleSet& samples, const BvhView& bvh, const TraceSceneView& scene,
                             const std::vector<Viewpoint>& viewpoints) {
    if (samples.samples.empty() || scene.triangleCount == 0) return 0;
    const OpenSpace space(scene, viewpoints);
    // The double-sided triangles the samples lie on, in triangle order.
    std::vector<uint8_t> held(scene.triangleCount, 0);
    for (const SurfaceSample& s : samples.samples)
        if (s.triangle < scene.triangleCount && scene.materials[scene.materialIds[s.triangle]].doubleSided) held[s.triangle] = 1;
    std::vector<uint32_t> triangles;
    for (uint32_t t = 0; t < scene.triangleCount; ++t)
        if (held[t]) triangles.push_back(t);
    std::vector<uint8_t> choice(scene.triangleCount, kKeepFront);
    vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (size_t k = 0; k < 3 * size_t(scene.triangleCount); ++k) {
        lo = glm::min(lo, scene.vertices[k]);
        hi = glm::max(hi, scene.vertices[k]);
    }
    const float reachCap = kReachCapOfScene * glm::length(hi - lo);
    tbb::parallel_for(size_t(0), triangles.size(), [&](size_t k) {
        const uint32_t t = triangles[k];
        const vec3* v = scene.vertices + 3 * size_t(t);
        const vec3 cross = windingCross(scene, t);
        const float area2 = glm::length(cross);
        if (!(area2 > 0.0f)) return;
        const vec3 n = cross / area2;
        Pcg32 rng = Pcg32::forItem(t, 0, 0x51de);
        const SideView front = lookFrom(bvh, scene, v, n, rng, scene.materialIds[t], reachCap);
        const SideView back = lookFrom(bvh, scene, v, -n, rng, scene.materialIds[t], reachCap);
        // Never a side inside a closed solid: one whose rays mostly meet its own material from
        // behind (a block's faces seen from within), or whose every ray meets something from
        // behind and that faces no open space (the sealed gap under a floor slab in a wall
        // shell). Counting any material alone would also seal a room whose walls were wound
        // outward: from within it looks the same, but people stand in it.
        auto enclosed = [&](const SideView& side, const vec3& normal) {
            return 2 * side.behindOwn > kSideRays ||
                   (side.behind == kSideRays && (space.empty() || openPoints(space, bvh, v, normal) == 0));
        };
        const bool frontEnclosed = enclosed(front, n), backEnclosed = enclosed(back, -n);
        // Four lookout points stand for the whole triangle: a tall wall triangle whose points
        // all lie behind a panel hung on it looked sealed on the room's side, and the strip of
        // it the room sees above the panel showed the sunlit outer face. Such a triangle's
        // samples are tested one by one when the other side sees outdoors.
        if (backEnclosed) {
            if (!frontEnclosed && front.open >= kClearlyFewer && !space.empty()) choice[t] = kKeepUnlessBackOpen;
            return;
        }
        if (frontEnclosed && back.open >= kClearlyFewer && !space.empty()) {
            choice[t] = kTurnUnlessFrontOpen;
            return;
        }
        const bool skyDecides = std::abs(back.open - front.open) >= kClearlyFewer;
        if (frontEnclosed || back.open + kClearlyFewer <= front.open ||
            (!skyDecides && front.reach < kMuchNearer * back.reach))
            choice[t] = kTurn;
    });
    size_t turned = 0, tested = 0;
    for (uint32_t t : triangles) {
        turned += choice[t] == kTurn || choice[t] == kTurnUnlessFrontOpen;
        tested += choice[t] != kKeepFront;
    }
    if (tested == 0) return 0;
    tbb::parallel_for(size_t(0), samples.samples.size(), [&](size_t k) {
        SurfaceSample& s = samples.samples[k];
        if (s.triangle >= scene.triangleCount) return;
        const uint8_t c = choice[s.triangle];
        if (c == kKeepFront) return;
        bool turn = c == kTurn;
        if (c == kTurnUnlessFrontOpen || c == kKeepUnlessBackOpen) {
            const vec3 n = glm::normalize(windingCross(scene, s.triangle));
            turn = c == kTurnUnlessFrontOpen ? !facesOpenSpace(space, bvh, s.position, n)
                                             : facesOpenSpace(space, bvh, s.position, -n);
        }
        if (turn) s.normal = -s.normal;
    });
    return turned;
}

}  // namespace vl
