#include "cone/cone_set.h"
#include "cone/cone_settings.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"

#include <catch2/catch.hpp>

#include <map>

#include <cmath>

using namespace vl;

namespace {

size_t nearestCone(const ConeSet& set, const vec3& d) {
    size_t best = 0;
    for (int k = 1; k < set.count; ++k)
        if (glm::dot(set.directions[k], d) > glm::dot(set.directions[best], d)) best = size_t(k);
    return best;
}

}  // namespace

TEST_CASE("cone sets have unit directions in the hemisphere and weights summing to one", "[cone]") {
    for (int count : {6, 16, 32}) {
        INFO(count << " cones");
        const ConeSet& set = coneSet(count);
        REQUIRE(set.count == count);
        double sum = 0.0;
        for (int k = 0; k < count; ++k) {
            CHECK(glm::length(set.directions[k]) == Approx(1.0f).epsilon(1e-6));
            CHECK(set.directions[k].z > 0.0f);
            CHECK(set.weights[k] > 0.0f);
            sum += set.weights[k];
        }
        CHECK(sum == Approx(1.0).epsilon(1e-6));
        CHECK(set.directions[0] == vec3(0, 0, 1));
        // Default aperture: a cap of one cone's share of the hemisphere, 2π(1 − cos α) = 2π/N.
        CHECK(2.0 * M_PI * (1.0 - std::cos(double(set.defaultHalfAngle))) == Approx(2.0 * M_PI / count).epsilon(1e-5));
    }
    CHECK(glm::degrees(coneSet(6).defaultHalfAngle) == Approx(33.557f).epsilon(1e-3));
    CHECK(glm::degrees(coneSet(16).defaultHalfAngle) == Approx(20.364f).epsilon(1e-3));
    CHECK(glm::degrees(coneSet(32).defaultHalfAngle) == Approx(14.362f).epsilon(1e-3));
    CHECK_THROWS_AS(coneSet(7), SettingsError);
}

TEST_CASE("cone weights are the cosine-weighted measure of each cone's cell", "[cone]") {
    // Independent estimate: cosine-distributed random directions (pdf cos θ / π), each
    // counted for its nearest cone; the fraction per cone estimates w_k with a binomial
    // standard error √(w(1−w)/M) ≤ 0.0005 for M = 10⁶.
    constexpr int kSamples = 1000000;
    for (int count : {6, 16, 32}) {
        INFO(count << " cones");
        const ConeSet& set = coneSet(count);
        std::vector<int> hits(size_t(count), 0);
        for (int i = 0; i < kSamples; ++i) {
            Pcg32 rng = Pcg32::forItem(uint64_t(i), 0, uint64_t(count));
            const float u = rng.next1D();
            const vec3 d = sampleCosineHemisphere(vec2(u, rng.next1D()));
            ++hits[nearestCone(set, d)];
        }
        for (int k = 0; k < count; ++k) {
            INFO("cone " << k);
            CHECK(double(hits[size_t(k)]) / kSamples == Approx(set.weights[k]).margin(0.0025));
        }
        // First moment of the cosine lobe: ∫ ω cos θ dω / π = (0, 0, 2/3). The cones' weighted
        // mean direction matches it up to the cells' discretisation (measured 0.604, 0.642,
        // 0.655 for 6, 16, 32 cones: the centres sit above their cells' cosine centroids).
        vec3 mean(0.0f);
        for (int k = 0; k < count; ++k) mean += set.weights[k] * set.directions[k];
        CHECK(std::abs(mean.x) < 1e-4f);
        CHECK(std::abs(mean.y) < 1e-4f);
        CHECK(mean.z == Approx(2.0 / 3.0).epsilon(count == 6 ? 0.1 : 0.04));
    }
}

TEST_CASE("the tabulated cone weights are the quadrature's, averaged over each ring", "[cone]") {
    // A ring's cones are rotations of one another, so their exact weights are equal; the
    // quadrature grid's φ spacing does not share the rings' symmetry, so its per-cone values
    // differ slightly and their ring mean is what coneSet tabulates.
    const std::map<int, std::vector<int>> rings = {{6, {1, 5}}, {16, {1, 6, 9}}, {32, {1, 7, 11, 13}}};
    for (const auto& [count, ringCounts] : rings) {
        INFO(count << " cones");
        const std::vector<float> quadrature = cosineCellWeights(coneDirections(count), 1024);
        const ConeSet& set = coneSet(count);
        size_t first = 0;
        for (int n : ringCounts) {
            double sum = 0.0;
            for (size_t k = first; k < first + size_t(n); ++k) sum += quadrature[k];
            for (size_t k = first; k < first + size_t(n); ++k) CHECK(set.weights[k] == Approx(sum / n).epsilon(1e-6));
            first += size_t(n);
        }
        CHECK(first == size_t(count));
    }
}

TEST_CASE("cone weights converge under quadrature refinement", "[cone]") {
    const std::vector<vec3> directions = coneDirections(16);
    const std::vector<float> coarse = cosineCellWeights(directions, 128);
    const std::vector<float> fine = cosineCellWeights(directions, 512);
    double sumCoarse = 0.0, sumFine = 0.0;
    for (size_t k = 0; k < directions.size(); ++k) {
        CHECK(coarse[k] == Approx(fine[k]).margin(2e-3));
        sumCoarse += coarse[k];
        sumFine += fine[k];
    }
    CHECK(sumCoarse == Approx(1.0).epsilon(1e-6));
    CHECK(sumFine == Approx(1.0).epsilon(1e-6));
    // A single cone along the normal owns the whole hemisphere.
    CHECK(cosineCellWeights({vec3(0, 0, 1)}, 64) == std::vector<float>{1.0f});
    // Two cones mirrored about the normal split it evenly.
    const std::vector<float> halves = cosineCellWeights({glm::normalize(vec3(1, 0, 1)), glm::normalize(vec3(-1, 0, 1))}, 256);
    CHECK(halves[0] == Approx(0.5f).margin(1e-6));
}

TEST_CASE("cone settings are validated with a message naming the setting", "[cone]") {
    CHECK_NOTHROW(validateConeSettings(ConeSettings{}));
    ConeSettings s;
    s.apertureDegrees = -5.0f;
    CHECK_THROWS_WITH(validateConeSettings(s, "job.json scene 2"),
                      Catch::Contains("job.json scene 2") && Catch::Contains("cone aperture -5"));
    s = ConeSettings{};
    s.apertureDegrees = 90.0f;
    CHECK_THROWS_AS(validateConeSettings(s), SettingsError);
    s = ConeSettings{};
    s.apertureDegrees = std::nanf("");
    CHECK_THROWS_AS(validateConeSettings(s), SettingsError);
    s = ConeSettings{};
    s.coneCount = 8;
    CHECK_THROWS_WITH(validateConeSettings(s), Catch::Contains("cone count 8"));
    s = ConeSettings{};
    s.stepFactor = 0.0f;
    CHECK_THROWS_WITH(validateConeSettings(s), Catch::Contains("step factor"));
    s = ConeSettings{};
    s.startOffset = -1.0f;
    CHECK_THROWS_WITH(validateConeSettings(s), Catch::Contains("start offset"));
    s = ConeSettings{};
    s.maxDistance = std::numeric_limits<float>::infinity();
    CHECK_THROWS_WITH(validateConeSettings(s), Catch::Contains("max distance"));
}
