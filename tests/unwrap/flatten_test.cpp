// Conformal flattening (unwrap/flatten.h): a developable surface unrolls with no stretch.
#include "unwrap/flatten.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace vl;

namespace {

// Flattened area over 3D area of each triangle (signed: negative where folded over).
std::vector<double> areaRatios(const FlattenProblem& problem) {
    std::vector<double> ratios;
    for (size_t k = 0; k + 2 < problem.corners.size(); k += 3) {
        const glm::dvec3 &a = problem.positions[problem.corners[k]], &b = problem.positions[problem.corners[k + 1]],
                         &c = problem.positions[problem.corners[k + 2]];
        const glm::dvec2 &p = problem.uv[problem.corners[k]], &q = problem.uv[problem.corners[k + 1]],
                         &r = problem.uv[problem.corners[k + 2]];
        const double flat = 0.5 * ((q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x));
        ratios.push_back(flat / (0.5 * glm::length(glm::cross(b - a, c - a))));
    }
    return ratios;
}

double spread(const std::vector<double>& ratios) {
    return *std::max_element(ratios.begin(), ratios.end()) / *std::min_element(ratios.begin(), ratios.end());
}

}  // namespace

TEST_CASE("A cylinder's side flattens conformally with no stretch, from its projection", "[unwrap]") {
    // 140° of a cylinder (normals from 20° to 160° off the projection axis), started from its
    // projection along that axis, which shrinks the triangles near the ends to a third.
    FlattenProblem problem;
    const int nx = 28, ny = 8;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            const double angle = glm::radians(20.0 + 140.0 * i / nx);
            const glm::dvec3 p(std::cos(angle), std::sin(angle), double(j) / ny);
            problem.positions.push_back(p);
            problem.uv.push_back(glm::dvec2(-p.x, p.z));  // along −y: counter-clockwise as the surface
        }
    const auto at = [&](int i, int j) { return uint32_t(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
            problem.corners.insert(problem.corners.end(),
                                   {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    const std::vector<double> before = areaRatios(problem);
    CHECK(*std::min_element(before.begin(), before.end()) > 0.0);
    CHECK(spread(before) > 2.5);

    flattenConformal(problem, 5000);
    const std::vector<double> after = areaRatios(problem);
    CHECK(*std::min_element(after.begin(), after.end()) > 0.0);  // nothing folded over
    CHECK(spread(after) < 1.001);
    // The arc unrolled straight: its length over its height is the angle in radians.
    const double along = glm::length(problem.uv[at(nx, 0)] - problem.uv[at(0, 0)]);
    const double up = glm::length(problem.uv[at(0, ny)] - problem.uv[at(0, 0)]);
    CHECK(along / up == Approx(glm::radians(140.0)).epsilon(2e-3));
}

TEST_CASE("Fixed vertices keep their place; the free ones follow the surface", "[unwrap]") {
    // A square folded 90° along its middle: the first half held where it lies, the second
    // half's free corners unfold it into one flat 2 × 1 rectangle.
    FlattenProblem problem;
    problem.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, -1}, {1, 1, -1}};
    problem.corners = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
    problem.uv = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1.2, 0.3}, {1.1, 0.8}};
    problem.fixed = {1, 1, 1, 1, 0, 0};
    flattenConformal(problem, 1000);
    CHECK(problem.uv[0] == glm::dvec2(0, 0));
    CHECK(problem.uv[2] == glm::dvec2(1, 1));
    CHECK(problem.uv[4].x == Approx(2.0).margin(1e-6));
    CHECK(problem.uv[4].y == Approx(0.0).margin(1e-6));
    CHECK(problem.uv[5].x == Approx(2.0).margin(1e-6));
    CHECK(problem.uv[5].y == Approx(1.0).margin(1e-6));
}
