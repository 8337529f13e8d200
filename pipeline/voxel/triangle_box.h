// Triangle–voxel geometry for the voxelizer, in voxel units (world position / h), double
// precision: the separating axis test, Sutherland–Hodgman clipping against voxel slabs,
// and the walk that hands every voxel a triangle overlaps, with the piece of the triangle
// inside it. Voxel (i, j, k) is the closed box [i−½, i+½] × [j−½, j+½] × [k−½, k+½]
// (OpenVDB's convention, see voxel_scene.h).
#pragma once

#include "core/hostdev.h"
#include "core/math.h"

#include <cmath>

namespace vl {

using glm::dvec2;
using glm::dvec3;

// Akenine-Möller's separating axis test (13 axes: 3 box normals, the triangle normal, 9
// edge × box-axis products) of a triangle against the closed box [−half, half]³, vertices
// given relative to the box centre. Touching counts as overlapping: only a strict gap
// separates, so two triangles sharing an edge on a voxel face both reach the voxels there.
VL_HOSTDEV inline bool triangleBoxOverlap(const dvec3& v0, const dvec3& v1, const dvec3& v2, double half) {
    for (int a = 0; a < 3; ++a) {
        const double lo = glm::min(v0[a], glm::min(v1[a], v2[a]));
        const double hi = glm::max(v0[a], glm::max(v1[a], v2[a]));
        if (lo > half || hi < -half) return false;
    }
    const dvec3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
    const dvec3 n = glm::cross(e0, e1);
    const double planeRadius = half * (std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z));
    if (std::fabs(glm::dot(n, v0)) > planeRadius) return false;

    // Axis = unit box axis × edge; p = projections of the three vertices, r = box radius.
    auto separated = [&](const dvec3& axis) {
        const double p0 = glm::dot(axis, v0), p1 = glm::dot(axis, v1), p2 = glm::dot(axis, v2);
        const double r = half * (std::fabs(axis.x) + std::fabs(axis.y) + std::fabs(axis.z));
        return glm::min(p0, glm::min(p1, p2)) > r || glm::max(p0, glm::max(p1, p2)) < -r;
    };
    const dvec3 edges[3] = {e0, e1, e2};
    for (const dvec3& e : edges) {
        if (separated(dvec3(0.0, -e.z, e.y))) return false;  // X × e
        if (separated(dvec3(e.z, 0.0, -e.x))) return false;  // Y × e
        if (separated(dvec3(-e.y, e.x, 0.0))) return false;  // Z × e
    }
    return true;
}

// A convex polygon from clipping one triangle; every vertex carries the barycentrics
// (b1, b2) of the original triangle, so material inputs can be sampled anywhere on it.
// A triangle clipped by 6 planes has at most 3 + 6 vertices.
struct ClipPolygon {
    static constexpr int kMaxVertices = 9;
    dvec3 position[kMaxVertices];
    dvec2 barycentric[kMaxVertices];
    int count = 0;

    VL_HOSTDEV static ClipPolygon triangle(const dvec3& q0, const dvec3& q1, const dvec3& q2) {
        ClipPolygon p;
        p.position[0] = q0, p.position[1] = q1, p.position[2] = q2;
        p.barycentric[0] = dvec2(0.0, 0.0), p.barycentric[1] = dvec2(1.0, 0.0), p.barycentric[2] = dvec2(0.0, 1.0);
        p.count = 3;
        return p;
    }
};

// Sutherland–Hodgman against one half-space: keeps sign·(x[axis] − bound) ≥ 0 (closed), so
// sign = +1 keeps x ≥ bound and −1 keeps x ≤ bound. New vertices land exactly on the plane.
VL_HOSTDEV inline ClipPolygon clipHalfSpace(const ClipPolygon& in, int axis, double bound, double sign) {
    ClipPolygon out;
    for (int i = 0; i < in.count; ++i) {
        const int next = i + 1 == in.count ? 0 : i + 1;
        const double da = sign * (in.position[i][axis] - bound);
        const double db = sign * (in.position[next][axis] - bound);
        if (da >= 0.0) {
            out.position[out.count] = in.position[i];
            out.barycentric[out.count] = in.barycentric[i];
            ++out.count;
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            const double t = da / (da - db);
            dvec3 p = in.position[i] + t * (in.position[next] - in.position[i]);
            p[axis] = bound;
            out.position[out.count] = p;
            out.barycentric[out.count] = in.barycentric[i] + t * (in.barycentric[next] - in.barycentric[i]);
            ++out.count;
        }
    }
    return out;
}

// The part of `in` inside the closed slab lo ≤ x[axis] ≤ hi.
VL_HOSTDEV inline ClipPolygon clipSlab(const ClipPolygon& in, int axis, double lo, double hi) {
    return clipHalfSpace(clipHalfSpace(in, axis, lo, 1.0), axis, hi, -1.0);
}

// Area of a planar polygon with unit normal n (fan from vertex 0); ≥ 0.
VL_HOSTDEV inline double polygonArea(const ClipPolygon& p, const dvec3& n) {
    double twice = 0.0;
    for (int i = 1; i + 1 < p.count; ++i)
        twice += glm::dot(n, glm::cross(p.position[i] - p.position[0], p.position[i + 1] - p.position[0]));
    return glm::max(0.0, 0.5 * twice);
}

// Index range of closed voxels [i−½, i+½] that meet [lo, hi] on one axis.
VL_HOSTDEV inline void voxelRange(double lo, double hi, int& first, int& last) {
    first = static_cast<int>(std::ceil(lo - 0.5));
    last = static_cast<int>(std::floor(hi + 0.5));
}

// Calls visit(ivec3 voxel, const ClipPolygon& piece, double pieceArea) once for every voxel
// that the triangle q0 q1 q2 (voxel units, unit normal n) overlaps by the separating axis
// test and leaves a piece of positive area in, in (x, y, z) order. Work is proportional to
// the voxels touched: the triangle is clipped to x slabs, each piece to y slabs, then z.
//
// Two rules keep the pieces a partition of the triangle, so Σ piece area = triangle area:
// - A voxel the triangle only touches (along an edge or at a point of the voxel's boundary)
//   gets a zero-area piece and is not visited. The closed boxes of the visited voxels still
//   cover every point of the triangle, so skipping them opens no crack.
// - A triangle lying exactly in a voxel face plane would belong to the voxels on both
//   sides; it goes to the one behind it (the side its normal points away from), so a wall
//   lying on a face fills one voxel layer fully rather than two layers half.
template <typename Visit>
VL_HOSTDEV void forEachVoxelPiece(const dvec3& q0, const dvec3& q1, const dvec3& q2, const dvec3& n,
                                  Visit&& visit) {
    const dvec3 lower = glm::min(q0, glm::min(q1, q2));
    const dvec3 upper = glm::max(q0, glm::max(q1, q2));
    // On a face plane (all three vertices at the same half-integer): keep only the voxel behind.
    auto restrictToBehind = [&](int axis, int& first, int& last) {
        if (lower[axis] != upper[axis]) return;
        const double shifted = lower[axis] + 0.5;
        if (shifted != std::floor(shifted)) return;
        const int face = static_cast<int>(shifted);  // plane between voxels face−1 and face
        first = last = n[axis] > 0.0 ? face - 1 : face;
    };
    auto rangeOf = [&](const ClipPolygon& poly, int axis, int& first, int& last) {
        double lo = poly.position[0][axis], hi = lo;
        for (int v = 1; v < poly.count; ++v) {
            lo = glm::min(lo, poly.position[v][axis]);
            hi = glm::max(hi, poly.position[v][axis]);
        }
        voxelRange(lo, hi, first, last);
        restrictToBehind(axis, first, last);
    };

    const ClipPolygon triangle = ClipPolygon::triangle(q0, q1, q2);
    int i0, i1;
    rangeOf(triangle, 0, i0, i1);
    for (int i = i0; i <= i1; ++i) {
        const ClipPolygon px = clipSlab(triangle, 0, i - 0.5, i + 0.5);
        if (px.count < 3) continue;
        int j0, j1;
        rangeOf(px, 1, j0, j1);
        for (int j = j0; j <= j1; ++j) {
            const ClipPolygon pxy = clipSlab(px, 1, j - 0.5, j + 0.5);
            if (pxy.count < 3) continue;
            int k0, k1;
            rangeOf(pxy, 2, k0, k1);
            for (int k = k0; k <= k1; ++k) {
                const dvec3 centre(i, j, k);
                if (!triangleBoxOverlap(q0 - centre, q1 - centre, q2 - centre, 0.5)) continue;
                const ClipPolygon piece = clipSlab(pxy, 2, k - 0.5, k + 0.5);
                if (piece.count < 3) continue;
                const double area = polygonArea(piece, n);
                if (area > 0.0) visit(ivec3(i, j, k), piece, area);
            }
        }
    }
}

}  // namespace vl
