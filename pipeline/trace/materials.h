// Scattering for the reference path tracer, inline VL_HOSTDEV so the CUDA launchers reuse it:
// reflection and refraction (ERRATA eq. 3–4), exact dielectric Fresnel and Schlick
// (eq. 5), and the three materials a glTF scene needs here: Lambert from baseColor, a
// mirror for metallic 1 / roughness 0, a smooth dielectric for KHR_materials_transmission.
//
// Convention: every direction points away from the surface (wo toward the viewer, wi
// toward where light comes from); n is unit and on the side of wo unless stated.
#pragma once

#include "core/math.h"
#include "core/sampling.h"

#include <cstdint>

namespace vl {

// ERRATA eq. 3: the mirror direction of l about n, u = 2(l·n)n − l.
VL_HOSTDEV inline vec3 reflectAbout(const vec3& l, const vec3& n) { return 2.0f * glm::dot(l, n) * n - l; }

// ERRATA eq. 4: t = c(−l + (l·n)n) − √(1 − c²(1 − (l·n)²)) n with c = n_a/n_b, n on the
// incident side (l·n > 0). Returns false for total internal reflection (negative radicand).
VL_HOSTDEV inline bool refractAbout(const vec3& l, const vec3& n, float c, vec3& t) {
    const float cosI = glm::dot(l, n);
    const float radicand = 1.0f - c * c * glm::max(0.0f, 1.0f - cosI * cosI);
    if (radicand < 0.0f) return false;
    t = c * (-l + cosI * n) - glm::sqrt(radicand) * n;
    return true;
}

// Unpolarised Fresnel reflectance of a smooth dielectric boundary, light arriving in the
// medium of index etaI at cos θ_i (> 0) onto the medium etaT. 1 under total internal
// reflection. The transmitted fraction is 1 − R (energy, not amplitude).
VL_HOSTDEV inline float fresnelDielectric(float cosI, float etaI, float etaT) {
    cosI = glm::clamp(cosI, 0.0f, 1.0f);
    const float sinI2 = glm::max(0.0f, 1.0f - cosI * cosI);
    const float ratio = etaI / etaT;
    const float sinT2 = ratio * ratio * sinI2;
    if (sinT2 >= 1.0f) return 1.0f;
    const float cosT = glm::sqrt(1.0f - sinT2);
    const float rs = (etaI * cosI - etaT * cosT) / (etaI * cosI + etaT * cosT);
    const float rp = (etaT * cosI - etaI * cosT) / (etaT * cosI + etaI * cosT);
    return glm::clamp(0.5f * (rs * rs + rp * rp), 0.0f, 1.0f);
}

// ERRATA eq. 5: F₀ = ((n_a − n_b)/(n_a + n_b))², F = F₀ + (1 − F₀)(1 − cos θ)⁵, where θ is
// the angle in the less dense medium (the transmitted angle when leaving the denser one);
// 1 when sin θ_t > 1.
VL_HOSTDEV inline float fresnelSchlick(float cosI, float etaI, float etaT) {
    const float f0 = (etaI - etaT) * (etaI - etaT) / ((etaI + etaT) * (etaI + etaT));
    float cosTheta = glm::clamp(cosI, 0.0f, 1.0f);
    if (etaI > etaT) {
        const float ratio = etaI / etaT;
        const float sinT2 = ratio * ratio * (1.0f - cosTheta * cosTheta);
        if (sinT2 >= 1.0f) return 1.0f;
        cosTheta = glm::sqrt(1.0f - sinT2);
    }
    const float m = 1.0f - cosTheta;
    const float m2 = m * m;
    return f0 + (1.0f - f0) * m2 * m2 * m;
}

// glTF's metal Fresnel: Schlick with F₀ = baseColor.
VL_HOSTDEV inline vec3 fresnelSchlickConductor(float cosI, const vec3& f0) {
    const float m = 1.0f - glm::clamp(cosI, 0.0f, 1.0f);
    const float m2 = m * m;
    return f0 + (vec3(1.0f) - f0) * (m2 * m2 * m);
}

enum class MaterialKind : uint32_t {
    Lambert = 0,     // baseColor / π
    Mirror = 1,      // metallic 1, roughness 0: perfect reflection tinted by Schlick(F₀ = baseColor)
    Dielectric = 2,  // transmission > 0: Fresnel reflection, refraction tinted by baseColor
};

// Which lobe a scattering event took. Delta lobes cannot be sampled by light sampling.
enum class Lobe : uint32_t { None = 0, Diffuse, SpecularReflection, SpecularTransmission };

// The local material at a hit: everything sampleLobe needs, textures already applied.
struct ShadingMaterial {
    MaterialKind kind = MaterialKind::Lambert;
    vec3 baseColor{1.0f};
    float ior = 1.5f;
    float transmission = 0.0f;  // Dielectric: fraction of the refracted light transmitted (rest diffuse)
};

// The lobe a vertex scatters by, chosen with probability equal to its weight (Fresnel,
// transmission), so the throughput only picks up the lobe's colour.
struct LobeChoice {
    Lobe lobe = Lobe::None;
    vec3 weight{0.0f};   // throughput factor (colour × radiance scaling), already divided by the choice probability
    vec3 direction{0.0f};  // the delta lobes' direction; unused for Diffuse
};

// wo: unit, toward the viewer. ng: geometric normal on the side of wo. ns: shading normal
// on the same side as ng. u: uniform in [0, 1).
VL_HOSTDEV inline LobeChoice chooseLobe(const ShadingMaterial& m, const vec3& wo, const vec3& ns, bool entering,
                                        float u) {
    LobeChoice choice;
    const float cosO = glm::dot(wo, ns);
    switch (m.kind) {
    case MaterialKind::Lambert:
        choice.lobe = Lobe::Diffuse;
        choice.weight = m.baseColor;
        return choice;
    case MaterialKind::Mirror:
        if (cosO <= 0.0f) return choice;
        choice.lobe = Lobe::SpecularReflection;
        choice.direction = reflectAbout(wo, ns);
        choice.weight = fresnelSchlickConductor(cosO, m.baseColor);
        return choice;
    case MaterialKind::Dielectric: {
        if (cosO <= 0.0f) return choice;
        const float etaI = entering ? 1.0f : m.ior;
        const float etaT = entering ? m.ior : 1.0f;
        const float fresnel = fresnelDielectric(cosO, etaI, etaT);
        if (u < fresnel) {
            choice.lobe = Lobe::SpecularReflection;
            choice.direction = reflectAbout(wo, ns);
            choice.weight = vec3(1.0f);
            return choice;
        }
        // Rescale u to [0, 1) for the second choice, transmission versus the diffuse base.
        const float v = (u - fresnel) / glm::max(1.0f - fresnel, 1e-7f);
        if (v < m.transmission) {
            vec3 t(0.0f);
            if (!refractAbout(wo, ns, etaI / etaT, t)) {
                // Only reachable through float rounding at the critical angle: reflect.
                choice.lobe = Lobe::SpecularReflection;
                choice.direction = reflectAbout(wo, ns);
                choice.weight = vec3(1.0f);
                return choice;
            }
            choice.lobe = Lobe::SpecularTransmission;
            choice.direction = glm::normalize(t);
            // Radiance is compressed into the denser medium: L_t = (η_t/η_i)² (1 − F) L_i,
            // so carrying radiance back along the path scales by (η_i/η_t)².
            const float scale = (etaI * etaI) / (etaT * etaT);
            choice.weight = m.baseColor * scale;
            return choice;
        }
        choice.lobe = Lobe::Diffuse;
        choice.weight = m.baseColor;
        return choice;
    }
    }
    return choice;
}

// Cosine-weighted sample of the diffuse lobe about ns: returns the direction; pdf cos θ/π.
VL_HOSTDEV inline vec3 sampleDiffuseDirection(const vec3& ns, vec2 u) {
    vec3 t, b;
    orthonormalBasis(ns, t, b);
    const vec3 local = sampleCosineHemisphere(u);
    return local.x * t + local.y * b + local.z * ns;
}

VL_HOSTDEV inline float diffusePdf(const vec3& ns, const vec3& wi) { return glm::max(0.0f, glm::dot(ns, wi)) * kInvPi; }

}  // namespace vl
