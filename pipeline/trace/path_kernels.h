// The reference path tracer's per-path kernels, inline VL_HOSTDEV over a TraceSceneView and
// a BvhView, so the TBB loops of path_tracer.cpp and the CUDA launchers run the same code.
//
// Unidirectional with next-event estimation: every punctual light at every diffuse vertex
// (a point light cannot be hit by chance), one emissive triangle picked by power and a
// point on it picked by area (pdf converted to solid angle), combined with BSDF sampling
// by the power heuristic; emitters hit by a BSDF ray get the matching MIS weight (1 after
// a delta lobe or for the camera's own ray). Russian roulette (ERRATA eq. 16, c = 0) from
// bounce `rouletteStart` on, survival probability min(1, max throughput). A path that leaves
// the scene sees the sky (TraceSceneView::sky): its uniform part by BSDF sampling alone,
// its image also by a direction drawn from the image at every diffuse vertex, the two
// combined by the power heuristic. Bounces are counted as Cycles counts them (PathSettings).
#pragma once

#include "core/rng.h"
#include "core/sampling.h"
#include "trace/bvh_traverse.h"
#include "trace/materials.h"
#include "trace/ray_offset.h"
#include "trace/surface_samples.h"
#include "trace/trace_scene.h"

namespace vl {

// Bounce counting follows Cycles: max bounces B means light scattered at most B + 1 times
// on its way to the sensor (B = 0 is direct light only). "Direct" is light scattered once
// (emitters seen by the camera count as direct too); "indirect" is everything else.
struct PathSettings {
    int maxBounces = 64;
    int rouletteStart = 5;      // first bounce (vertex index, 0 = first hit) where roulette may end a path
    bool russianRoulette = true;
};

struct PathSample {
    vec3 direct{0.0f};
    vec3 indirect{0.0f};
    vec3 albedo{0.0f};  // base colour at the first hit (camera paths)
};

// Whether anything blocks the open segment from `from` (leaving along normal `fromNormal`'s
// side) to `to` (offset along `toNormal`; pass a zero vector for a point light).
VL_HOSTDEV inline bool occluded(const BvhView& bvh, const vec3& from, const vec3& fromNormal, const vec3& to,
                                const vec3& toNormal) {
    Ray ray;
    ray.origin = offsetRayOrigin(from, fromNormal, bvh.extent);
    const vec3 target = toNormal == vec3(0.0f) ? to : offsetRayOrigin(to, toNormal, bvh.extent);
    ray.direction = target - ray.origin;
    ray.tMin = 0.0f;
    ray.tMax = 1.0f;
    return intersectAny(bvh, ray);
}

// glTF KHR_lights_punctual's range window (1 inside, smoothly 0 at the range).
VL_HOSTDEV inline float rangeWindow(float distance2, float range) {
    if (!(range > 0.0f)) return 1.0f;
    const float ratio2 = distance2 / (range * range);
    return glm::clamp(1.0f - ratio2 * ratio2, 0.0f, 1.0f);
}

// What a punctual light (a sun's disk drawn at `disk`) brings to p before its shadow ray: the
// direction toward it, its irradiance E·cos θ (zero under the horizon of ns or ng) and where
// the shadow ray ends (toInfinity for a directional light).
struct PunctualArrival {
    vec3 wi{0.0f};
    vec3 irradiance{0.0f};
    vec3 target{0.0f};
    bool toInfinity = false;
};
VL_HOSTDEV inline PunctualArrival punctualArrival(const TraceLight& light, const vec3& p, const vec3& ng, const vec3& ns,
                                                  vec2 disk) {
    PunctualArrival a;
    vec3 e;
    if (light.type == TraceLightType::Directional) {
        a.wi = -light.direction;
        if (light.cosHalfAngle < 1.0f) a.wi = coneDirectionAbout(a.wi, light.cosHalfAngle, disk);
        e = light.intensity;
        a.toInfinity = true;
    } else {
        const vec3 d = light.position - p;
        const float r2 = glm::dot(d, d);
        if (!(r2 > 0.0f)) return a;
        a.wi = d / glm::sqrt(r2);
        float falloff = rangeWindow(r2, light.range) / r2;
        if (light.type == TraceLightType::Spot) {
            const float t = glm::clamp(glm::dot(light.direction, -a.wi) * light.spotScale + light.spotOffset, 0.0f, 1.0f);
            falloff *= t * t;
        }
        e = light.intensity * falloff;
        a.target = light.position;
    }
    const float cosS = glm::dot(ns, a.wi);
    if (cosS <= 0.0f || glm::dot(ng, a.wi) <= 0.0f || !(maxComponent(e) > 0.0f)) return a;
    a.irradiance = e * cosS;
    return a;
}

// Whether the shadow ray of an arrival is blocked.
VL_HOSTDEV inline bool arrivalBlocked(const BvhView& bvh, const PunctualArrival& a, const vec3& p, const vec3& ng) {
    if (a.toInfinity) {
        Ray ray;
        ray.origin = offsetRayOrigin(p, ng, bvh.extent);
        ray.direction = a.wi;
        return intersectAny(bvh, ray);
    }
    return occluded(bvh, p, ng, a.target, vec3(0.0f));
}

// One punctual light's incident radiance × cos θ at a point (irradiance, shadowed), for a
// diffuse lobe about ns on the side of ng. A directional light with a disk (cosHalfAngle < 1)
// arrives from the direction of its cone that `disk`, a point of the unit disk, stands for
// (coneDirection): its mean over uniform points of the disk is the disk's irradiance,
// penumbrae included.
VL_HOSTDEV inline vec3 punctualLightIrradiance(const BvhView& bvh, const TraceLight& light, const vec3& p,
                                               const vec3& ng, const vec3& ns, vec2 disk) {
    const PunctualArrival a = punctualArrival(light, p, ng, ns, disk);
    if (!(maxComponent(a.irradiance) > 0.0f)) return vec3(0.0f);
    return arrivalBlocked(bvh, a, p, ng) ? vec3(0.0f) : a.irradiance;
}

// Σ over punctual lights, a sun's disk sampled uniformly at `u` ∈ [0, 1)².
VL_HOSTDEV inline vec3 punctualIrradiance(const TraceSceneView& s, const BvhView& bvh, const vec3& p,
                                          const vec3& ng, const vec3& ns, vec2 u) {
    const vec2 disk = sampleConcentricDisk(u);
    vec3 sum(0.0f);
    for (uint32_t i = 0; i < s.lightCount; ++i) sum += punctualLightIrradiance(bvh, s.lights[i], p, ng, ns, disk);
    return sum;
}

// One emissive-triangle sample for a diffuse lobe about ns: returns Le · cos θ · w_MIS / pdf
// (to be multiplied by albedo/π), zero when shadowed or facing away.
VL_HOSTDEV inline vec3 emitterIrradianceSample(const TraceSceneView& s, const BvhView& bvh, const vec3& p,
                                               const vec3& ng, const vec3& ns, Pcg32& rng) {
    const float uPick = rng.next1D();
    vec2 uPoint;
    rng.next2D(uPoint.x, uPoint.y);
    if (s.emitterCount == 0) return vec3(0.0f);
    const uint32_t triangle = s.emitters[pickEmitter(s, uPick)];
    const vec2 b = sampleUniformTriangle(uPoint);
    const SurfaceHit light = surfaceAt(s, triangle, b.x, b.y);
    const vec3 d = light.position - p;
    const float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.0f)) return vec3(0.0f);
    const vec3 wi = d / glm::sqrt(dist2);
    const float cosS = glm::dot(ns, wi);
    if (cosS <= 0.0f || glm::dot(ng, wi) <= 0.0f) return vec3(0.0f);
    const float cosL = glm::abs(glm::dot(light.geometricNormal, wi));
    const float area = triangleArea(s, triangle);
    const float selectPdf = s.emitterSelectPdf[triangle];
    if (!(cosL > 0.0f) || !(area > 0.0f) || !(selectPdf > 0.0f)) return vec3(0.0f);
    const vec3 le = emissionAt(s, light, -wi);
    if (!(maxComponent(le) > 0.0f)) return vec3(0.0f);
    const float pdf = selectPdf / area * dist2 / cosL;  // solid angle
    if (!(pdf > 0.0f) || !isFinite(pdf)) return vec3(0.0f);
    const vec3 lightSide = glm::dot(light.geometricNormal, wi) < 0.0f ? light.geometricNormal : -light.geometricNormal;
    if (occluded(bvh, p, ng, light.position, lightSide)) return vec3(0.0f);
    const float weight = powerHeuristic(pdf, cosS * kInvPi);
    return le * (cosS * weight / pdf);
}

// One direction drawn from the sky's image for a diffuse lobe about ns: its radiance ·
// cos θ · w_MIS / pdf (to be multiplied by albedo/π), zero when blocked or below the surface.
// Draws no random numbers without an image, so such scenes keep their sequences.
VL_HOSTDEV inline vec3 skyImageIrradianceSample(const TraceSceneView& s, const BvhView& bvh, const vec3& p,
                                                const vec3& ng, const vec3& ns, Pcg32& rng) {
    if (!s.sky.samplable()) return vec3(0.0f);
    vec2 u;
    rng.next2D(u.x, u.y);
    float pdf = 0.0f;
    vec2 at;
    const vec3 wi = sampleSkyImage(s.sky, u, pdf, &at);
    if (!(pdf > 0.0f)) return vec3(0.0f);
    const float cosS = glm::dot(ns, wi);
    if (cosS <= 0.0f || glm::dot(ng, wi) <= 0.0f) return vec3(0.0f);
    Ray ray;
    ray.origin = offsetRayOrigin(p, ng, bvh.extent);
    ray.direction = wi;
    if (intersectAny(bvh, ray)) return vec3(0.0f);
    const vec3 image = skyRadianceAt(s.sky, at) - s.sky.uniform;  // what the draw estimates
    const vec3 contribution = image * (cosS * powerHeuristic(pdf, cosS * kInvPi) / pdf);
    return isFinite(contribution) ? contribution : vec3(0.0f);
}

// What a path that leaves the scene along wi sees, its image part weighted against the
// image's own draws (bsdfPdf 0: the camera's ray or a delta lobe, no weight).
VL_HOSTDEV inline vec3 escapedRadiance(const SkyView& sky, const vec3& wi, float bsdfPdf) {
    if (!sky.hasImage()) return sky.uniform;
    const SkySeen seen = skySeenAlong(sky, wi);
    const float weight = bsdfPdf > 0.0f && sky.samplable() ? powerHeuristic(bsdfPdf, seen.imagePdf) : 1.0f;
    return sky.uniform + (seen.radiance - sky.uniform) * weight;
}

// The solid-angle pdf with which light sampling would have produced the direction that hit
// emitter triangle `hit` at distance t (for the MIS weight of a BSDF-sampled hit).
VL_HOSTDEV inline float emitterPdf(const TraceSceneView& s, const SurfaceHit& hit, const vec3& direction, float t) {
    if (!s.emitterSelectPdf) return 0.0f;
    const float selectPdf = s.emitterSelectPdf[hit.triangle];
    const float area = triangleArea(s, hit.triangle);
    const float cosL = glm::abs(glm::dot(hit.geometricNormal, direction));
    if (!(selectPdf > 0.0f) || !(area > 0.0f) || !(cosL > 0.0f)) return 0.0f;
    const float pdf = selectPdf / area * t * t / cosL;
    return isFinite(pdf) ? pdf : 0.0f;
}

// Continues a path at surface vertex `h` (bounce 0), wo pointing back toward the previous
// vertex (the camera, or the receiver's normal side), with throughput beta.
// When `whiteReceiver` is set, the first vertex scatters as a white Lambert surface about
// its shading normal, whatever its material: the path then estimates irradiance/π there.
VL_HOSTDEV inline void continuePath(const TraceSceneView& s, const BvhView& bvh, SurfaceHit h, vec3 wo, vec3 beta,
                                    Pcg32& rng, const PathSettings& settings, bool whiteReceiver, PathSample& out) {
    for (int bounce = 0;; ++bounce) {
        // Orient the frame to the side the path arrived from.
        const bool front = glm::dot(wo, h.geometricNormal) >= 0.0f;
        const vec3 ng = front ? h.geometricNormal : -h.geometricNormal;
        vec3 ns = front ? h.shadingNormal : -h.shadingNormal;
        if (glm::dot(ns, ng) <= 0.0f) ns = ng;

        ShadingMaterial material;
        if (!(whiteReceiver && bounce == 0)) material = shadingMaterialAt(s, h);
        const LobeChoice lobe = chooseLobe(material, wo, ns, front, rng.next1D());
        if (lobe.lobe == Lobe::None) return;
        vec3& sink = bounce == 0 ? out.direct : out.indirect;

        vec3 wi;
        float bsdfPdf = 0.0f;
        const bool delta = lobe.lobe != Lobe::Diffuse;
        if (!delta) {
            const vec3 fOverPi = beta * lobe.weight * kInvPi;
            vec2 sun(0.0f);
            if (s.sunDisks > 0) rng.next2D(sun.x, sun.y);
            vec3 incident = punctualIrradiance(s, bvh, h.position, ng, ns, sun);
            incident += emitterIrradianceSample(s, bvh, h.position, ng, ns, rng);
            incident += skyImageIrradianceSample(s, bvh, h.position, ng, ns, rng);
            const vec3 contribution = fOverPi * incident;
            if (isFinite(contribution)) sink += contribution;
            vec2 u;
            rng.next2D(u.x, u.y);
            wi = sampleDiffuseDirection(ns, u);
            bsdfPdf = diffusePdf(ns, wi);
            if (!(bsdfPdf > 0.0f) || glm::dot(wi, ng) <= 0.0f) return;
        } else {
            wi = lobe.direction;
            const float side = glm::dot(wi, ng);
            if (lobe.lobe == Lobe::SpecularReflection ? side <= 0.0f : side >= 0.0f) return;
        }
        beta *= lobe.weight;
        if (!(maxComponent(beta) > 0.0f) || !isFinite(beta)) return;

        if (settings.russianRoulette && bounce >= settings.rouletteStart) {
            const float survive = glm::min(1.0f, maxComponent(beta));
            if (!(survive > 0.0f) || rng.next1D() >= survive) return;
            beta /= survive;
        }

        Ray ray;
        ray.origin = offsetRayOrigin(h.position, glm::dot(wi, ng) > 0.0f ? ng : -ng, bvh.extent);
        ray.direction = wi;
        Hit hit;
        if (!intersectClosest(bvh, ray, hit)) {
            // Out of the scene: the sky. Its uniform part by BSDF sampling alone (a diffuse
            // lobe's cosine sampling is its own importance sampling), its image weighted
            // against the image's draws.
            const vec3 contribution = beta * escapedRadiance(s.sky, wi, delta ? 0.0f : bsdfPdf);
            if (isFinite(contribution)) sink += contribution;
            return;
        }
        const SurfaceHit next = surfaceAt(s, hit.triangle, hit.b1, hit.b2);
        const vec3 le = emissionAt(s, next, -wi);
        if (maxComponent(le) > 0.0f) {
            const float weight = delta ? 1.0f : powerHeuristic(bsdfPdf, emitterPdf(s, next, wi, hit.t));
            const vec3 contribution = beta * le * weight;
            if (isFinite(contribution)) sink += contribution;
        }
        if (bounce + 1 > settings.maxBounces) return;
        h = next;
        wo = -wi;
    }
}

// A camera path along `ray`: emission seen directly, then continuePath.
VL_HOSTDEV inline PathSample traceCameraPath(const TraceSceneView& s, const BvhView& bvh, const Ray& ray, Pcg32& rng,
                                             const PathSettings& settings) {
    PathSample out;
    Hit hit;
    if (!intersectClosest(bvh, ray, hit)) {
        out.direct = skyRadianceAlong(s.sky, ray.direction);
        return out;
    }
    const SurfaceHit h = surfaceAt(s, hit.triangle, hit.b1, hit.b2);
    const vec3 wo = -ray.direction;
    out.direct = emissionAt(s, h, wo);
    out.albedo = baseColorAt(s, h);
    continuePath(s, bvh, h, wo, vec3(1.0f), rng, settings, false, out);
    return out;
}

// One irradiance/π estimate at a receiver point (a lightmap texel sample): the outgoing
// radiance of a white Lambert surface there, without its own emission.
VL_HOSTDEV inline PathSample traceReceiverPath(const TraceSceneView& s, const BvhView& bvh, const SurfaceSample& r,
                                               Pcg32& rng, const PathSettings& settings) {
    PathSample out;
    SurfaceHit h;
    h.position = r.position;
    h.shadingNormal = r.normal;
    h.geometricNormal = r.normal;
    if (r.triangle < s.triangleCount) {
        const vec3* v = s.vertices + 3 * static_cast<size_t>(r.triangle);
        const vec3 cross = glm::cross(v[1] - v[0], v[2] - v[0]);
        const float length = glm::length(cross);
        if (length > 0.0f) h.geometricNormal = glm::dot(cross, r.normal) >= 0.0f ? cross / length : -cross / length;
    }
    h.uv[0] = h.uv[1] = vec2(0.0f);
    h.color = vec4(1.0f);
    h.triangle = r.triangle;
    h.material = 0;
    out.albedo = r.albedo;
    // Viewed from the side of its normal: wo = ns selects that side.
    continuePath(s, bvh, h, r.normal, vec3(1.0f), rng, settings, true, out);
    return out;
}

}  // namespace vl
