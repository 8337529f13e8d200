// The voxel direct-lighting kernel, written once for the TBB pass (lighting.cpp) and a CUDA
// launcher: plain structs, plain pointers and the NanoVDB index grid, no allocation.
//
// Positions here are in index space (voxel units): voxel (i, j, k) is centred at (i, j, k)
// and spans [i − ½, i + ½] on each axis. Distances for attenuation are converted to metres.
//
// Visibility steps through the voxels' opacity (ERRATA eq. 17), with two rules that keep a
// surface from shadowing itself, and leaps empty nodes without changing a bit of the result:
// "Visibility stepping" below says how.
#pragma once

#include "core/hostdev.h"
#include "core/math.h"
#include "core/polygon_irradiance.h"
#include "core/sampling.h"
#include "voxel/voxel_scene.h"

#include <nanovdb/NanoVDB.h>

#include <cstdint>

namespace vl::lighting {

enum : int { kPointLight = 0, kSpotLight = 1, kDirectionalLight = 2 };
enum : int { kWeightLambert = 0, kWeightVillegas = 1, kWeightSixAxis = 2 };

// Start of a visibility ray beyond the voxel's own box, in voxels (keeps the start point off
// the face itself, where rounding would pick either neighbour).
constexpr float kStartEpsilon = 1e-3f;
// Tolerance on the surface-layer tests (voxel units), far below any lattice spacing.
constexpr float kLayerTolerance = 1e-4f;
// Direction components below this are treated as zero: the ray never crosses that axis.
constexpr float kParallel = 1e-20f;

struct KernelLight {
    int type = kPointLight;
    int paperAttenuation = 0;  // 0: glTF physical; 1: eq. (18) with kc, kl, kq
    vec3 position{0.0f};       // index space
    vec3 direction{0.0f, 0.0f, -1.0f};  // unit, the way the light travels
    vec3 intensity{0.0f};      // colour × intensity: W/sr (point, spot), W/m² (directional)
    float range = 0.0f;        // metres; 0 = infinite
    float spotScale = 0.0f;    // KHR_lights_punctual lightAngleScale
    float spotOffset = 0.0f;   // KHR_lights_punctual lightAngleOffset
    float kc = 0.0f, kl = 0.0f, kq = 1.0f;
    float cosHalfAngle = 1.0f;  // directional: its disk (scene.h angularDiameter); 1 = one direction
};

// Emissive triangles are shaded in patches: a quad split along its diagonal (two triangles
// of one uniform emitter, in one plane, sharing an edge) is one patch whose visibility
// samples cover both, so a quad light costs one visibility ray per stratum, not two; any
// other triangle is a patch of its own. A patch's first triangle holds `patchSize` (1 or
// 2); the second has patchSize 0.
//
// A uniform patch's n × n strata are jittered per voxel (uniformPatchSample): every voxel
// sees the penumbra through points of its own, so what the few points miss is noise from
// voxel to voxel, which the bounces' gathers average, and not the hard shadow of one fixed
// point shared by every voxel. With the points fixed per triangle, a quad light sampled
// once per patch is a point light for the bounces (docs/decisions.md, "Emitter strata"). A
// textured patch keeps its fixed samples (emitterSamples), where its texture was read.
struct EmitterTriangle {
    vec3 v0{0.0f}, v1{0.0f}, v2{0.0f};  // index space
    vec3 normal{0.0f, 0.0f, 1.0f};      // unit, front face (counter-clockwise)
    vec3 radiance{0.0f};                // Le where `uniform`
    float area = 0.0f;                  // m²
    int uniform = 1;                    // 0: textured emission, sampled only
    int doubleSided = 0;
    uint32_t patchSize = 1;
    uint32_t firstSample = 0;           // textured patches: their fixed samples
    uint32_t sampleCount = 0;
};

struct EmitterSample {
    vec3 position{0.0f};  // index space
    vec3 power{0.0f};     // Le × the sample's share of the triangle's area (W/sr)
};

struct KernelStats {
    uint64_t evaluations = 0;
    uint64_t steps = 0;
};

using IndexGrid = nanovdb::NanoGrid<int32_t>;
using IndexAccessor = IndexGrid::AccessorType;

// Everything the kernel reads, as plain pointers (host or device memory alike).
struct LightingView {
    const IndexGrid* grid = nullptr;   // voxel coordinate → channel index, −1 in the background
    const ivec3* coords = nullptr;
    const vec3* albedo = nullptr;
    const vec3* normal = nullptr;
    const float* axisWeights = nullptr;  // 6 per voxel: +X, −X, +Y, −Y, +Z, −Z
    const float* opacity = nullptr;
    const uint8_t* solid = nullptr;
    const vec3* surfaceOffset = nullptr;  // per voxel (voxel_scene.h); null: the centres
    ivec3 boundsMin{0};  // inclusive bounds of the active voxels
    ivec3 boundsMax{-1};
    float voxelSize = 1.0f;  // metres
    const KernelLight* lights = nullptr;
    uint32_t lightCount = 0;
    const EmitterTriangle* emitters = nullptr;
    uint32_t emitterCount = 0;
    const EmitterSample* emitterSamples = nullptr;
    int emitterStrata = 1;  // n: n × n points per uniform patch and voxel
    int normalWeighting = kWeightLambert;
    int visibility = 1;
};

VL_HOSTDEV inline float normL1(const vec3& v) { return glm::abs(v.x) + glm::abs(v.y) + glm::abs(v.z); }

// ---------------------------------------------------------------------------------------
// Normal weights, per surface side (voxel_scene.h voxelSides): a voxel's faces are grouped
// into the sides of the surface they show, each side with one unit normal n_s. A side
// weighs incoming light by one of:
//   lambert   max(n_s·L, 0);
//   villegas  Σ_a n_s,a²·max(sign(n_s,a)·L_a, 0) (Villegas 2016 on the side's normal);
//   six-axis  Σ_{f in side} w_f·max(d_f·L, 0) / Σ_{f in side} w_f (the side's own faces).
// All three agree on an axis-aligned flat surface; where normals cancel every face is a side
// of its own with n_s = d_f and all three are max(d_f·L, 0). Lambert is exact for a flat
// surface of any orientation; six-axis conserves the light a 90° corner of axis-aligned
// faces receives in total (the mean normal at 45° overstates it by up to √2) but understates
// a tilted plane (by 1/‖n‖₁, 29 % at 45°).

struct NormalWeight {
    float cosine = 0.0f;
    vec3 litNormal{0.0f};  // unit normal the visibility ray leaves along; zero when cosine is 0
};

// `side` is the side's unit normal, `faces` the voxel's six axis weights, `inSide` which of
// them belong to the side (bit f), `L` the unit direction toward the light.
VL_HOSTDEV inline NormalWeight sideWeight(int mode, const vec3& side, const float* faces, unsigned inSide,
                                          const vec3& L) {
    NormalWeight result;
    vec3 litFaces(0.0f);  // the lit faces' weighted directions, for the lit-side normal
    float cosine = 0.0f;
    if (mode == kWeightLambert) {
        cosine = glm::max(glm::dot(side, L), 0.0f);
    } else if (mode == kWeightVillegas) {
        for (int a = 0; a < 3; ++a) {
            if (side[a] == 0.0f) continue;
            const float sign = side[a] > 0.0f ? 1.0f : -1.0f;
            const float facing = glm::max(sign * L[a], 0.0f);
            const float weight = side[a] * side[a];
            cosine += weight * facing;
            if (facing > 0.0f) litFaces[a] += weight * sign;
        }
    } else {
        float total = 0.0f;
        float sum = 0.0f;
        for (int f = 0; f < 6; ++f) {
            if (!((inSide >> f) & 1u)) continue;
            const int axis = f >> 1;
            const float sign = (f & 1) ? -1.0f : 1.0f;
            const float facing = glm::max(sign * L[axis], 0.0f);
            total += faces[f];
            sum += faces[f] * facing;
            if (facing > 0.0f) litFaces[axis] += faces[f] * sign;
        }
        cosine = total > 0.0f ? sum / total : 0.0f;
    }
    if (!(cosine > 0.0f)) return result;
    // The side's normal when it faces the light (at a corner it keeps both faces' neighbours
    // in the surface layer); otherwise the faces that do see the light (a corner lit from
    // one face's side only).
    const vec3 lit = glm::dot(side, L) > 0.0f ? side : litFaces;
    const float litLength = glm::length(lit);
    if (!(litLength > 0.0f)) return result;
    result.cosine = glm::min(cosine, 1.0f);
    result.litNormal = lit / litLength;
    return result;
}

// Whether the side's weight can be non-zero toward the (unnormalised) direction d: it is
// zero exactly when none of these linear tests is positive, so three vertices decide it for
// a whole triangle.
VL_HOSTDEV inline bool sideSees(int mode, const vec3& side, const float* faces, unsigned inSide, const vec3& d) {
    if (mode == kWeightLambert) return glm::dot(side, d) > 0.0f;
    if (mode == kWeightVillegas) {
        for (int a = 0; a < 3; ++a)
            if ((side[a] > 0.0f && d[a] > 0.0f) || (side[a] < 0.0f && d[a] < 0.0f)) return true;
        return false;
    }
    for (int f = 0; f < 6; ++f) {
        const float sign = (f & 1) ? -1.0f : 1.0f;
        if (((inSide >> f) & 1u) && faces[f] > 0.0f && sign * d[f >> 1] > 0.0f) return true;
    }
    return false;
}

// Unshadowed irradiance per unit radiance that a side receives from a triangle (vertices
// relative to the receiver): the side's weight integrated over the triangle's solid angle,
// in closed form (Lambert's polygon formula, core/polygon_irradiance.h). Each weighting is a
// sum of clamped cosines: lambert max(n_s·ω, 0); villegas Σ_a n_s,a²·max(±e_a·ω, 0); six-axis
// Σ_f w_f·max(d_f·ω, 0) / Σ_f w_f; and ∫ max(d·ω, 0) dω over the triangle is its irradiance
// on a plane of normal d.
VL_HOSTDEV inline float sideTriangleIrradiance(int mode, const vec3& side, const float* faces, unsigned inSide,
                                               const vec3 (&relative)[3]) {
    if (mode == kWeightLambert) return clippedTriangleIrradiance(relative, side);
    float sum = 0.0f, total = 0.0f;
    for (int f = 0; f < 6; ++f) {
        const int axis = f >> 1;
        const float sign = (f & 1) ? -1.0f : 1.0f;
        float weight;
        if (mode == kWeightVillegas) {
            weight = side[axis] * sign > 0.0f ? side[axis] * side[axis] : 0.0f;
        } else {
            weight = ((inSide >> f) & 1u) ? faces[f] : 0.0f;
            total += weight;
        }
        if (!(weight > 0.0f)) continue;
        vec3 d(0.0f);
        d[axis] = sign;
        sum += weight * clippedTriangleIrradiance(relative, d);
    }
    if (mode == kWeightVillegas) return sum;
    return total > 0.0f ? sum / total : 0.0f;
}

// ---------------------------------------------------------------------------------------
// Attenuation: irradiance at the receiver from a punctual light, before the normal weight
// and visibility. `L` points from the receiver to the light; `distance` in metres.

VL_HOSTDEV inline float spotFactor(const KernelLight& light, const vec3& L) {
    if (light.type != kSpotLight) return 1.0f;
    const float cd = glm::dot(light.direction, -L);
    const float a = glm::clamp(cd * light.spotScale + light.spotOffset, 0.0f, 1.0f);
    return a * a;
}

VL_HOSTDEV inline vec3 punctualIrradiance(const KernelLight& light, const vec3& L, float distance, float minDistance) {
    if (light.type == kDirectionalLight) return light.intensity;
    const float r = glm::max(distance, minDistance);
    float falloff;
    if (light.paperAttenuation) {
        falloff = 1.0f / (light.kc + light.kl * r + light.kq * r * r);
    } else {
        float window = 1.0f;
        if (light.range > 0.0f) {
            const float q = r / light.range;
            window = glm::max(glm::min(1.0f - q * q * q * q, 1.0f), 0.0f);
        }
        falloff = window / (r * r);
    }
    return light.intensity * (falloff * spotFactor(light, L));
}

// ---------------------------------------------------------------------------------------
// Visibility stepping.
//
// Visibility (ERRATA eq. 17). A ray leaves the receiving voxel toward the light and visits,
// in order, every voxel it passes through (Amanatides–Woo). Each visited occupied voxel k
// adds w_k·α_k·(1 − V) with w_k = min(1, 1/(i·d)), where i·d is the distance along the ray
// from the receiver's centre to the voxel's centre (the projection; exactly i for a ray
// along an axis, i·√2 along a face diagonal), and a solid voxel makes V = 1. The voxel that
// holds the light's end point is not between receiver and light and is never visited.
//
// Self-occlusion. A voxel averages the surface inside it, and the voxels of the same surface
// lie beside it, so a ray from the centre toward a grazing light would cross its own
// surface's neighbours. Two rules keep a surface from shadowing itself:
//  * the ray starts off the voxel's own box, at c + (½‖n‖₁ + ε)·n along the unit lit-side
//    normal n (for a floor, on the top face: it then lives in the layer above and cannot pass
//    under a wall standing on that floor);
//  * a voxel whose centre lies less than ‖n‖₁ above the receiver's centre along n belongs to
//    the receiver's surface layer (the voxels a plane through the receiver can touch) and
//    does not occlude it. For an axis-aligned plane that is exactly its own layer; the layer
//    above (height 1) does occlude.
// The emitter end of a ray to an emissive-triangle sample is treated alike: voxels whose
// centres lie within ½‖n_e‖₁ of the emitter's plane on its front are the emitter's own
// surface. An emitter sample inside the receiver's surface layer itself (less than ‖n‖₁
// above its centre) is not light the receiver shows: an emitter that close lies against the
// surface and covers the part it would light (a ceiling light mounted flat under the
// ceiling, its back face lighting the ceiling it hides), and the voxels that hold both show
// the emitter's side, not the hidden ceiling. Lit anyway, the ceiling above a double-sided
// quad light glows through the light's voxels and lights the floor where the path tracer
// has nothing (docs/decisions.md, "Voxel self-occlusion").
//
// Empty-space skipping (HDDA). The DDA's state is only the integer voxel coordinate; every
// plane-crossing time is computed from it afresh, never accumulated. Leaping an empty NanoVDB
// node (no leaf there) therefore lands on exactly the voxel the one-voxel DDA would reach
// when it leaves that node (the merge of the three axes' crossing sequences is solved
// directly), so both traversals visit the same active voxels in the same order and give the
// same bits. nanovdb::HDDA accumulates its crossing times and nudges them forward by an
// epsilon, which breaks that agreement at voxel edges and corners; this is its hierarchical
// idea over the same tree (ReadAccessor::getDim), made exact.

struct RayEnd {
    vec3 point{0.0f};
    vec3 normal{0.0f};     // unit, facing the receiver; zero: no surface at the end
    float layer = -1.0f;   // voxels with centre height ≤ layer above `point` belong to it
};

class VoxelWalk {
public:
    VL_HOSTDEV VoxelWalk(const vec3& origin, const vec3& dir) : origin_(origin) {
        for (int a = 0; a < 3; ++a) {
            step_[a] = dir[a] > kParallel ? 1 : (dir[a] < -kParallel ? -1 : 0);
            inverse_[a] = step_[a] != 0 ? 1.0f / dir[a] : 0.0f;
            half_[a] = 0.5f * static_cast<float>(step_[a]);
        }
    }

    // Time at which the ray leaves, along `axis`, a voxel with coordinate c on that axis.
    VL_HOSTDEV float exitTime(int axis, int c) const {
        if (step_[axis] == 0) return kInfinity;
        return ((static_cast<float>(c) + half_[axis]) - origin_[axis]) * inverse_[axis];
    }

    // The axis the ray leaves voxel c through (ties: the lowest axis), and when.
    VL_HOSTDEV int exitAxis(const ivec3& c, float& time) const {
        const float t0 = exitTime(0, c.x), t1 = exitTime(1, c.y), t2 = exitTime(2, c.z);
        int axis = 0;
        time = t0;
        if (t1 < time) { axis = 1; time = t1; }
        if (t2 < time) { axis = 2; time = t2; }
        return axis;
    }

    // Leaps the box [lo, lo + size − 1]³ holding c, which is known to be empty. Sets c to the
    // first voxel after the box that the one-voxel walk reaches, and returns the time it
    // leaves the box. The walk's crossings are the merge, by (time, axis), of each axis's
    // increasing crossing times; the box is left at the first crossing past its far face, and
    // on every other axis the walk has taken exactly the crossings that come before it.
    VL_HOSTDEV float leapBox(ivec3& c, int size) const {
        int last[3];
        float leave[3];
        for (int a = 0; a < 3; ++a) {
            const int lo = c[a] & ~(size - 1);
            last[a] = step_[a] > 0 ? lo + size - 1 : lo;
            leave[a] = exitTime(a, last[a]);
        }
        int exit = 0;
        if (leave[1] < leave[exit]) exit = 1;
        if (leave[2] < leave[exit]) exit = 2;
        const float time = leave[exit];
        for (int a = 0; a < 3; ++a) {
            if (a == exit || step_[a] == 0) continue;
            c[a] = firstCrossingNotBefore(a, c[a], last[a], time, exit);
        }
        c[exit] = last[exit] + step_[exit];
        return time;
    }

    VL_HOSTDEV int step(int axis) const { return step_[axis]; }

private:
    VL_HOSTDEV bool crossesBefore(int axis, int c, float time, int exitAxis) const {
        const float t = exitTime(axis, c);
        return t < time || (t == time && axis < exitAxis);
    }

    // The coordinate along `axis` at time `time`: the first c in [from, last] (walk order)
    // whose crossing does not come before the exit crossing.
    VL_HOSTDEV int firstCrossingNotBefore(int axis, int from, int last, float time, int exitAxis) const {
        const int s = step_[axis];
        const float lowF = static_cast<float>(s > 0 ? from : last);
        const float highF = static_cast<float>(s > 0 ? last : from);
        const float guessF = glm::clamp(glm::floor(time / inverse_[axis] + origin_[axis] + 0.5f), lowF, highF);
        int c = static_cast<int>(guessF);
        while (c != last && crossesBefore(axis, c, time, exitAxis)) c += s;
        while (c != from && !crossesBefore(axis, c - s, time, exitAxis)) c -= s;
        return c;
    }

    vec3 origin_;
    vec3 inverse_;
    vec3 half_;
    int step_[3];
};

// V along the ray origin + t·dir, t in [0, tEnd) (index space, dir unit). `receiver` is the
// receiving voxel's centre and `litNormal` its unit lit-side normal (the surface layer).
template <bool Hierarchical>
VL_HOSTDEV inline float occlusionAlongRay(const LightingView& view, IndexAccessor& accessor, const vec3& receiver,
                                          const vec3& litNormal, const vec3& origin, const vec3& dir, float tEnd,
                                          const RayEnd& end, uint64_t& steps) {
    const VoxelWalk walk(origin, dir);
    const float receiverLayer = normL1(litNormal) - kLayerTolerance;
    const float endLayer = end.layer + kLayerTolerance;
    ivec3 c(static_cast<int>(glm::floor(origin.x + 0.5f)), static_cast<int>(glm::floor(origin.y + 0.5f)),
            static_cast<int>(glm::floor(origin.z + 0.5f)));
    float V = 0.0f;
    for (;;) {
        bool past = false;
        for (int a = 0; a < 3; ++a) {
            const int s = walk.step(a);
            past = past || (c[a] > view.boundsMax[a] && s >= 0) || (c[a] < view.boundsMin[a] && s <= 0);
        }
        if (past) break;
        float tExit;
        const int axis = walk.exitAxis(c, tExit);
        if (!(tExit < tEnd)) break;  // this voxel holds the end point
        const nanovdb::Coord ijk(c.x, c.y, c.z);
        ++steps;
        int32_t index;
        if (Hierarchical) {
            // One lookup per step: inside a leaf read it there; outside every leaf the node
            // or tile around c is empty (the index grid has no active tiles): leap it.
            const auto* leaf = accessor.probeLeaf(ijk);
            if (leaf) {
                index = leaf->getValue(ijk);
            } else {
                const uint32_t dim = accessor.getDim(ijk, 0);
                if (dim > 1 && !accessor.isActive(ijk)) {
                    if (!(walk.leapBox(c, static_cast<int>(dim)) < tEnd)) break;
                    continue;
                }
                index = accessor.getValue(ijk);
            }
        } else {
            index = accessor.getValue(ijk);
        }
        if (index >= 0) {
            const vec3 centre(c);
            const vec3 fromReceiver = centre - receiver;
            const bool ownSurface = glm::dot(litNormal, fromReceiver) < receiverLayer;
            const bool endSurface = end.layer >= 0.0f && glm::dot(end.normal, centre - end.point) <= endLayer;
            if (!ownSurface && !endSurface) {
                if (view.solid[index]) return 1.0f;
                const float alpha = glm::clamp(view.opacity[index], 0.0f, 1.0f);
                const float distance = glm::dot(fromReceiver, dir);
                const float weight = distance > 1.0f ? 1.0f / distance : 1.0f;
                V += weight * alpha * (1.0f - V);
                if (V >= 1.0f) return 1.0f;
            }
        }
        c[axis] += walk.step(axis);
    }
    return V;
}

// V for a ray from the receiving voxel toward `target` (index space; tEnd = infinity for a
// directional light, where `target` is unused and `towardLight` is the direction).
template <bool Hierarchical>
VL_HOSTDEV inline float visibilityLoss(const LightingView& view, IndexAccessor& accessor, const vec3& receiver,
                                       const vec3& litNormal, const vec3& towardLight, const vec3& target,
                                       bool toInfinity, const RayEnd& end, uint64_t& steps) {
    const vec3 origin = receiver + (0.5f * normL1(litNormal) + kStartEpsilon) * litNormal;
    if (toInfinity)
        return occlusionAlongRay<Hierarchical>(view, accessor, receiver, litNormal, origin, towardLight, kInfinity, end,
                                               steps);
    const vec3 segment = target - origin;
    const float length = glm::length(segment);
    // A light between the receiver's centre and the start point has nothing in front of it.
    if (!(length > 1e-6f) || glm::dot(segment, litNormal) <= 0.0f) return 0.0f;
    return occlusionAlongRay<Hierarchical>(view, accessor, receiver, litNormal, origin, segment / length, length, end,
                                           steps);
}

// A uniform patch's points for one voxel are jittered by a generator of the voxel's own,
// seeded (voxelInPatchFrame) by where the voxel lies in the patch's own frame (its first
// triangle's first edge, the normal), rounded to half voxels, not by the voxel's index or grid
// coordinate: a scene turned a quarter turn, moved or scaled then lights each voxel through
// the same points (seeded by the index, a quarter turn moves the bake: docs/decisions.md,
// "The scene's own frame"). Two voxel centres differ by at least 1/√3 > ½ along some axis of
// any frame, so no two voxels share a seed. The salt is the textured emitters' fixed
// samples' too (lighting.cpp).
constexpr uint64_t kEmitterJitterSalt = 0x4C49474854ull;  // "LIGHT"

VL_HOSTDEV inline uint64_t voxelInPatchFrame(const EmitterTriangle& first, const vec3& voxel) {
    const vec3 u = glm::normalize(first.v1 - first.v0);
    const vec3 v = glm::cross(first.normal, u);
    const vec3 d = voxel - first.v0;
    const auto whole = [](float x) {
        return static_cast<uint64_t>(static_cast<int64_t>(glm::floor(2.0f * x + 0.5f))) & 0x1FFFFFu;
    };
    return whole(glm::dot(d, u)) | whole(glm::dot(d, v)) << 21 | whole(glm::dot(d, first.normal)) << 42;
}

// Stratum k of a uniform patch's n × n for the voxel whose seed is `seed`: its x chooses the
// patch's triangle by area, mapped area-preservingly onto it. The power is Le × the
// stratum's share of the patch's area (W/sr).
VL_HOSTDEV inline EmitterSample uniformPatchSample(const EmitterTriangle* patch, int strata, uint32_t k, uint64_t seed,
                                                   uint32_t patchIndex) {
    vec2 u = jitteredStratum(seed, patchIndex, strata, int(k % uint32_t(strata)), int(k / uint32_t(strata)),
                             kEmitterJitterSalt);
    const float area = patch[0].patchSize == 2 ? patch[0].area + patch[1].area : patch[0].area;
    int t = 0;
    if (patch[0].patchSize == 2) {
        const float firstShare = patch[0].area / area;
        t = u.x < firstShare ? 0 : 1;
        u.x = glm::clamp(t == 0 ? u.x / firstShare : (u.x - firstShare) / (1.0f - firstShare), 0.0f, 1.0f);
    }
    const vec2 b = sampleUniformTriangle(u);
    EmitterSample sample;
    sample.position = (1.0f - b.x - b.y) * patch[t].v0 + b.x * patch[t].v1 + b.y * patch[t].v2;
    sample.power = patch[0].radiance * (area / static_cast<float>(strata * strata));
    return sample;
}

// ---------------------------------------------------------------------------------------
// One voxel, all lights: every surface side of the voxel (voxelSides) is lit on its own, with
// one visibility ray per light and lit side, and every face shows its side's radiance.

struct VoxelLighting {
    vec3 radiance{0.0f};          // faceWeightedMean of the faces (voxel_scene.h)
    vec3 faceRadiance[6] = {};    // +X, −X, +Y, −Y, +Z, −Z; zero for a face without surface
    float occlusion = 0.0f;       // mean V over the lights (and lit sides) that reach the voxel
};

template <bool Hierarchical>
VL_HOSTDEV inline VoxelLighting shadeVoxel(const LightingView& view, IndexAccessor& accessor, uint32_t i,
                                           KernelStats& stats) {
    // Light arrives at the surface inside the voxel, not at its centre, which can lie half a
    // voxel off it (under a light a few voxels away that is a few percent of 1/r²);
    // visibility still walks from the centre, where the self-occlusion rules are set.
    const vec3 receiver(view.coords[i]);
    const vec3 surface = view.surfaceOffset ? receiver + view.surfaceOffset[i] : receiver;
    const float* faces = view.axisWeights + 6 * static_cast<size_t>(i);
    const VoxelSides sides = voxelSides(view.normal[i], faces);
    unsigned inSide[6] = {0u, 0u, 0u, 0u, 0u, 0u};
    for (int f = 0; f < 6; ++f)
        if (sides.sideOfFace[f] >= 0) inSide[sides.sideOfFace[f]] |= 1u << f;
    const int mode = view.normalWeighting;
    const float h = view.voxelSize;
    const float minDistance = 0.5f * h;
    vec3 irradiance[6] = {vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f)};
    float occlusionSum = 0.0f;
    uint32_t lightsReaching = 0;

    for (uint32_t l = 0; l < view.lightCount; ++l) {
        const KernelLight& light = view.lights[l];
        vec3 L;
        float distance = 0.0f;
        if (light.type == kDirectionalLight) {
            L = -light.direction;
            if (light.cosHalfAngle < 1.0f) {
                // A sun's disk: one direction of its cone per voxel, jittered by the voxel's
                // own generator; the bounces' gathers average the penumbrae that makes.
                const ivec3 c = view.coords[i];
                const uint64_t key = (uint64_t(uint32_t(c.x)) << 42) ^ (uint64_t(uint32_t(c.y)) << 21) ^ uint64_t(uint32_t(c.z));
                const vec2 u = jitteredStratum(key, l, 1, 0, 0, 0x53554Eu);  // "SUN"
                L = coneDirectionAbout(L, light.cosHalfAngle, sampleConcentricDisk(u));
            }
        } else {
            const vec3 toLight = light.position - surface;
            const float d = glm::length(toLight);
            if (!(d > 1e-6f)) continue;  // the light sits on the surface point: no direction
            L = toLight / d;
            distance = d * h;
        }
        const vec3 E = punctualIrradiance(light, L, distance, minDistance);
        if (!(maxComponent(E) > 0.0f)) continue;
        float loss = 0.0f;
        int sidesLit = 0;
        for (int s = 0; s < sides.count; ++s) {
            const NormalWeight w = sideWeight(mode, sides.normal[s], faces, inSide[s], L);
            if (!(w.cosine > 0.0f)) continue;
            float V = 0.0f;
            if (view.visibility)
                V = visibilityLoss<Hierarchical>(view, accessor, receiver, w.litNormal, L, light.position,
                                                 light.type == kDirectionalLight, RayEnd{}, stats.steps);
            irradiance[s] += E * (w.cosine * (1.0f - V));
            loss += V;
            ++sidesLit;
        }
        if (sidesLit == 0) continue;
        ++stats.evaluations;
        occlusionSum += loss / static_cast<float>(sidesLit);
        ++lightsReaching;
    }

    for (uint32_t e = 0; e < view.emitterCount; ++e) {
        const EmitterTriangle& tri = view.emitters[e];
        if (tri.patchSize == 0) continue;  // shaded with its patch's first triangle
        const EmitterTriangle* patch = view.emitters + e;
        // Behind the emitter (or in its plane): no sample can reach the voxel's surface point.
        const float facingEmitter = glm::dot(tri.normal, surface - tri.v0);
        if (facingEmitter == 0.0f || (facingEmitter < 0.0f && !tri.doubleSided)) continue;
        // Behind every side of the voxel.
        bool seen = false;
        for (uint32_t t = 0; t < tri.patchSize && !seen; ++t)
            for (int s = 0; s < sides.count && !seen; ++s)
                seen = sideSees(mode, sides.normal[s], faces, inSide[s], patch[t].v0 - surface) ||
                       sideSees(mode, sides.normal[s], faces, inSide[s], patch[t].v1 - surface) ||
                       sideSees(mode, sides.normal[s], faces, inSide[s], patch[t].v2 - surface);
        if (!seen) continue;
        const vec3 frontNormal = facingEmitter > 0.0f ? tri.normal : -tri.normal;
        const float emitterLayer = 0.5f * normL1(tri.normal);
        float triangleLoss = 0.0f;
        uint32_t samplesReaching = 0;
        // Per side: the samples' unshadowed and visible sums (the ratio estimator's weights).
        float unshadowed[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
        vec3 visible[6] = {vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f)};
        const uint32_t sampleCount = tri.uniform ? uint32_t(view.emitterStrata * view.emitterStrata) : tri.sampleCount;
        const uint64_t patchSeed = tri.uniform ? voxelInPatchFrame(tri, receiver) : 0;
        for (uint32_t k = 0; k < sampleCount; ++k) {
            const EmitterSample sample = tri.uniform ? uniformPatchSample(patch, view.emitterStrata, k, patchSeed, e)
                                                     : view.emitterSamples[tri.firstSample + k];
            const vec3 toSample = sample.position - surface;
            const float d = glm::length(toSample);
            if (!(d > 1e-6f)) continue;
            const vec3 L = toSample / d;
            const float cosEmitter = -glm::dot(frontNormal, L);
            if (!(cosEmitter > 0.0f)) continue;
            const float r = glm::max(d * h, minDistance);
            const vec3 E = sample.power * (cosEmitter / (r * r));
            if (!(maxComponent(E) > 0.0f)) continue;
            float loss = 0.0f;
            int sidesLit = 0;
            for (int s = 0; s < sides.count; ++s) {
                const NormalWeight w = sideWeight(mode, sides.normal[s], faces, inSide[s], L);
                if (!(w.cosine > 0.0f)) continue;
                float V = 0.0f;
                if (view.visibility &&
                    glm::dot(w.litNormal, sample.position - receiver) < normL1(w.litNormal) - kLayerTolerance) {
                    V = 1.0f;  // the emitter lies in the receiver's surface layer: see "Visibility stepping"
                } else if (view.visibility) {
                    RayEnd end;
                    end.point = sample.position;
                    end.normal = frontNormal;
                    end.layer = emitterLayer;
                    V = visibilityLoss<Hierarchical>(view, accessor, receiver, w.litNormal, L, sample.position, false,
                                                     end, stats.steps);
                }
                const vec3 e = E * w.cosine;
                unshadowed[s] += e.x + e.y + e.z;
                visible[s] += e * (1.0f - V);
                loss += V;
                ++sidesLit;
            }
            if (sidesLit == 0) continue;
            ++stats.evaluations;
            triangleLoss += loss / static_cast<float>(sidesLit);
            ++samplesReaching;
        }
        // A uniform emitter: its exact unshadowed irradiance times the fraction of the
        // samples' contribution that arrives unshadowed. Fully lit or fully shadowed sides
        // are then exact; only penumbrae carry the samples' error (lighting/direct_light.h does
        // the same at the receivers). A textured emitter keeps the plain stratified sum.
        for (int s = 0; s < sides.count; ++s) {
            if (!tri.uniform) {
                irradiance[s] += visible[s];
                continue;
            }
            if (!(unshadowed[s] > 0.0f)) continue;  // no sample above the side's horizon: a grazing sliver
            const float visibleFraction = (visible[s].x + visible[s].y + visible[s].z) / unshadowed[s];
            float unshadowedPatch = 0.0f;
            for (uint32_t t = 0; t < tri.patchSize; ++t) {
                const vec3 relative[3] = {patch[t].v0 - surface, patch[t].v1 - surface, patch[t].v2 - surface};
                unshadowedPatch += sideTriangleIrradiance(mode, sides.normal[s], faces, inSide[s], relative);
            }
            irradiance[s] += tri.radiance * (unshadowedPatch * visibleFraction);
        }
        if (samplesReaching > 0) {
            occlusionSum += triangleLoss / static_cast<float>(samplesReaching);
            ++lightsReaching;
        }
    }

    VoxelLighting result;
    const vec3 reflectance = view.albedo[i] * kInvPi;
    for (int f = 0; f < 6; ++f) {
        const int s = sides.sideOfFace[f];
        result.faceRadiance[f] = s >= 0 ? reflectance * irradiance[s] : vec3(0.0f);
    }
    result.radiance = faceWeightedMean(result.faceRadiance, faces);
    result.occlusion = lightsReaching > 0 ? occlusionSum / static_cast<float>(lightsReaching) : 0.0f;
    return result;
}

}  // namespace vl::lighting
