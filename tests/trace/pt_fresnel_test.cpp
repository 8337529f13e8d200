// Fresnel, Snell and the dielectric lobe (ERRATA eq. 3–5): energy conservation checked
// against the Fresnel amplitude transmission coefficients (an independent formula), total
// internal reflection past the critical angle, Snell's law on the refracted vector.
#include "trace/materials.h"

#include "core/rng.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;

namespace {

// Incident direction l (toward where light comes from) at angle theta from n = +Z.
vec3 incident(double theta, double phi = 0.3) {
    return vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
}

// Transmitted energy fraction from the amplitude coefficients t_s, t_p:
// T = (n_t cos θ_t)/(n_i cos θ_i) · (t_s² + t_p²)/2.
double transmittanceFromAmplitudes(double cosI, double n1, double n2) {
    const double sinT = n1 / n2 * std::sqrt(1.0 - cosI * cosI);
    const double cosT = std::sqrt(1.0 - sinT * sinT);
    const double ts = 2.0 * n1 * cosI / (n1 * cosI + n2 * cosT);
    const double tp = 2.0 * n1 * cosI / (n2 * cosI + n1 * cosT);
    return (n2 * cosT) / (n1 * cosI) * 0.5 * (ts * ts + tp * tp);
}

}  // namespace

TEST_CASE("Fresnel reflectance plus transmittance is one over angles and indices", "[trace]") {
    for (double ior : {1.1, 1.33, 1.5, 2.42})
        for (bool entering : {true, false}) {
            const double n1 = entering ? 1.0 : ior, n2 = entering ? ior : 1.0;
            const double critical = n1 > n2 ? std::asin(n2 / n1) : M_PI / 2;
            for (int i = 0; i < 40; ++i) {
                const double theta = (i + 0.5) / 40.0 * critical * 0.999;
                const double cosI = std::cos(theta);
                const double R = fresnelDielectric(float(cosI), float(n1), float(n2));
                const double T = transmittanceFromAmplitudes(cosI, n1, n2);
                INFO("ior " << ior << " entering " << entering << " theta " << theta);
                REQUIRE(R >= 0.0);
                REQUIRE(R <= 1.0);
                REQUIRE(R + T == Approx(1.0).margin(2e-6));
            }
        }
    // Normal incidence: ((n1 − n2)/(n1 + n2))², the F₀ of ERRATA eq. 5, for both formulas.
    REQUIRE(fresnelDielectric(1.0f, 1.0f, 1.5f) == Approx(0.04).epsilon(1e-5));
    REQUIRE(fresnelSchlick(1.0f, 1.0f, 1.5f) == Approx(0.04).epsilon(1e-5));
    REQUIRE(fresnelSchlick(0.0f, 1.0f, 1.5f) == Approx(1.0));
}

TEST_CASE("Total internal reflection beyond the critical angle", "[trace]") {
    for (float ior : {1.33f, 1.5f, 2.42f}) {
        const double critical = std::asin(1.0 / ior);
        for (double theta : {critical + 1e-3, critical + 0.1, 0.5 * (critical + M_PI / 2), M_PI / 2 - 1e-3}) {
            const vec3 l = incident(theta);
            vec3 t(0.0f);
            INFO("ior " << ior << " theta " << theta);
            REQUIRE_FALSE(refractAbout(l, vec3(0, 0, 1), ior, t));  // from glass (n_a = ior) to air
            REQUIRE(fresnelDielectric(l.z, ior, 1.0f) == 1.0f);
            REQUIRE(fresnelSchlick(l.z, ior, 1.0f) == 1.0f);
            // The dielectric lobe then always reflects, whatever the random number.
            ShadingMaterial glass;
            glass.kind = MaterialKind::Dielectric;
            glass.ior = ior;
            glass.transmission = 1.0f;
            for (float u : {0.0f, 0.5f, 0.999f}) REQUIRE(chooseLobe(glass, l, vec3(0, 0, 1), false, u).lobe == Lobe::SpecularReflection);
        }
        const vec3 below = incident(critical - 1e-3);
        vec3 t(0.0f);
        REQUIRE(refractAbout(below, vec3(0, 0, 1), ior, t));
        REQUIRE(fresnelDielectric(below.z, ior, 1.0f) < 1.0f);
    }
}

TEST_CASE("Refraction obeys Snell's law and reflection mirrors the angle", "[trace]") {
    const vec3 n(0, 0, 1);
    for (double ior : {1.1, 1.5, 2.42})
        for (bool entering : {true, false}) {
            const double n1 = entering ? 1.0 : ior, n2 = entering ? ior : 1.0;
            const double critical = n1 > n2 ? std::asin(n2 / n1) : M_PI / 2;
            for (int i = 0; i < 25; ++i) {
                const double theta = i / 25.0 * critical * 0.99;
                const vec3 l = incident(theta, 0.1 * i);
                vec3 t(0.0f);
                REQUIRE(refractAbout(l, n, float(n1 / n2), t));
                const double sinI = std::sqrt(double(l.x) * l.x + double(l.y) * l.y);
                const double sinT = std::sqrt(double(t.x) * t.x + double(t.y) * t.y);
                INFO("ior " << ior << " entering " << entering << " theta " << theta);
                REQUIRE(std::abs(n1 * sinI - n2 * sinT) < 1e-6);
                REQUIRE(glm::length(t) == Approx(1.0f).margin(1e-6));
                REQUIRE(t.z < 0.0f);  // crosses to the other side
                // In the plane of incidence, on the far side of the normal.
                REQUIRE(std::abs(glm::dot(glm::cross(l, n), t)) < 1e-6f);
                REQUIRE(double(t.x) * l.x + double(t.y) * l.y <= 0.0);
                const vec3 r = reflectAbout(l, n);
                REQUIRE(r.z == Approx(l.z).margin(1e-6));
                REQUIRE(r.x == Approx(-l.x).margin(1e-6));
                REQUIRE(r.y == Approx(-l.y).margin(1e-6));
            }
        }
}

TEST_CASE("Schlick's approximation of ERRATA eq. 5 uses the transmitted angle leaving the denser medium", "[trace]") {
    // Reciprocity: leaving glass at θ_i gives the same F as entering at the matching θ_t.
    for (double thetaT : {0.1, 0.5, 1.0, 1.4}) {
        const double thetaI = std::asin(std::sin(thetaT) / 1.5);
        REQUIRE(fresnelSchlick(float(std::cos(thetaI)), 1.5f, 1.0f) ==
                Approx(fresnelSchlick(float(std::cos(thetaT)), 1.0f, 1.5f)).epsilon(1e-4));
    }
    // Within a few hundredths of the exact curve for glass below grazing angles.
    for (int i = 0; i < 20; ++i) {
        const float cosI = std::cos(i / 20.0f * 1.4f);
        REQUIRE(std::abs(fresnelSchlick(cosI, 1.0f, 1.5f) - fresnelDielectric(cosI, 1.0f, 1.5f)) < 0.03f);
    }
}

TEST_CASE("The dielectric lobe reflects with the Fresnel probability and transmits the rest", "[trace]") {
    ShadingMaterial glass;
    glass.kind = MaterialKind::Dielectric;
    glass.ior = 1.5f;
    glass.transmission = 1.0f;
    const vec3 l = incident(1.2);
    const double F = fresnelDielectric(l.z, 1.0f, 1.5f);
    Pcg32 rng(7, 9);
    constexpr int n = 200000;
    int reflected = 0;
    for (int i = 0; i < n; ++i) {
        const LobeChoice c = chooseLobe(glass, l, vec3(0, 0, 1), true, rng.next1D());
        REQUIRE(c.lobe != Lobe::Diffuse);
        if (c.lobe == Lobe::SpecularReflection) {
            ++reflected;
            REQUIRE(c.weight == vec3(1.0f));
        } else {
            // Radiance entering glass is carried back scaled by (1/1.5)².
            REQUIRE(c.weight.x == Approx(1.0f / 2.25f));
            REQUIRE(c.direction.z < 0.0f);
        }
    }
    const double sigma = std::sqrt(F * (1.0 - F) / n);
    REQUIRE(std::abs(double(reflected) / n - F) < 4.0 * sigma);
}
