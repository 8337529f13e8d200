// Fixed cone layouts for diffuse irradiance: E(p, n) ≈ π Σ_k w_k L_k, L_k the radiance a
// cone gathers, Σ_k w_k = 1.
//
// Directions (local frame, +Z = the normal) sit in equal-area rings: a cone along the normal,
// then rings of n_r cones whose bands each hold n_r/N of the hemisphere's solid angle, every
// cone at its band's mean height z (alternate rings staggered by half a spacing):
//   6 = 1 + 5,  16 = 1 + 6 + 9,  32 = 1 + 7 + 11 + 13 (near-square cells in each ring).
// Weights are the cosine-weighted solid angle of each cone's Voronoi cell on the hemisphere
// (the directions closer to it than to any other cone), divided by π:
//   w_k = (1/π) ∫_{cell_k} cos θ dω.
// They are found by quadrature: cos θ dω = ½ d(z²) dφ, so a midpoint grid uniform in (z², φ)
// has equal cosine-weighted measure per point; w_k = (points nearest cone k) / (all points).
// Σ w_k = 1 holds by construction, hence a uniform environment of radiance L gives E = π·L
// exactly, and a piecewise-constant radiance over the cells is integrated exactly.
#pragma once

#include "core/math.h"

#include <vector>

namespace vl {

struct ConeSet {
    static constexpr int kMaxCones = 32;
    int count = 0;
    float defaultHalfAngle = 0.0f;  // radians: cap solid angle 2π(1 − cos α) = 2π/count
    vec3 directions[kMaxCones] = {};  // unit, local frame, +Z = normal
    float weights[kMaxCones] = {};    // Σ = 1
};

// The set with 6, 16 or 32 cones (built once, then shared). SettingsError for other counts.
const ConeSet& coneSet(int count);

// The equal-area ring directions for `count` (6, 16 or 32) before weighting.
std::vector<vec3> coneDirections(int count);

// w_k = (1/π) ∫_{Voronoi cell of k} cos θ dω by the (z², φ) midpoint quadrature with
// `resolution`² points; ties go to the lower index. Exposed so tests can check it.
std::vector<float> cosineCellWeights(const std::vector<vec3>& directions, int resolution);

}  // namespace vl
