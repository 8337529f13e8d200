#include "unwrap/flatten.h"

#include <cmath>
#include <limits>

namespace vl {

namespace {

// One triangle's part of the energy: with g_j the gradient of vertex j's hat function in the
// triangle's own plane, the map's Cauchy-Riemann residuals are
//   r1 = Σ g_j.x u_j − g_j.y v_j   (∂u/∂x − ∂v/∂y),   r2 = Σ g_j.y u_j + g_j.x v_j   (∂u/∂y + ∂v/∂x),
// both zero where the triangle is only turned and scaled; its energy is area × (r1² + r2²).
// Only triangles with a free vertex take part; v[j] is that vertex's index among the free
// ones, or −1 for a fixed vertex (its uv in `held`).
struct Term {
    int32_t v[3];
    glm::dvec2 g[3];
    glm::dvec2 held[3];
    double area = 0.0;
};

// The residuals of a term for free uv x (fixed vertices at `held` when withHeld, else 0).
void residuals(const Term& t, const std::vector<glm::dvec2>& x, bool withHeld, double& r1, double& r2) {
    r1 = r2 = 0.0;
    for (int j = 0; j < 3; ++j) {
        const glm::dvec2 p = t.v[j] >= 0 ? x[size_t(t.v[j])] : (withHeld ? t.held[j] : glm::dvec2(0.0));
        r1 += t.g[j].x * p.x - t.g[j].y * p.y;
        r2 += t.g[j].y * p.x + t.g[j].x * p.y;
    }
}

// The energy's gradient over 2 at x, over the free vertices (the fixed ones' part included
// when withHeld; without it, H x).
void gradient(const std::vector<Term>& terms, const std::vector<glm::dvec2>& x, bool withHeld, std::vector<glm::dvec2>& out) {
    std::fill(out.begin(), out.end(), glm::dvec2(0.0));
    for (const Term& t : terms) {
        double r1, r2;
        residuals(t, x, withHeld, r1, r2);
        r1 *= t.area;
        r2 *= t.area;
        for (int j = 0; j < 3; ++j)
            if (t.v[j] >= 0) out[size_t(t.v[j])] += glm::dvec2(r1 * t.g[j].x + r2 * t.g[j].y, -r1 * t.g[j].y + r2 * t.g[j].x);
    }
}

double dot(const std::vector<glm::dvec2>& a, const std::vector<glm::dvec2>& b) {
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i) sum += a[i].x * b[i].x + a[i].y * b[i].y;
    return sum;
}

}  // namespace

void flattenConformal(FlattenProblem& problem, int iterations) {
    const size_t n = problem.positions.size();
    if (n == 0) return;
    std::vector<uint8_t> fixed = problem.fixed;
    fixed.resize(n, 0);
    size_t fixedCount = 0;
    for (uint8_t f : fixed) fixedCount += f ? 1 : 0;
    if (fixedCount < 2) {
        // Two pins along the guess's wider axis: the ends of the piece.
        glm::dvec2 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
        for (const glm::dvec2& p : problem.uv) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        const int axis = hi.x - lo.x >= hi.y - lo.y ? 0 : 1;
        size_t first = 0, last = 0;
        for (size_t i = 1; i < n; ++i) {
            if (problem.uv[i][axis] < problem.uv[first][axis]) first = i;
            if (problem.uv[i][axis] > problem.uv[last][axis]) last = i;
        }
        if (first == last) return;
        fixed.assign(n, 0);
        fixed[first] = fixed[last] = 1;
    }
    std::vector<int32_t> freeIndex(n, -1);
    std::vector<uint32_t> freeVertices;
    for (uint32_t i = 0; i < n; ++i)
        if (!fixed[i]) {
            freeIndex[i] = int32_t(freeVertices.size());
            freeVertices.push_back(i);
        }
    if (freeVertices.empty()) return;

    std::vector<Term> terms;
    for (size_t k = 0; k + 2 < problem.corners.size(); k += 3) {
        const uint32_t v[3] = {problem.corners[k], problem.corners[k + 1], problem.corners[k + 2]};
        if (fixed[v[0]] && fixed[v[1]] && fixed[v[2]]) continue;
        const glm::dvec3 &a = problem.positions[v[0]], &b = problem.positions[v[1]], &c = problem.positions[v[2]];
        const glm::dvec3 cross = glm::cross(b - a, c - a);
        const double twice = glm::length(cross);
        const double ab = glm::length(b - a);
        if (!(twice > 0.0) || !(ab > 0.0)) continue;
        Term t;
        // The triangle in its own plane, counterclockwise: a at the origin, b on +x.
        const glm::dvec3 e1 = (b - a) / ab, e2 = glm::cross(cross / twice, e1);
        const glm::dvec2 p[3] = {glm::dvec2(0.0), glm::dvec2(ab, 0.0), glm::dvec2(glm::dot(c - a, e1), glm::dot(c - a, e2))};
        for (int j = 0; j < 3; ++j) {
            const glm::dvec2 e = p[(j + 2) % 3] - p[(j + 1) % 3];  // the edge opposite vertex j
            t.g[j] = glm::dvec2(-e.y, e.x) / twice;
            t.v[j] = freeIndex[v[j]];
            t.held[j] = problem.uv[v[j]];
        }
        t.area = 0.5 * twice;
        terms.push_back(t);
    }
    if (terms.empty()) return;

    // Jacobi preconditioner: the diagonal of H (the same for u and v of a vertex).
    const size_t m = freeVertices.size();
    std::vector<double> diagonal(m, 0.0);
    for (const Term& t : terms)
        for (int j = 0; j < 3; ++j)
            if (t.v[j] >= 0) diagonal[size_t(t.v[j])] += t.area * glm::dot(t.g[j], t.g[j]);

    std::vector<glm::dvec2> x(m), r(m), z(m), p(m), hp(m);
    for (size_t i = 0; i < m; ++i) x[i] = problem.uv[freeVertices[i]];
    gradient(terms, x, true, r);
    for (size_t i = 0; i < m; ++i) {
        r[i] = diagonal[i] > 0.0 ? -r[i] : glm::dvec2(0.0);  // a vertex of zero-area triangles only keeps its guess
        z[i] = diagonal[i] > 0.0 ? r[i] / diagonal[i] : glm::dvec2(0.0);
    }
    p = z;
    double rz = dot(r, z);
    const double start = rz;
    for (int k = 0; k < iterations && rz > 1e-24 * start && rz > 0.0; ++k) {
        gradient(terms, p, false, hp);
        const double php = dot(p, hp);
        if (!(php > 0.0)) break;
        const double alpha = rz / php;
        for (size_t i = 0; i < m; ++i) {
            x[i] += alpha * p[i];
            r[i] -= alpha * hp[i];
            z[i] = diagonal[i] > 0.0 ? r[i] / diagonal[i] : glm::dvec2(0.0);
        }
        const double next = dot(r, z);
        const double beta = next / rz;
        rz = next;
        for (size_t i = 0; i < m; ++i) p[i] = z[i] + beta * p[i];
        if (problem.stop && (k + 1) % std::max(problem.checkEvery, 1) == 0) {
            for (size_t i = 0; i < m; ++i) problem.uv[freeVertices[i]] = x[i];
            if (problem.stop(problem.uv, k + 1)) return;
        }
    }
    for (size_t i = 0; i < m; ++i) problem.uv[freeVertices[i]] = x[i];
}

}  // namespace vl
