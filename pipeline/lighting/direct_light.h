// Exact direct irradiance at a bake receiver, through the BVH (DESIGN.md "Receivers"):
// punctual lights with one shadow ray each; emissive triangles by the ratio estimator
//     E = E_analytic · Σ_j f_j V_j / Σ_j f_j,
// where E_analytic is Lambert's closed form for the triangle (clipped to the receiver's
// hemisphere) and f_j, V_j are the unshadowed contribution and visibility at n × n
// stratified points of the triangle. Where the emitter is fully visible or fully hidden the
// result is exact; only penumbrae carry the stratification's error, and with a fixed seed it
// is deterministic, not noise. Textured emitters (non-uniform radiance) fall back to the
// plain stratified estimate. VL_HOSTDEV so the CUDA bake reuses it.
#pragma once

#include "core/polygon_irradiance.h"
#include "core/sampling.h"
#include "core/shared_edge.h"
#include "trace/materials.h"
#include "trace/path_kernels.h"
#include "trace/surface_samples.h"
#include "trace/trace_scene.h"

namespace vl {

struct DirectLightSettings {
    // n: n × n visibility points per emissive triangle, ⌈n√2⌉² per parallelogram quad (36 at
    // 4, 64 at 5), only in penumbrae. 4: the lowest that keeps the accuracy target at every
    // turn of the scene, for less error² × time than 5 (docs/decisions.md, "Emitter strata").
    int emitterStrata = 4;
    // m: m × m stratified cosine-weighted directions per receiver sample that look for the
    // sky (Scene::sky). 10: the fewest that hold the sky's accuracy target on an open box
    // (docs/decisions.md, "Sky strata").
    int skyStrata = 10;
    // false: the sky is left out here, for receivers that gather it with their indirect light
    // (a lightmap's records, gather/texel_gather.h).
    bool skyAtSamples = true;
    // How many nodes a receiver sample's cut of a tree of many lights takes, per tree
    // (trace/light_tree.h): the nearer and brighter lights alone and exact, the rest sampled.
    // docs/many-lights.md.
    int lightCut = 64;
    // false: the lights an engine draws itself (TraceLight::engineDrawn) are left out, for a
    // lightmap that holds their indirect light alone.
    bool engineDrawnLights = true;
    // false: no punctual light at all, for an irradiance volume's probes, which take them
    // exactly (probes/irradiance_volume.h).
    bool punctualLights = true;
};

// cos θ_r · cos θ_e / d² between a receiver (p; geometric normal ng, shading normal ns) and
// a point q of an emitter whose front faces `towardReceiver`, wi the unit direction to q; 0
// where q lies under either horizon or on p.
VL_HOSTDEV inline float geometricFactor(const vec3& p, const vec3& ng, const vec3& ns, const vec3& q,
                                        const vec3& towardReceiver, vec3& wi) {
    const vec3 d = q - p;
    const float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.0f)) return 0.0f;
    wi = d / glm::sqrt(dist2);
    const float cosR = glm::dot(ns, wi);
    const float cosE = -glm::dot(towardReceiver, wi);
    if (cosR <= 0.0f || cosE <= 0.0f || glm::dot(ng, wi) <= 0.0f) return 0.0f;
    return cosR * cosE / dist2;
}

// Irradiance from emissive triangle `emitter` at receiver (p, ng, ns): ng is the geometric
// normal on the receiving side, ns the shading normal. Stratum (i, j) of the n × n points is
// jittered by its own generator (seed, `stream`·n² + its index).
//
// A uniform emitter is first tested at seven points: its corners and edge midpoints (drawn
// 1% toward the centroid, off the edges it shares with its surroundings) and its centroid.
// Where all seven are seen, or all hidden, it is taken as wholly seen or wholly hidden and
// the strata are not traced: most receivers see an emitter whole or not at all, and a shadow
// edge crossing a triangle leaves test points on both sides of it. Only penumbrae, and
// occluders small enough to hide between the seven points, take the n × n strata: the error of
// tracing every stratum for far fewer shadow rays, where corners and centroid alone miss the
// corners of shadows (docs/decisions.md, "Emitter strata").
VL_HOSTDEV inline vec3 emitterIrradiance(const TraceSceneView& s, const BvhView& bvh, uint32_t emitter, const vec3& p,
                                         const vec3& ng, const vec3& ns, int strata, uint64_t seed, uint64_t stream) {
    const vec3* v = s.vertices + 3 * static_cast<size_t>(emitter);
    const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
    const float twiceArea = glm::length(cross);
    if (!(twiceArea > 0.0f)) return vec3(0.0f);
    const vec3 emitterNormal = cross / twiceArea;
    const TraceMaterial& material = s.materials[s.materialIds[emitter]];
    const float facing = glm::dot(p - v[0], emitterNormal);  // > 0: p sees the front face
    if (facing == 0.0f || (facing < 0.0f && !material.doubleSided)) return vec3(0.0f);

    const vec3 relative[3] = {v[0] - p, v[1] - p, v[2] - p};
    vec3 clipped[4];
    const int clippedCount = clipToHemisphere(relative, 3, ns, clipped);
    if (clippedCount < 3) return vec3(0.0f);
    const vec3 towardReceiver = facing > 0.0f ? emitterNormal : -emitterNormal;
    const bool uniform = material.emissiveTexture.texture < 0;
    const vec3 wholly = material.emission * polygonIrradiance(clipped, clippedCount, ns);

    if (uniform) {
        const vec3 centroid = (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
        const vec3 points[7] = {centroid,
                                v[0] + 0.01f * (centroid - v[0]),
                                v[1] + 0.01f * (centroid - v[1]),
                                v[2] + 0.01f * (centroid - v[2]),
                                0.5f * (v[0] + v[1]) + 0.01f * (centroid - 0.5f * (v[0] + v[1])),
                                0.5f * (v[1] + v[2]) + 0.01f * (centroid - 0.5f * (v[1] + v[2])),
                                0.5f * (v[2] + v[0]) + 0.01f * (centroid - 0.5f * (v[2] + v[0]))};
        int seen = 0, hidden = 0;
        for (const vec3& q : points) {
            const vec3 wi = q - p;
            if (!(glm::dot(ns, wi) > 0.0f && glm::dot(ng, wi) > 0.0f && -glm::dot(towardReceiver, wi) > 0.0f)) continue;
            if (occluded(bvh, p, ng, q, towardReceiver))
                ++hidden;
            else
                ++seen;
        }
        if (seen == 7) return wholly;
        if (hidden == 7) return vec3(0.0f);
    }

    // Stratified points: unshadowed contribution f_j and visibility V_j.
    const float pointArea = 0.5f * twiceArea / static_cast<float>(strata * strata);
    vec3 sampled(0.0f), sampledVisible(0.0f);
    for (int i = 0; i < strata; ++i)
        for (int j = 0; j < strata; ++j) {
            const vec2 b = sampleUniformTriangle(jitteredStratum(seed, stream, strata, i, j, 0xD1EC7u));
            const SurfaceHit point = surfaceAt(s, emitter, b.x, b.y);
            vec3 wi;
            const float g = geometricFactor(p, ng, ns, point.position, towardReceiver, wi);
            if (!(g > 0.0f)) continue;
            const vec3 f = emissionAt(s, point, -wi) * (g * pointArea);
            sampled += f;
            if (!occluded(bvh, p, ng, point.position, towardReceiver)) sampledVisible += f;
        }
    if (!uniform) return sampledVisible;

    const float sampledSum = sampled.x + sampled.y + sampled.z;
    if (!(sampledSum > 0.0f)) return vec3(0.0f);  // no point above the horizon: a sliver at grazing angles
    const float visibleFraction = (sampledVisible.x + sampledVisible.y + sampledVisible.z) / sampledSum;
    return wholly * visibleFraction;
}

// Irradiance from a parallelogram quad of one uniform emitter, emitters `first` and the next
// (TraceSceneView::emitterQuad): the same ratio estimator over the whole quad, whose points
// lie on one m × m grid of square strata, m = ⌈n·√2⌉ (about the 2·n² points its halves
// would take). Two n × n grids warped onto the triangles (sampleUniformTriangle) place their
// strata less evenly than one grid of the quad, and a penumbra's error is what the strata
// leave uneven, so one grid gives less error for about the same points (docs/decisions.md,
// "Emitter strata"). The wholly-seen test takes the quad's corners, edge midpoints and centre
// (9 points for its halves' 14).
VL_HOSTDEV inline vec3 emitterQuadIrradiance(const TraceSceneView& s, const BvhView& bvh, uint32_t first, const vec3& p,
                                             const vec3& ng, const vec3& ns, int strata, uint64_t seed, uint64_t stream) {
    const uint32_t halves[2] = {s.emitters[first], s.emitters[first + 1]};
    const vec3* va = s.vertices + 3 * static_cast<size_t>(halves[0]);
    const vec3* vb = s.vertices + 3 * static_cast<size_t>(halves[1]);
    // The corner of the first half that the second lacks, and the edges to the shared two.
    const int own = sharedEdge(va, vb).ownA;
    const vec3 origin = va[own];
    const vec3 edge1 = va[(own + 1) % 3] - origin, edge2 = va[(own + 2) % 3] - origin;
    const vec3 cross = glm::cross(edge1, edge2);
    const float area = glm::length(cross);
    if (!(area > 0.0f)) return vec3(0.0f);
    const vec3 emitterNormal = cross / area;
    const TraceMaterial& material = s.materials[s.materialIds[halves[0]]];
    const float facing = glm::dot(p - origin, emitterNormal);  // > 0: p sees the front face
    if (facing == 0.0f || (facing < 0.0f && !material.doubleSided)) return vec3(0.0f);

    float unshadowed = 0.0f;
    for (const vec3* v : {va, vb}) {
        const vec3 relative[3] = {v[0] - p, v[1] - p, v[2] - p};
        unshadowed += clippedTriangleIrradiance(relative, ns);
    }
    if (!(unshadowed > 0.0f)) return vec3(0.0f);
    const vec3 wholly = material.emission * unshadowed;
    const vec3 towardReceiver = facing > 0.0f ? emitterNormal : -emitterNormal;

    int seen = 0, hidden = 0;
    for (int i = 0; i < 9; ++i) {
        // Corners, edge midpoints and centre: (0, ½, 1)² drawn 1% toward the centre.
        const float u = 0.5f + 0.99f * (0.5f * float(i % 3) - 0.5f), v = 0.5f + 0.99f * (0.5f * float(i / 3) - 0.5f);
        const vec3 wi = origin + u * edge1 + v * edge2 - p;
        if (!(glm::dot(ns, wi) > 0.0f && glm::dot(ng, wi) > 0.0f && -glm::dot(towardReceiver, wi) > 0.0f)) continue;
        if (occluded(bvh, p, ng, p + wi, towardReceiver))
            ++hidden;
        else
            ++seen;
    }
    if (seen == 9) return wholly;
    if (hidden == 9) return vec3(0.0f);

    const int m = static_cast<int>(glm::ceil(static_cast<float>(strata) * 1.41421356f - 1e-4f));
    float sampled = 0.0f, sampledVisible = 0.0f;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            const vec2 u = jitteredStratum(seed, stream, m, i, j, 0xD1EC7u);
            const vec3 point = origin + u.x * edge1 + u.y * edge2;
            vec3 wi;
            const float f = geometricFactor(p, ng, ns, point, towardReceiver, wi);
            if (!(f > 0.0f)) continue;
            sampled += f;
            if (!occluded(bvh, p, ng, point, towardReceiver)) sampledVisible += f;
        }
    if (!(sampled > 0.0f)) return vec3(0.0f);  // no point above the horizon: a sliver at grazing angles
    return wholly * (sampledVisible / sampled);
}

// One open direction's share of an image sky's irradiance when `cosineRays` cosine-weighted
// directions and `imageDraws` draws from the image both look for it (the balance heuristic):
// L(d)·cos θ / (N_cos·p_cos(d) + N_image·p_image(d)).
VL_HOSTDEV inline vec3 skyShare(const SkySeen& seen, float cosTheta, float cosineRays, float imageDraws) {
    const float pdfs = cosineRays * cosTheta * kInvPi + imageDraws * seen.imagePdf;
    return pdfs > 0.0f ? seen.radiance * (cosTheta / pdfs) : vec3(0.0f);
}

// Whether the sky is seen from p along d: above the geometric surface and unblocked.
VL_HOSTDEV inline bool skyOpenAlong(const BvhView& bvh, const vec3& p, const vec3& ng, const vec3& d) {
    if (!(glm::dot(d, ng) > 0.0f)) return false;
    Ray ray;
    ray.direction = d;
    ray.origin = offsetRayOrigin(p, ng, bvh.extent);
    return !intersectAny(bvh, ray);
}

// The image draws' part of an image sky's irradiance at p: drawsPerAxis² stratified draws
// (seeded by `seed`), each open one adding its share against `cosineRays` cosine directions
// that look for the sky beside them.
VL_HOSTDEV inline vec3 skyImageDrawsIrradiance(const TraceSceneView& s, const BvhView& bvh, const vec3& p,
                                               const vec3& ng, const vec3& ns, int drawsPerAxis, float cosineRays,
                                               uint64_t seed) {
    if (!s.sky.samplable()) return vec3(0.0f);
    const float draws = static_cast<float>(drawsPerAxis * drawsPerAxis);
    vec3 sum(0.0f);
    for (int i = 0; i < drawsPerAxis; ++i)
        for (int j = 0; j < drawsPerAxis; ++j) {
            float pdf = 0.0f;
            vec2 at;
            const vec3 d = sampleSkyImage(s.sky, jitteredStratum(seed, 1, drawsPerAxis, i, j, 0x534B59u), pdf, &at);
            const float cosTheta = glm::dot(ns, d);
            if (pdf > 0.0f && cosTheta > 0.0f && skyOpenAlong(bvh, p, ng, d))
                sum += skyShare({skyRadianceAt(s.sky, at), pdf}, cosTheta, cosineRays, draws);
        }
    return sum;
}

// Irradiance from the sky at a receiver. A uniform sky: π·L_sky times the share of m × m
// stratified cosine-weighted directions about ns (each jittered by its own generator, seed
// and stratum) that leave the scene, above the geometric surface too. The sky is seen in
// every direction nothing blocks, so unlike an emitter there is no closed form to scale:
// this is the plain stratified estimate, exact where the whole hemisphere is open (a floor
// under the sky) or closed. An image sky adds m × m stratified draws from the image
// (sky.h), and both sets count by the balance heuristic (skyShare). A small bright sun in
// the image is found by its own draws, which cosine directions alone would miss or hit by
// chance.
// `tangent`, when given (unit, ⊥ ns), lays the directions out about ns from it (a frame that
// turns with the scene); else orthonormalBasis's.
VL_HOSTDEV inline vec3 skyIrradiance(const TraceSceneView& s, const BvhView& bvh, const vec3& p, const vec3& ng,
                                     const vec3& ns, int strata, uint64_t seed, const vec3* tangent = nullptr) {
    if (!s.sky.present()) return vec3(0.0f);
    const float n = static_cast<float>(strata * strata);
    int seen = 0;
    vec3 sum(0.0f);
    vec3 t, b;
    if (tangent) {
        t = *tangent;
        b = glm::cross(ns, t);
    } else {
        orthonormalBasis(ns, t, b);
    }
    for (int i = 0; i < strata; ++i)
        for (int j = 0; j < strata; ++j) {
            const vec3 local = sampleCosineHemisphere(jitteredStratum(seed, 0, strata, i, j, 0x534B59u));  // "SKY"
            const vec3 d = local.x * t + local.y * b + local.z * ns;
            if (!skyOpenAlong(bvh, p, ng, d)) continue;
            ++seen;
            if (s.sky.hasImage()) sum += skyShare(skySeenAlong(s.sky, d), glm::dot(ns, d), n, s.sky.samplable() ? n : 0.0f);
        }
    if (!s.sky.hasImage()) return s.sky.uniform * (kPi * static_cast<float>(seen) / n);
    sum += skyImageDrawsIrradiance(s, bvh, p, ng, ns, strata, n, seed);
    return isFinite(sum) ? sum : vec3(0.0f);
}

// Irradiance from a directional light with a disk (a sun, TraceLight::cosHalfAngle < 1): the
// mean over its cone of E·cos θ·V. Its centre and eight points of its rim (drawn 1% in) are
// tested first: where all nine see it and the whole cone is above the surface it is exact,
// E·(n·a)·(1 + cos α)/2 (a cone's mean cosine against a plane, a its axis); where none does
// (hidden or under the horizon), 0. Only penumbrae take n × n stratified directions (the
// emitters' n).
VL_HOSTDEV inline vec3 sunIrradiance(const BvhView& bvh, const TraceLight& light, const vec3& p, const vec3& ng,
                                     const vec3& ns, int strata, uint64_t seed, uint32_t lightIndex) {
    const vec3 axis = -light.direction;
    const float sinHalf = glm::sqrt(glm::max(0.0f, 1.0f - light.cosHalfAngle * light.cosHalfAngle));
    int seen = 0, hidden = 0;
    for (int k = 0; k < 9; ++k) {
        const float angle = 2.0f * kPi * float(k) / 8.0f;
        const vec2 disk = k == 0 ? vec2(0.0f) : 0.99f * vec2(glm::cos(angle), glm::sin(angle));
        const vec3 lit = punctualLightIrradiance(bvh, light, p, ng, ns, disk);
        (maxComponent(lit) > 0.0f ? seen : hidden) += 1;
    }
    // The cone's lowest elevation over a plane of normal n: cos(angle(n, a) + α).
    const auto lowest = [&](const vec3& n) {
        return glm::dot(n, axis) * light.cosHalfAngle - glm::length(glm::cross(n, axis)) * sinHalf;
    };
    if (seen == 9 && lowest(ns) > 0.0f && lowest(ng) > 0.0f)
        return light.intensity * (glm::dot(ns, axis) * 0.5f * (1.0f + light.cosHalfAngle));
    if (hidden == 9) return vec3(0.0f);
    vec3 sum(0.0f);
    for (int a = 0; a < strata; ++a)
        for (int b = 0; b < strata; ++b) {
            const vec2 disk = sampleConcentricDisk(jitteredStratum(seed, lightIndex, strata, a, b, 0x53554Eu));  // "SUN"
            sum += punctualLightIrradiance(bvh, light, p, ng, ns, disk);
        }
    return sum / float(strata * strata);
}

// One emitter patch's irradiance at a receiver by one point drawn uniformly over its area at u
// ∈ [0, 1)² and its shadow ray: Le · cos θ_r · cos θ_e / d² · V · A, unbiased (k: the emitter of
// a single triangle or of a quad's first half). What a light tree's sampled node takes for the
// light it draws, where the ratio estimator's test points would cost more than its draw's noise.
VL_HOSTDEV inline vec3 patchAreaSample(const TraceSceneView& s, const BvhView& bvh, uint32_t k, const vec3& p,
                                       const vec3& ng, const vec3& ns, vec2 u) {
    const int8_t quad = s.emitterQuad ? s.emitterQuad[k] : kQuadSingle;
    uint32_t triangle = s.emitters[k];
    float area = triangleArea(s, triangle);
    if (quad == kQuadFirstHalf) {
        // The quad's halves by area: u.x picks one and is reused within it.
        const uint32_t second = s.emitters[k + 1];
        const float secondArea = triangleArea(s, second);
        const float share = area / (area + secondArea);
        if (u.x < share) {
            u.x = u.x / share;
        } else {
            u.x = glm::min((u.x - share) / (1.0f - share), 0.99999994f);
            triangle = second;
        }
        area += secondArea;
    }
    const vec3 cross = windingCross(s, triangle);
    const float twiceArea = glm::length(cross);
    if (!(twiceArea > 0.0f)) return vec3(0.0f);
    const vec3 emitterNormal = cross / twiceArea;
    const vec3* v = s.vertices + 3 * static_cast<size_t>(triangle);
    const float facing = glm::dot(p - v[0], emitterNormal);
    if (facing == 0.0f || (facing < 0.0f && !s.materials[s.materialIds[triangle]].doubleSided)) return vec3(0.0f);
    const vec3 towardReceiver = facing > 0.0f ? emitterNormal : -emitterNormal;
    const vec2 b = sampleUniformTriangle(u);
    const SurfaceHit point = surfaceAt(s, triangle, b.x, b.y);
    vec3 wi;
    const float g = geometricFactor(p, ng, ns, point.position, towardReceiver, wi);
    if (!(g > 0.0f) || occluded(bvh, p, ng, point.position, towardReceiver)) return vec3(0.0f);
    return emissionAt(s, point, -wi) * (g * area);
}

// The point and spot lights of a tree at a receiver, unbiased (light_tree.h); one shadow ray
// per node of the cut; engineDrawn false leaves out the lights an engine draws. Zero without a tree.
VL_HOSTDEV inline vec3 treePointLightsIrradiance(const TraceSceneView& s, const BvhView& bvh, const vec3& p,
                                                 const vec3& ng, const vec3& ns, int budget, uint64_t seed,
                                                 bool engineDrawn = true) {
    return estimateLightTree(s.pointLightTree, p, ns, budget, seed, [&](uint32_t light, int, bool) {
        if (!engineDrawn && s.lights[light].engineDrawn) return vec3(0.0f);
        return punctualLightIrradiance(bvh, s.lights[light], p, ng, ns, vec2(0.0f));
    });
}

// How many nodes the cut of the point lights' tree takes at a gather ray's hit: a record
// averages its rays' hits, so one or two lights a hit suffice (docs/many-lights.md).
constexpr int kHitLightCut = 2;

// How much of a punctual light p sees, 0..1 (a shadowmask's value): a point or spot light by
// one shadow ray; a sun's disk by the nine points of sunIrradiance, and where they disagree
// (a penumbra) the share of `strata` × `strata` stratified directions over the disk that are
// open. A direction under the geometric surface (ng) counts as blocked: the surface shadows
// itself. Its light's falloff, cone and cosine are not in it: an engine multiplies them in.
VL_HOSTDEV inline float lightVisibility(const BvhView& bvh, const TraceLight& light, const vec3& p, const vec3& ng,
                                        int strata, uint64_t seed, uint32_t lightIndex) {
    const auto open = [&](vec2 disk) {
        PunctualArrival a;
        if (light.type == TraceLightType::Directional) {
            a.wi = light.cosHalfAngle < 1.0f ? coneDirectionAbout(-light.direction, light.cosHalfAngle, disk)
                                             : -light.direction;
            a.toInfinity = true;
        } else {
            const vec3 d = light.position - p;
            if (!(glm::dot(d, d) > 0.0f)) return 0.0f;
            a.wi = glm::normalize(d);
            a.target = light.position;
        }
        if (glm::dot(ng, a.wi) <= 0.0f) return 0.0f;
        return arrivalBlocked(bvh, a, p, ng) ? 0.0f : 1.0f;
    };
    if (light.type != TraceLightType::Directional || !(light.cosHalfAngle < 1.0f)) return open(vec2(0.0f));
    float seen = 0.0f;
    for (int k = 0; k < 9; ++k) {
        const float angle = 2.0f * kPi * float(k) / 8.0f;
        seen += open(k == 0 ? vec2(0.0f) : 0.99f * vec2(glm::cos(angle), glm::sin(angle)));
    }
    if (seen == 9.0f || seen == 0.0f) return seen / 9.0f;
    float sum = 0.0f;
    for (int a = 0; a < strata; ++a)
        for (int b = 0; b < strata; ++b)
            sum += open(sampleConcentricDisk(jitteredStratum(seed, lightIndex, strata, a, b, 0x4D41534Bu)));  // "MASK"
    return sum / float(strata * strata);
}

// Σ over the punctual lights at p, a sun's disk at u ∈ [0, 1)²: each directional light, and
// each point or spot light or, with their tree, its cut of `budget` (seeded by `seed`).
VL_HOSTDEV inline vec3 punctualLightsIrradiance(const TraceSceneView& s, const BvhView& bvh, const vec3& p,
                                                const vec3& ng, const vec3& ns, vec2 u, int budget, uint64_t seed) {
    if (!s.pointLightTree.nodes) return punctualIrradiance(s, bvh, p, ng, ns, u);
    const vec2 disk = sampleConcentricDisk(u);
    vec3 e(0.0f);
    for (uint32_t i = 0; i < s.lightCount; ++i)
        if (s.lights[i].type == TraceLightType::Directional) e += punctualLightIrradiance(bvh, s.lights[i], p, ng, ns, disk);
    return e + treePointLightsIrradiance(s, bvh, p, ng, ns, budget, seed);
}

// Direct irradiance E at point p (geometric normal ng, shading normal ns, both unit; lights,
// emitters and the sky), deterministic per `seed`.
VL_HOSTDEV inline vec3 directIrradianceAt(const TraceSceneView& s, const BvhView& bvh, const vec3& p, const vec3& ng,
                                          const vec3& ns, const DirectLightSettings& settings, uint64_t seed) {
    vec3 e(0.0f);
    const bool pointTree = s.pointLightTree.nodes != nullptr && settings.punctualLights;
    for (uint32_t i = 0; i < s.lightCount && settings.punctualLights; ++i) {
        const TraceLight& light = s.lights[i];
        if (!settings.engineDrawnLights && light.engineDrawn) continue;
        if (light.type == TraceLightType::Directional && light.cosHalfAngle < 1.0f)
            e += sunIrradiance(bvh, light, p, ng, ns, settings.emitterStrata, seed, i);
        else if (light.type == TraceLightType::Directional || !pointTree)
            e += punctualLightIrradiance(bvh, light, p, ng, ns, vec2(0.0f));
    }
    if (pointTree)
        e += treePointLightsIrradiance(s, bvh, p, ng, ns, settings.lightCut, seed, settings.engineDrawnLights);
    if (settings.skyAtSamples) e += skyIrradiance(s, bvh, p, ng, ns, settings.skyStrata, seed);
    const auto patch = [&](uint32_t k) {
        const int8_t quad = s.emitterQuad ? s.emitterQuad[k] : kQuadSingle;
        if (quad == kQuadFirstHalf) return emitterQuadIrradiance(s, bvh, k, p, ng, ns, settings.emitterStrata, seed, k);
        if (quad == kQuadSingle)
            return emitterIrradiance(s, bvh, s.emitters[k], p, ng, ns, settings.emitterStrata, seed, k);
        return vec3(0.0f);
    };
    if (s.emitterTree.nodes) {
        const uint64_t treeSeed = seed ^ 0x454D4954ull;  // "EMIT"
        return e + estimateLightTree(s.emitterTree, p, ns, settings.lightCut, treeSeed,
                                     [&](uint32_t k, int draw, bool alone) {
                                         if (alone) return patch(k);
                                         Pcg32 point = Pcg32::forItem(treeSeed, uint64_t(draw), 0x504F494Eull);  // "POIN"
                                         vec2 u;
                                         point.next2D(u.x, u.y);
                                         return patchAreaSample(s, bvh, k, p, ng, ns, u);
                                     });
    }
    for (uint32_t k = 0; k < s.emitterCount; ++k) e += patch(k);
    return e;
}

// Direct irradiance E at a receiver sample, on its side of its triangle.
VL_HOSTDEV inline vec3 directIrradiance(const TraceSceneView& s, const BvhView& bvh, const SurfaceSample& r,
                                        const DirectLightSettings& settings, uint64_t seed) {
    const vec3* v = s.vertices + 3 * static_cast<size_t>(r.triangle);
    vec3 ng = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
    if (glm::dot(ng, r.normal) < 0.0f) ng = -ng;
    return directIrradianceAt(s, bvh, r.position, ng, r.normal, settings, seed);
}

}  // namespace vl

namespace vl {

// How many nodes a surface point's cut of a tree of many lights takes, per tree: a voxel
// side averages several points and the bounces average the voxels (docs/many-lights.md).
constexpr int kSurfacePointLightCut = 4;

// One emitter patch's light at a surface point, by one shadow ray placed at u (the
// surfacePointIrradiance below); k is the emitter of a single triangle or of a quad's first half.
VL_HOSTDEV inline vec3 patchPointIrradiance(const TraceSceneView& s, const BvhView& bvh, uint32_t k, const vec3& p,
                                            const vec3& ng, const vec3& ns, vec2 u, float layer, uint32_t* rays,
                                            uint32_t* blocked) {
    const int8_t quad = s.emitterQuad ? s.emitterQuad[k] : kQuadSingle;
    if (quad == kQuadSecondHalf) return vec3(0.0f);
    const uint32_t first = s.emitters[k];
    const vec3* v = s.vertices + 3 * size_t(first);
    const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
    const float twiceArea = glm::length(cross);
    if (!(twiceArea > 0.0f)) return vec3(0.0f);
    const vec3 emitterNormal = cross / twiceArea;
    const TraceMaterial& material = s.materials[s.materialIds[first]];
    const float facing = glm::dot(p - v[0], emitterNormal);
    if (facing == 0.0f || (facing < 0.0f && !material.doubleSided)) return vec3(0.0f);
    const vec3 towardReceiver = facing > 0.0f ? emitterNormal : -emitterNormal;
    if (glm::abs(facing) < layer && glm::dot(ns, towardReceiver) < -0.5f) return vec3(0.0f);
    // The patch: the quad's two halves, or the triangle; its unshadowed light and a point of it.
    float unshadowed = 0.0f;
    vec3 point, centre;
    if (quad == kQuadFirstHalf) {
        const vec3* w = s.vertices + 3 * size_t(s.emitters[k + 1]);
        for (const vec3* t : {v, w}) {
            const vec3 relative[3] = {t[0] - p, t[1] - p, t[2] - p};
            unshadowed += clippedTriangleIrradiance(relative, ns);
        }
        const int own = sharedEdge(v, w).ownA;
        point = v[own] + u.x * (v[(own + 1) % 3] - v[own]) + u.y * (v[(own + 2) % 3] - v[own]);
        centre = 0.5f * (v[(own + 1) % 3] + v[(own + 2) % 3]);
    } else {
        const vec3 relative[3] = {v[0] - p, v[1] - p, v[2] - p};
        unshadowed = clippedTriangleIrradiance(relative, ns);
        const vec2 b = sampleUniformTriangle(u);
        point = (1.0f - b.x - b.y) * v[0] + b.x * v[1] + b.y * v[2];
        centre = (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
    }
    if (!(unshadowed > 0.0f)) return vec3(0.0f);
    vec3 radiance = material.emission;
    if (material.emissiveTexture.texture >= 0) {
        // Textured: the radiance where the ray lands (one stratum of the plain estimate).
        const vec2 b = sampleUniformTriangle(u);
        const SurfaceHit at = surfaceAt(s, first, b.x, b.y);
        point = at.position;
        radiance = emissionAt(s, at, glm::normalize(p - point));
    }
    // A point under the horizon cannot tell the patch's visibility: its centre does.
    const auto above = [&](const vec3& q) {
        const vec3 wi = q - p;
        return glm::dot(ns, wi) > 0.0f && glm::dot(ng, wi) > 0.0f && -glm::dot(towardReceiver, wi) > 0.0f;
    };
    if (!above(point)) {
        point = centre;
        if (!above(point)) return vec3(0.0f);
    }
    const bool hidden = occluded(bvh, p, ng, point, towardReceiver);
    if (rays) {
        ++*rays;
        if (hidden) ++*blocked;
    }
    return hidden ? vec3(0.0f) : radiance * unshadowed;
}

// Direct irradiance at one of many points that average over a surface together (a voxel
// side's points, lighting/surface_points.h), without the sky: every light, a sun's disk and
// every emitter patch seen through one shadow ray, placed at u ∈ [0, 1)² (a point of the
// disk, of the quad or triangle), so that the points of one surface, each with its own u,
// stratify what one point alone would sample. An emitter's unshadowed light is exact (Lambert's
// polygon formula) and the ray scales it by its visibility, as the receivers' ratio estimator
// does with one stratum. `layer`: an emitter whose plane lies within it of p, facing p's
// surface, is the cover of that surface, not light it shows (a quad light mounted flat under a
// ceiling lights the ceiling it hides, and a voxel holding both would show that light where
// the emitter is); 0 lights every emitter. `rays` and `blocked`, when given, count the shadow
// rays that emitters and lights took (those with light to bring) and those that were blocked.
// Past kLightTreeFrom lights or emitters, a cut of their tree stands for the visits.
VL_HOSTDEV inline vec3 surfacePointIrradiance(const TraceSceneView& s, const BvhView& bvh, const vec3& p, const vec3& ng,
                                              const vec3& ns, vec2 u, float layer, uint64_t seed,
                                              uint32_t* rays = nullptr, uint32_t* blocked = nullptr) {
    const auto light = [&](const TraceLight& lamp) {
        const vec2 disk = lamp.cosHalfAngle < 1.0f ? sampleConcentricDisk(u) : vec2(0.0f);
        const PunctualArrival arrival = punctualArrival(lamp, p, ng, ns, disk);
        if (!(maxComponent(arrival.irradiance) > 0.0f)) return vec3(0.0f);
        const bool hidden = arrivalBlocked(bvh, arrival, p, ng);
        if (rays) {
            ++*rays;
            if (hidden) ++*blocked;
        }
        return hidden ? vec3(0.0f) : arrival.irradiance;
    };
    vec3 e(0.0f);
    const bool pointTree = s.pointLightTree.nodes != nullptr;
    for (uint32_t i = 0; i < s.lightCount; ++i)
        if (!pointTree || s.lights[i].type == TraceLightType::Directional) e += light(s.lights[i]);
    if (pointTree)
        e += estimateLightTree(s.pointLightTree, p, ns, kSurfacePointLightCut, seed,
                               [&](uint32_t i, int, bool) { return light(s.lights[i]); });
    if (s.emitterTree.nodes)
        return e + estimateLightTree(s.emitterTree, p, ns, kSurfacePointLightCut, seed ^ 0x454D4954ull, [&](uint32_t k, int, bool) {
                   return patchPointIrradiance(s, bvh, k, p, ng, ns, u, layer, rays, blocked);
               });
    for (uint32_t k = 0; k < s.emitterCount; ++k) e += patchPointIrradiance(s, bvh, k, p, ng, ns, u, layer, rays, blocked);
    return e;
}

}  // namespace vl
