// Conformal flattening of a piece of surface (least squares conformal maps, Lévy et al. 2002):
// the 2D coordinates of its vertices that keep each triangle's angles as well as possible in
// the least-squares sense, every triangle weighted by its area. A developable surface (a
// cylinder, a folded strip, two walls meeting at a corner) unrolls onto the plane with no
// stretch, where a projection along one direction stretches it by 1/cos of its tilt; a curved
// surface spreads its area distortion over the whole piece instead of piling it at the rim.
//
// The solve is preconditioned conjugate gradients on the normal equations, in double, in one
// fixed order: the same input gives the same bytes on every run and at any thread count.
#pragma once

#include "core/math.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace vl {

struct FlattenProblem {
    std::vector<glm::dvec3> positions;      // the piece's vertices
    std::vector<uint32_t> corners;          // 3 per triangle, indices into positions
    std::vector<glm::dvec2> uv;             // the starting guess, one per vertex; the answer on return
    std::vector<uint8_t> fixed;             // 1: the vertex keeps its uv (at least 2 fixed vertices, or none)
    // Asked every checkEvery steps with the layout so far (every vertex) and the steps taken:
    // true stops the solve there (a layout good enough to use need not be the least-squares
    // one, and one far from it after many steps will not get there).
    std::function<bool(const std::vector<glm::dvec2>&, int)> stop;
    int checkEvery = 16;
};

// Solves for the free vertices' uv (at most `iterations` steps). With no vertex fixed, the two
// vertices farthest apart along the guess's wider axis are held where the guess has them
// (fixing the similarity LSCM leaves free). A vertex that only zero-area triangles touch keeps
// its guess.
void flattenConformal(FlattenProblem& problem, int iterations = 2000);

}  // namespace vl
