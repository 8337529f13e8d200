#include "core/rng.h"
#include "core/sampling.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace vl;

TEST_CASE("PCG32 is reproducible per item and differs between items", "[core]") {
    Pcg32 a = Pcg32::forItem(42, 7), b = Pcg32::forItem(42, 7), c = Pcg32::forItem(43, 7);
    bool allSame = true;
    for (int i = 0; i < 16; ++i) {
        const uint32_t x = a.nextU32();
        REQUIRE(x == b.nextU32());
        allSame = allSame && x == c.nextU32();
    }
    REQUIRE_FALSE(allSame);
}

TEST_CASE("next1D stays in the unit interval with mean one half", "[core]") {
    Pcg32 rng(1, 2);
    double sum = 0.0;
    constexpr int n = 200000;
    for (int i = 0; i < n; ++i) {
        const float u = rng.next1D();
        REQUIRE(u >= 0.0f);
        REQUIRE(u < 1.0f);
        sum += u;
    }
    // Standard error of the mean of U(0,1) is 1/sqrt(12 n); allow 5 of them.
    REQUIRE(std::abs(sum / n - 0.5) < 5.0 / std::sqrt(12.0 * n));
}

TEST_CASE("Tent filter of ERRATA eq. 11 maps to the interval -1 to 1 with a triangular density", "[core]") {
    REQUIRE(sampleTent(0.0f) == Approx(-1.0f));
    REQUIRE(sampleTent(0.5f) == Approx(0.0f));
    REQUIRE(sampleTent(0.125f) == Approx(-0.5f));  // CDF of the tent at -0.5 is 1/8
    REQUIRE(sampleTent(0.875f) == Approx(0.5f));
}

TEST_CASE("Concentric disk samples stay in the unit disk and cosine samples in the upper hemisphere", "[core]") {
    Pcg32 rng(3, 4);
    double meanCos = 0.0;
    constexpr int n = 100000;
    for (int i = 0; i < n; ++i) {
        const vec2 u(rng.next1D(), rng.next1D());
        const vec2 d = sampleConcentricDisk(u);
        REQUIRE(glm::dot(d, d) <= 1.0f + 1e-6f);
        const vec3 w = sampleCosineHemisphere(u);
        REQUIRE(w.z >= 0.0f);
        REQUIRE(glm::length(w) == Approx(1.0f).epsilon(1e-5));
        meanCos += w.z;
    }
    // E[cos θ] under pdf cos θ/π is 2/3.
    REQUIRE(meanCos / n == Approx(2.0 / 3.0).epsilon(0.01));
}

TEST_CASE("Orthonormal basis is orthonormal for axis and near-axis normals", "[core]") {
    for (vec3 n : {vec3(0, 0, 1), vec3(0, 0, -1), vec3(1, 0, 0), glm::normalize(vec3(1e-7f, 0, -1)),
                   glm::normalize(vec3(0.3f, -0.5f, 0.8f))}) {
        vec3 t, b;
        orthonormalBasis(n, t, b);
        REQUIRE(std::abs(glm::dot(t, n)) < 1e-6f);
        REQUIRE(std::abs(glm::dot(b, n)) < 1e-6f);
        REQUIRE(std::abs(glm::dot(t, b)) < 1e-6f);
        REQUIRE(glm::length(t) == Approx(1.0f).epsilon(1e-5));
        REQUIRE(glm::length(b) == Approx(1.0f).epsilon(1e-5));
    }
}
