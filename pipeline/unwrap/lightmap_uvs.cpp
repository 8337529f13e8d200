#include "unwrap/lightmap_uvs.h"

#include "core/error.h"
#include "unwrap/flatten.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <queue>
#include <set>
#include <tuple>
#include <unordered_map>

namespace vl {

namespace {

// How far (in texels) a chart's corners stay from the edges of the texels its padding begins
// at: beyond a float uv's rounding at kMaxAtlasSide (2^-24 × 8192 = 5e-4 texel), so no corner
// read back from TEXCOORD_1 lands in the padding.
constexpr double kChartInset = 1.0 / 256.0;
constexpr float kTouchSlack = 1.0f / 512.0f;
// The texel size by profiles is searched within [kProfileBracket, 1] of the rectangles' in
// kProfileSteps bisections: to 0.6% of it.
constexpr double kProfileBracket = 0.8;
constexpr int kProfileSteps = 5;
// A merge may leave the union's bounding rectangle, in texels with its padding at the texel
// size the charts are merged for, at most this much larger than its parts' two together:
// charts that branch out pack worse than their parts did, while two small charts that join
// save a padding.
constexpr double kMergeRectangleSlack = 1.1;
// Past the length cap (kMergeLengthShare), a merge may make the longer part this much longer:
// a lip folded off a face's long side, not a room's walls unrolled.
constexpr double kMergeLengthGrowth = 1.05;
// Conjugate-gradient steps of a merge's flattening at most: the parts' own layouts are the
// start, so the solve mostly has to settle the seam between them.
constexpr int kMergeIterations = 400;
// A merge's solve gives up after this many steps while its stretch is above this many times
// the bound: such solves seldom end within it, and letting each run its course costs much UV
// time for a few more merges (docs/atlas.md).
constexpr int kHopelessSteps = 32;
constexpr double kHopelessStretch = 1.15;
// The whole union is solved only where the layout with big's vertices held stretches less than
// this many times the bound (and folds nothing): few of the solves that start further off come
// within it (docs/atlas.md, "How the charts are made").
constexpr double kFullSolveStretch = 1.5;

// One mesh's triangles, welded by position (glTF splits vertices at every seam of their other
// attributes).
struct Topology {
    std::vector<uint32_t> weldedId;  // per mesh vertex
    std::vector<glm::dvec3> welded;  // per welded vertex
    std::unordered_map<uint64_t, std::vector<uint32_t>> edges;
    std::vector<vec3> normal;
    std::vector<float> area;
    const Mesh* mesh = nullptr;
    uint32_t corner(uint32_t t, int k) const { return weldedId[mesh->indices[3 * size_t(t) + size_t(k)]]; }
};

uint64_t edgeKey(uint32_t a, uint32_t b) {
    if (a > b) std::swap(a, b);
    return (uint64_t(a) << 32) | b;
}

struct PositionHash {
    size_t operator()(const vec3& p) const {
        // −0 and +0 weld (they compare equal): + 0.0f makes −0 +0 before the bits are read.
        const vec3 q = p + vec3(0.0f);
        uint32_t bits[3];
        std::memcpy(bits, &q, sizeof bits);
        return (size_t(bits[0]) * 73856093u) ^ (size_t(bits[1]) * 19349663u) ^ (size_t(bits[2]) * 83492791u);
    }
};

Topology meshTopology(const Mesh& mesh) {
    Topology topo;
    topo.mesh = &mesh;
    std::unordered_map<vec3, uint32_t, PositionHash> welded;
    topo.weldedId.resize(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const auto [it, added] = welded.emplace(mesh.positions[v], uint32_t(welded.size()));
        if (added) topo.welded.push_back(glm::dvec3(mesh.positions[v]));
        topo.weldedId[v] = it->second;
    }
    const size_t triangles = mesh.triangleCount();
    topo.normal.resize(triangles);
    topo.area.resize(triangles);
    for (uint32_t t = 0; t < triangles; ++t) {
        const uint32_t* i = &mesh.indices[3 * size_t(t)];
        const vec3 cross = glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]], mesh.positions[i[2]] - mesh.positions[i[0]]);
        topo.area[t] = 0.5f * glm::length(cross);
        topo.normal[t] = topo.area[t] > 0.0f ? cross / (2.0f * topo.area[t]) : vec3(0.0f);
        for (int k = 0; k < 3; ++k) topo.edges[edgeKey(topo.corner(t, k), topo.corner(t, (k + 1) % 3))].push_back(t);
    }
    return topo;
}

// Whether triangles t and u, which share the edge between welded vertices a and b, meet at a
// hard crease: folded by more than acos(minFoldCos), and shaded apart there (their vertex
// normals at an end differ by more than kSmoothShadingDegrees, or the mesh has none). A
// smooth-shaded fold is lit as one surface and may stay inside a chart.
bool hardCrease(const Topology& topo, uint32_t t, uint32_t u, uint32_t a, uint32_t b, float minFoldCos) {
    if (glm::dot(topo.normal[t], topo.normal[u]) >= minFoldCos) return false;
    const Mesh& mesh = *topo.mesh;
    if (mesh.normals.size() != mesh.positions.size()) return true;
    const float smooth = std::cos(glm::radians(kSmoothShadingDegrees));
    const auto normalAt = [&](uint32_t triangle, uint32_t welded) {
        for (int k = 0; k < 3; ++k)
            if (topo.corner(triangle, k) == welded) return mesh.normals[mesh.indices[3 * size_t(triangle) + size_t(k)]];
        return vec3(0.0f);
    };
    return glm::dot(normalAt(t, a), normalAt(u, a)) < smooth || glm::dot(normalAt(t, b), normalAt(u, b)) < smooth;
}

struct Chart {
    uint32_t mesh = 0;
    std::vector<uint32_t> triangles;  // the mesh's
    std::vector<uint32_t> vertices;   // welded vertices
    std::vector<uint32_t> corners;    // 3 per triangle: indices into vertices
    std::vector<vec2> coords;         // per vertex: where it lies flattened, in scene units
    double area = 0.0;                // in 3D
    vec2 lower{0.0f}, upper{0.0f};    // its extent, once turned (measureChart)
    double projectedArea = 0.0;
    bool turned = false;  // packed with U along the atlas's v
    glm::ivec2 origin{0};  // texel of its rectangle's corner
    glm::ivec2 size{0};    // rectangle in texels, padding included, after `turned`
    int orientation = -1;  // profile packing: 0 as is, 1 half-turned, 2 transposed, 3 both; -1 rectangle packing
    glm::ivec2 texels{0};  // texels its footprint spans along U and V
};

// Where a point of the chart (in texels from the chart's lower corner, inset) lands in the
// atlas, for a chart packed by its profile.
vec2 placedOnAtlas(const Chart& chart, vec2 local) {
    const vec2 n(chart.texels);
    switch (chart.orientation) {
    case 1: local = n - local; break;
    case 2: local = vec2(local.y, local.x); break;
    case 3: local = vec2(n.y - local.y, n.x - local.x); break;
    default: break;
    }
    return vec2(chart.origin) + vec2(float(kPaddingTexels)) + local;
}

// Triangle i of a chart (its i-th, not the mesh's), flattened.
void chartTriangle(const Chart& chart, size_t i, vec2 (&p)[3]) {
    for (int k = 0; k < 3; ++k) p[k] = chart.coords[chart.corners[3 * i + size_t(k)]];
}

double area2d(const vec2 (&p)[3]) {
    return 0.5 * std::abs(double(p[1].x - p[0].x) * (p[2].y - p[0].y) - double(p[1].y - p[0].y) * (p[2].x - p[0].x));
}

// Whether two triangles of a plane overlap in area: no edge normal of either separates them
// by more than `slack` (triangles that share an edge or a corner only touch). In double,
// about a's first corner: with coordinates metres from the origin, dot products in floats err
// by 1e-7 m, more than the slack, so two triangles sharing an edge could read as overlapping
// (small triangles far from the origin then come out as thousands of one-triangle charts:
// docs/atlas.md).
bool overlapIn2d(const vec2 (&a)[3], const vec2 (&b)[3], float slack) {
    // Boxes apart by more than the slack: apart (most pairs a grid cell holds).
    const vec2 loA = glm::min(a[0], glm::min(a[1], a[2])), hiA = glm::max(a[0], glm::max(a[1], a[2]));
    const vec2 loB = glm::min(b[0], glm::min(b[1], b[2])), hiB = glm::max(b[0], glm::max(b[1], b[2]));
    const float margin = 2.0f * slack + 1e-6f * std::max({std::abs(loA.x), std::abs(loA.y), std::abs(hiA.x), std::abs(hiA.y)});
    if (hiA.x + margin < loB.x || hiB.x + margin < loA.x || hiA.y + margin < loB.y || hiB.y + margin < loA.y) return false;
    glm::dvec2 da[3], db[3];
    for (int k = 0; k < 3; ++k) {
        da[k] = glm::dvec2(a[k]) - glm::dvec2(a[0]);
        db[k] = glm::dvec2(b[k]) - glm::dvec2(a[0]);
    }
    const glm::dvec2* sides[2] = {da, db};
    for (const glm::dvec2* tri : sides)
        for (int k = 0; k < 3; ++k) {
            const glm::dvec2 edge = tri[(k + 1) % 3] - tri[k];
            const glm::dvec2 axis(-edge.y, edge.x);
            const double length = glm::length(axis);
            if (!(length > 0.0)) continue;
            double loA = std::numeric_limits<double>::max(), hiA = -loA, loB = loA, hiB = -loA;
            for (int j = 0; j < 3; ++j) {
                const double pa = glm::dot(da[j], axis) / length, pb = glm::dot(db[j], axis) / length;
                loA = std::min(loA, pa);
                hiA = std::max(hiA, pa);
                loB = std::min(loB, pb);
                hiB = std::max(hiB, pb);
            }
            if (hiA <= loB + slack || hiB <= loA + slack) return false;
        }
    return true;
}

// Flattened triangles bucketed by a grid of cells about twice a triangle's size, to find the
// ones a new triangle would overlap. A triangle spanning more than kMaxCells cells (a wall's
// two triangles among a cushion's thousands) is kept in a list of its own that every query
// scans, and a query that large scans every triangle: filling its cells would cost more.
class OverlapGrid {
public:
    explicit OverlapGrid(float cell) : cell_(std::max(cell, 1e-12f)), slack_(1e-5f * cell_) {}
    // Whether p overlaps a triangle held.
    bool overlaps(const vec2 (&p)[3]) const {
        const auto hits = [&](const Held& o) { return overlapIn2d(p, o.p, slack_); };
        if (cellCount(p) > kMaxCells) return std::any_of(all_.begin(), all_.end(), hits);
        if (std::any_of(large_.begin(), large_.end(), hits)) return true;
        bool found = false;
        cells(p, [&](uint64_t key) {
            if (found) return;
            const auto it = grid_.find(key);
            if (it != grid_.end()) found = std::any_of(it->second.begin(), it->second.end(), hits);
        });
        return found;
    }
    void hold(const vec2 (&p)[3]) {
        Held h;
        for (int k = 0; k < 3; ++k) h.p[k] = p[k];
        all_.push_back(h);
        if (cellCount(p) > kMaxCells)
            large_.push_back(h);
        else
            cells(p, [&](uint64_t key) { grid_[key].push_back(h); });
    }
    void clear() {
        grid_.clear();
        large_.clear();
        all_.clear();
    }

private:
    static constexpr double kMaxCells = 64.0;
    struct Held {
        vec2 p[3];
    };
    double cellCount(const vec2 (&p)[3]) const {
        const vec2 lo = glm::min(p[0], glm::min(p[1], p[2])) / cell_, hi = glm::max(p[0], glm::max(p[1], p[2])) / cell_;
        return (std::floor(double(hi.x)) - std::floor(double(lo.x)) + 1.0) * (std::floor(double(hi.y)) - std::floor(double(lo.y)) + 1.0);
    }
    template <typename Visit>
    void cells(const vec2 (&p)[3], Visit&& visit) const {
        const vec2 lo = glm::min(p[0], glm::min(p[1], p[2])) / cell_, hi = glm::max(p[0], glm::max(p[1], p[2])) / cell_;
        for (int y = int(std::floor(lo.y)); y <= int(std::floor(hi.y)); ++y)
            for (int x = int(std::floor(lo.x)); x <= int(std::floor(hi.x)); ++x)
                visit((uint64_t(uint32_t(x)) << 32) | uint32_t(y));
    }
    float cell_, slack_;
    std::unordered_map<uint64_t, std::vector<Held>> grid_;
    std::vector<Held> large_, all_;
};

// The charts grown over a mesh (see the header), each projected along its first triangle's
// normal.
std::vector<Chart> growCharts(const Topology& topo, uint32_t meshIndex) {
    const size_t triangles = topo.area.size();
    std::vector<uint32_t> order(triangles);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return topo.area[a] > topo.area[b]; });
    const float minCos = std::cos(glm::radians(kChartAngleDegrees));
    std::vector<int32_t> chartOf(triangles, -1);
    std::vector<Chart> charts;
    std::vector<uint32_t> queue;
    // A chart refuses a triangle whose projection would overlap one it holds (a surface that
    // folds back under itself within the cone: docs/atlas.md); the refused triangle starts or
    // joins another chart.
    double totalArea = 0.0;
    for (float a : topo.area) totalArea += a;
    OverlapGrid grid(2.0f * std::sqrt(float(totalArea / double(std::max<size_t>(triangles, 1)))));
    vec3 axisU, axisV;
    const auto project = [&](uint32_t t, vec2 (&p)[3]) {
        for (int k = 0; k < 3; ++k) {
            const vec3 q = topo.mesh->positions[topo.mesh->indices[3 * size_t(t) + size_t(k)]];
            p[k] = vec2(glm::dot(q, axisU), glm::dot(q, axisV));
        }
    };
    for (uint32_t seed : order) {
        if (chartOf[seed] >= 0) continue;
        const int32_t c = static_cast<int32_t>(charts.size());
        charts.emplace_back();
        Chart& chart = charts.back();
        chart.mesh = meshIndex;
        const vec3 n = glm::length(topo.normal[seed]) > 0.0f ? topo.normal[seed] : vec3(0.0f, 0.0f, 1.0f);
        orthonormalBasis(n, axisU, axisV);
        chartOf[seed] = c;
        queue.assign(1, seed);
        grid.clear();
        vec2 p[3];
        if (topo.area[seed] > 0.0f) {
            project(seed, p);
            grid.hold(p);
        }
        for (size_t q = 0; q < queue.size(); ++q) {
            const uint32_t t = queue[q];
            chart.triangles.push_back(t);
            for (int k = 0; k < 3; ++k)
                for (uint32_t other : topo.edges.at(edgeKey(topo.corner(t, k), topo.corner(t, (k + 1) % 3)))) {
                    if (chartOf[other] >= 0) continue;
                    // A zero-area triangle projects to nothing wherever it goes.
                    if (topo.area[other] > 0.0f) {
                        if (!(glm::dot(topo.normal[other], n) >= minCos)) continue;
                        project(other, p);
                        if (grid.overlaps(p)) continue;
                        grid.hold(p);
                    }
                    chartOf[other] = c;
                    queue.push_back(other);
                }
        }
        // Its vertices, each projected once.
        std::unordered_map<uint32_t, uint32_t> local;
        for (uint32_t t : chart.triangles) {
            chart.area += topo.area[t];
            for (int k = 0; k < 3; ++k) {
                const uint32_t w = topo.corner(t, k);
                const auto [it, added] = local.emplace(w, uint32_t(chart.vertices.size()));
                if (added) {
                    chart.vertices.push_back(w);
                    const vec3 q(topo.welded[w]);
                    chart.coords.push_back(vec2(glm::dot(q, axisU), glm::dot(q, axisV)));
                }
                chart.corners.push_back(it->second);
            }
        }
    }
    return charts;
}

// The convex hull of points (Andrew's monotone chain), counter-clockwise.
std::vector<vec2> convexHull(std::vector<vec2> points) {
    std::sort(points.begin(), points.end(), [](const vec2& a, const vec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return points;
    const auto cross = [](const vec2& o, const vec2& a, const vec2& b) {
        return double(a.x - o.x) * double(b.y - o.y) - double(a.y - o.y) * double(b.x - o.x);
    };
    std::vector<vec2> hull(2 * points.size());
    size_t k = 0;
    for (size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    for (size_t i = points.size() - 1, lowerEnd = k + 1; i-- > 0;) {
        while (k >= lowerEnd && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    return hull;
}

// The smallest bounding rectangle of points: a side of it lies along an edge of their convex
// hull (Freeman and Shapira 1975). A principal-axes turn put a square wall at 45° (its
// corners' spread is the same along every axis) and doubled its rectangle.
struct Rectangle {
    float angle = 0.0f;      // the turn of its first side
    double area = 0.0;
    double longSide = 0.0, shortSide = 0.0;
};

Rectangle smallestRectangle(const std::vector<vec2>& points) {
    const std::vector<vec2> hull = convexHull(points);
    Rectangle best;
    best.area = std::numeric_limits<double>::max();
    for (size_t e = 0; e < hull.size(); ++e) {
        const vec2 d = hull[(e + 1) % hull.size()] - hull[e];
        if (!(glm::length(d) > 0.0f)) continue;
        const float a = std::atan2(d.y, d.x);
        const vec2 u(std::cos(a), std::sin(a)), v(-std::sin(a), std::cos(a));
        float lu = std::numeric_limits<float>::max(), hu = -lu, lv = lu, hv = -lu;
        for (const vec2& p : hull) {
            lu = std::min(lu, glm::dot(p, u));
            hu = std::max(hu, glm::dot(p, u));
            lv = std::min(lv, glm::dot(p, v));
            hv = std::max(hv, glm::dot(p, v));
        }
        const double area = double(hu - lu) * double(hv - lv);
        if (area < best.area * (1.0 - 1e-6)) {  // ties keep the first edge: the same turn on every run
            best.area = area;
            best.angle = a;
            best.longSide = std::max(double(hu - lu), double(hv - lv));
            best.shortSide = std::min(double(hu - lu), double(hv - lv));
        }
    }
    if (best.area == std::numeric_limits<double>::max()) {  // fewer than 3 distinct points
        best.area = 0.0;
        for (const vec2& p : hull)
            for (const vec2& q : hull) best.longSide = std::max(best.longSide, double(glm::length(p - q)));
    }
    return best;
}

// Texels a chart's rectangle of sides a × b takes in the atlas at texel size s, its padding
// included (as pack() counts them).
double paddedTexels(double a, double b, double s) {
    const auto texels = [&](double extent) { return std::floor(extent / s + 2.0 * kChartInset) + 1.0 + 2.0 * kPaddingTexels; };
    return texels(a) * texels(b);
}
double paddedTexels(const Rectangle& r, double s) { return paddedTexels(r.longSide, r.shortSide, s); }

// Turns a chart so that its bounding rectangle is the smallest, and measures it.
void measureChart(Chart& chart) {
    const Rectangle rectangle = smallestRectangle(chart.coords);
    const vec2 u(std::cos(rectangle.angle), std::sin(rectangle.angle)), v(-std::sin(rectangle.angle), std::cos(rectangle.angle));
    chart.lower = vec2(std::numeric_limits<float>::max());
    chart.upper = vec2(-std::numeric_limits<float>::max());
    for (vec2& p : chart.coords) {
        p = vec2(glm::dot(p, u), glm::dot(p, v));
        chart.lower = glm::min(chart.lower, p);
        chart.upper = glm::max(chart.upper, p);
    }
    chart.projectedArea = 0.0;
    for (size_t t = 0; t < chart.triangles.size(); ++t) {
        vec2 p[3];
        chartTriangle(chart, t, p);
        chart.projectedArea += area2d(p);
    }
}

// A part of a chart: the triangles marked `part`, with their layout (a part of a valid
// layout is valid).
Chart chartPart(const Topology& topo, const Chart& chart, const std::vector<int32_t>& pieceOf, int32_t part) {
    Chart out;
    out.mesh = chart.mesh;
    std::unordered_map<uint32_t, uint32_t> local;
    for (size_t i = 0; i < chart.triangles.size(); ++i) {
        if (pieceOf[i] != part) continue;
        out.triangles.push_back(chart.triangles[i]);
        out.area += topo.area[chart.triangles[i]];
        for (int k = 0; k < 3; ++k) {
            const uint32_t c = chart.corners[3 * i + size_t(k)];
            const auto [it, added] = local.emplace(c, uint32_t(out.vertices.size()));
            if (added) {
                out.vertices.push_back(chart.vertices[c]);
                out.coords.push_back(chart.coords[c]);
            }
            out.corners.push_back(it->second);
        }
    }
    return out;
}

// A chart whose rectangle is more than half empty (the top of a skirting board running round
// a room is a frame almost all empty, and profiles only nest charts from above, so nothing
// lands in its middle) is cut in two: the triangles nearer (along the chart) to one or the
// other of two triangles far apart, the first at one end of its rectangle's long side, the
// second the farthest from it; each part is cut again while it is more than half empty. The
// parts replace the chart where their rectangles, padding included at texel size s, take fewer
// texels than its own. A straight cut across the rectangle does not free a frame whose sides
// are each one long triangle: every cut has a side's triangle spanning it.
void splitWasteful(const Topology& topo, Chart chart, double s, std::vector<Chart>& out) {
    const Rectangle rectangle = smallestRectangle(chart.coords);
    const size_t n = chart.triangles.size();
    double flat = 0.0;
    std::vector<glm::dvec2> centre(n);
    for (size_t i = 0; i < n; ++i) {
        vec2 p[3];
        chartTriangle(chart, i, p);
        flat += area2d(p);
        centre[i] = (glm::dvec2(p[0]) + glm::dvec2(p[1]) + glm::dvec2(p[2])) / 3.0;
    }
    if (n < 2 || rectangle.area <= 2.0 * flat) {
        out.push_back(std::move(chart));
        return;
    }
    std::unordered_map<uint64_t, std::vector<uint32_t>> edges;
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k)
            edges[edgeKey(chart.corners[3 * i + size_t(k)], chart.corners[3 * i + size_t((k + 1) % 3)])].push_back(i);
    // Distances along the chart from a triangle: Dijkstra over triangles sharing an edge, steps
    // between their centres (ties: the lower triangle first).
    const auto distances = [&](uint32_t from) {
        std::vector<double> d(n, std::numeric_limits<double>::max());
        std::priority_queue<std::pair<double, uint32_t>, std::vector<std::pair<double, uint32_t>>, std::greater<>> queue;
        d[from] = 0.0;
        queue.push({0.0, from});
        while (!queue.empty()) {
            const auto [dist, i] = queue.top();
            queue.pop();
            if (dist > d[i]) continue;
            for (int k = 0; k < 3; ++k)
                for (uint32_t j : edges[edgeKey(chart.corners[3 * i + size_t(k)], chart.corners[3 * i + size_t((k + 1) % 3)])]) {
                    const double next = dist + glm::length(centre[j] - centre[i]);
                    if (next < d[j]) {
                        d[j] = next;
                        queue.push({next, j});
                    }
                }
        }
        return d;
    };
    // Along the rectangle's long side (its first side or the other).
    glm::dvec2 axis(std::cos(rectangle.angle), std::sin(rectangle.angle));
    {
        double lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()}, hi[2] = {-lo[0], -lo[1]};
        const glm::dvec2 other(-axis.y, axis.x);
        for (const vec2& p : chart.coords)
            for (int k = 0; k < 2; ++k) {
                const double d = glm::dot(glm::dvec2(p), k == 0 ? axis : other);
                lo[k] = std::min(lo[k], d);
                hi[k] = std::max(hi[k], d);
            }
        if (hi[1] - lo[1] > hi[0] - lo[0]) axis = other;
    }
    uint32_t first = 0;
    for (uint32_t i = 1; i < n; ++i)
        if (glm::dot(centre[i], axis) < glm::dot(centre[first], axis)) first = i;
    const std::vector<double> fromFirst = distances(first);
    uint32_t second = first;
    for (uint32_t i = 0; i < n; ++i)
        if (fromFirst[i] != std::numeric_limits<double>::max() && fromFirst[i] > fromFirst[second]) second = i;
    if (second == first) {
        out.push_back(std::move(chart));
        return;
    }
    const std::vector<double> fromSecond = distances(second);
    std::vector<int32_t> side(n);
    for (size_t i = 0; i < n; ++i) side[i] = fromSecond[i] < fromFirst[i] ? 1 : 0;
    std::vector<Chart> parts;
    for (int32_t part = 0; part < 2; ++part) splitWasteful(topo, chartPart(topo, chart, side, part), s, parts);
    double cost = 0.0;
    for (const Chart& part : parts) cost += paddedTexels(smallestRectangle(part.coords), s);
    if (cost < paddedTexels(rectangle, s)) {
        for (Chart& part : parts) out.push_back(std::move(part));
    } else {
        out.push_back(std::move(chart));
    }
}

// Merging neighbouring charts of one mesh (see the header).
class ChartMerger {
public:
    // s: about the texel size the charts will be packed at; lengthCap: see kMergeLengthShare.
    // keepCreases: charts meeting along a hard crease do not merge (kMergeFoldDegrees).
    ChartMerger(const Topology& topo, std::vector<Chart>& charts, double lengthCap, double s, bool keepCreases)
        : topo_(topo), charts_(charts), lengthCap_(lengthCap), texel_(s), keepCreases_(keepCreases),
          localOf_(topo.welded.size(), -1) {}

    void run() {
        const size_t n = charts_.size();
        alive_.assign(n, 1);
        version_.assign(n, 0);
        neighbours_.assign(n, {});
        rectangles_.resize(n);
        std::vector<uint32_t> chartOf(topo_.area.size());
        const float minFoldCos = std::cos(glm::radians(kMergeFoldDegrees));
        for (uint32_t c = 0; c < n; ++c) {
            for (uint32_t t : charts_[c].triangles) chartOf[t] = c;
            rectangles_[c] = smallestRectangle(charts_[c].coords);
        }
        // Neighbours and the length of edge they share, in the triangles' order.
        for (uint32_t t = 0; t < chartOf.size(); ++t)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = topo_.corner(t, k), b = topo_.corner(t, (k + 1) % 3);
                if (a > b) continue;  // each edge of each triangle once
                const double length = glm::length(topo_.welded[a] - topo_.welded[b]);
                for (uint32_t other : topo_.edges.at(edgeKey(a, b)))
                    if (chartOf[other] != chartOf[t]) {
                        neighbours_[chartOf[t]][chartOf[other]] += length;
                        neighbours_[chartOf[other]][chartOf[t]] += length;
                        if (keepCreases_ && hardCrease(topo_, t, other, a, b, minFoldCos))
                            creased_.insert(edgeKey(chartOf[t], chartOf[other]));
                    }
            }
        for (uint32_t c = 0; c < n; ++c) push(c);
        while (!queue_.empty()) {
            const Candidate candidate = queue_.top();
            queue_.pop();
            const uint32_t a = candidate.a, b = candidate.b;
            if (!alive_[a] || !alive_[b] || version_[a] != candidate.versionA || version_[b] != candidate.versionB) continue;
            if (failed_.count(edgeKey(a, b)) || creased_.count(edgeKey(a, b))) continue;
            const bool aBigger = charts_[a].area > charts_[b].area || (charts_[a].area == charts_[b].area && a < b);
            const uint32_t big = aBigger ? a : b, small = aBigger ? b : a;
            Chart merged;
            // A pair once refused is not tried again, even after one of them grows: a chart
            // with a hundred small neighbours would otherwise flatten again for each of them.
            if (!merge(charts_[big], charts_[small], rectangles_[big], rectangles_[small], merged)) {
                failed_.insert(edgeKey(a, b));
                continue;
            }
            charts_[big] = std::move(merged);
            rectangles_[big] = smallestRectangle(charts_[big].coords);
            charts_[small] = Chart();
            alive_[small] = 0;
            ++version_[big];
            for (const auto& [other, length] : neighbours_[small]) {
                if (other == big) continue;
                if (creased_.count(edgeKey(small, other))) creased_.insert(edgeKey(big, other));
                neighbours_[big][other] += length;
                neighbours_[other].erase(small);
                neighbours_[other][big] += length;
            }
            neighbours_[big].erase(small);
            neighbours_[small].clear();
            push(big);
        }
        std::vector<Chart> kept;
        for (uint32_t c = 0; c < n; ++c)
            if (alive_[c]) kept.push_back(std::move(charts_[c]));
        charts_ = std::move(kept);
    }

private:
    struct Candidate {
        double smallerArea, sharedLength;
        uint32_t a, b;  // a < b
        uint32_t versionA, versionB;
        // The priority queue's top is its largest: the smallest chart first, then the longest
        // shared edge, then the lowest ids (the same order on every run).
        bool operator<(const Candidate& o) const {
            if (smallerArea != o.smallerArea) return smallerArea > o.smallerArea;
            if (sharedLength != o.sharedLength) return sharedLength < o.sharedLength;
            return std::tie(a, b) > std::tie(o.a, o.b);
        }
    };

    void push(uint32_t c) {
        for (const auto& [other, length] : neighbours_[c]) {
            const uint32_t a = std::min(c, other), b = std::max(c, other);
            if (failed_.count(edgeKey(a, b)) || creased_.count(edgeKey(a, b))) continue;
            queue_.push({std::min(charts_[a].area, charts_[b].area), length, a, b, version_[a], version_[b]});
        }
    }

    // The union of big and small, flattened: small's layout turned and scaled onto big's
    // along the vertices they share, then small's own vertices solved with big's held, then
    // (where that is not valid) the whole union solved from there. False where no layout
    // passes accept().
    bool merge(const Chart& big, const Chart& small, const Rectangle& bigRectangle, const Rectangle& smallRectangle,
               Chart& out) {
        out.mesh = big.mesh;
        out.triangles = big.triangles;
        out.triangles.insert(out.triangles.end(), small.triangles.begin(), small.triangles.end());
        out.vertices = big.vertices;
        out.corners = big.corners;
        for (uint32_t i = 0; i < big.vertices.size(); ++i) localOf_[big.vertices[i]] = int32_t(i);
        // The similarity (complex a z + b) that takes small's shared vertices onto big's, in
        // the least-squares sense.
        glm::dvec2 centreSmall(0.0), centreBig(0.0);
        size_t shared = 0;
        for (uint32_t i = 0; i < small.vertices.size(); ++i)
            if (localOf_[small.vertices[i]] >= 0) {
                centreSmall += glm::dvec2(small.coords[i]);
                centreBig += glm::dvec2(big.coords[size_t(localOf_[small.vertices[i]])]);
                ++shared;
            }
        glm::dvec2 a(0.0);
        double norm = 0.0;
        if (shared >= 2) {
            centreSmall /= double(shared);
            centreBig /= double(shared);
            for (uint32_t i = 0; i < small.vertices.size(); ++i)
                if (localOf_[small.vertices[i]] >= 0) {
                    const glm::dvec2 zs = glm::dvec2(small.coords[i]) - centreSmall;
                    const glm::dvec2 zb = glm::dvec2(big.coords[size_t(localOf_[small.vertices[i]])]) - centreBig;
                    a += glm::dvec2(zb.x * zs.x + zb.y * zs.y, zb.y * zs.x - zb.x * zs.y);  // zb × conj(zs)
                    norm += glm::dot(zs, zs);
                }
        }
        FlattenProblem problem;
        const bool aligned = norm > 0.0;
        if (aligned) {
            a /= norm;
            problem.uv.reserve(big.vertices.size() + small.vertices.size());
            for (const vec2& p : big.coords) problem.uv.push_back(glm::dvec2(p));
            problem.fixed.assign(big.vertices.size(), 1);
            for (uint32_t i = 0; i < small.vertices.size(); ++i) {
                const uint32_t w = small.vertices[i];
                if (localOf_[w] >= 0) continue;
                localOf_[w] = int32_t(out.vertices.size());
                out.vertices.push_back(w);
                const glm::dvec2 z = glm::dvec2(small.coords[i]) - centreSmall;
                problem.uv.push_back(centreBig + glm::dvec2(a.x * z.x - a.y * z.y, a.x * z.y + a.y * z.x));
                problem.fixed.push_back(0);
            }
            for (uint32_t c : small.corners) out.corners.push_back(uint32_t(localOf_[small.vertices[c]]));
        }
        for (uint32_t w : out.vertices) localOf_[w] = -1;
        if (!aligned) return false;
        problem.corners = out.corners;
        problem.positions.reserve(out.vertices.size());
        for (uint32_t w : out.vertices) problem.positions.push_back(topo_.welded[w]);
        // A solve stops once its layout is within the stretch bound, or where it is still well
        // outside it after kHopelessSteps.
        problem.stop = [&](const std::vector<glm::dvec2>& uv, int steps) {
            double ratio = 0.0;
            return stretch(uv, out, ratio) || (steps >= kHopelessSteps && ratio > kHopelessStretch * maxStretch_);
        };
        const double longest = std::max(lengthCap_, kMergeLengthGrowth * std::max(bigRectangle.longSide, smallRectangle.longSide));
        const double roomiest = kMergeRectangleSlack * (paddedTexels(bigRectangle, texel_) + paddedTexels(smallRectangle, texel_));
        if (problem.uv.size() > big.vertices.size()) {
            flattenConformal(problem, kMergeIterations);
            if (accept(problem.uv, out, longest, roomiest)) return true;
            double ratio = 0.0;
            stretch(problem.uv, out, ratio);
            if (ratio > kFullSolveStretch * maxStretch_) return false;
        }
        problem.fixed.clear();
        flattenConformal(problem, kMergeIterations);
        return accept(problem.uv, out, longest, roomiest);
    }

    // Whether no triangle of a layout of the union is folded over and their area stretch
    // (largest flattened / 3D area over smallest) is within the bound; `ratio` that stretch.
    bool stretch(const std::vector<glm::dvec2>& uv, const Chart& out, double& ratio) const {
        double lowest = std::numeric_limits<double>::max(), highest = 0.0;
        ratio = std::numeric_limits<double>::max();
        for (size_t i = 0; i < out.triangles.size(); ++i) {
            const double area3 = topo_.area[out.triangles[i]];
            if (!(area3 > 0.0)) continue;
            const glm::dvec2 &p0 = uv[out.corners[3 * i]], &p1 = uv[out.corners[3 * i + 1]], &p2 = uv[out.corners[3 * i + 2]];
            const double flat = 0.5 * ((p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x));
            if (!(flat > 0.0)) return false;
            lowest = std::min(lowest, flat / area3);
            highest = std::max(highest, flat / area3);
        }
        if (!(highest > 0.0)) return false;
        ratio = highest / lowest;
        return ratio <= maxStretch_;
    }

    // Whether a layout of the union is valid (stretch(), a rectangle no longer than `longest`
    // that takes no more than `roomiest` texels, nothing overlapping); then its coordinates,
    // scaled so that no triangle is denser than the scene's texel (flattened area at most 3D).
    bool accept(const std::vector<glm::dvec2>& uv, Chart& out, double longest, double roomiest) const {
        double ratio = 0.0;
        if (!stretch(uv, out, ratio)) return false;
        double highest = 0.0;
        for (size_t i = 0; i < out.triangles.size(); ++i) {
            const double area3 = topo_.area[out.triangles[i]];
            if (!(area3 > 0.0)) continue;
            const glm::dvec2 &p0 = uv[out.corners[3 * i]], &p1 = uv[out.corners[3 * i + 1]], &p2 = uv[out.corners[3 * i + 2]];
            highest = std::max(highest, 0.5 * ((p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x)) / area3);
        }
        const double scale = 1.0 / std::sqrt(highest);
        out.coords.resize(uv.size());
        for (size_t v = 0; v < uv.size(); ++v) out.coords[v] = vec2(uv[v] * scale);
        const Rectangle rectangle = smallestRectangle(out.coords);
        if (rectangle.longSide > longest * (1.0 + 1e-6) || paddedTexels(rectangle, texel_) > roomiest) return false;
        // Nothing overlaps: each triangle against those before it.
        double area = 0.0;
        for (uint32_t t : out.triangles) area += topo_.area[t];
        OverlapGrid grid(2.0f * std::sqrt(float(area / double(out.triangles.size()))));
        for (size_t i = 0; i < out.triangles.size(); ++i) {
            if (!(topo_.area[out.triangles[i]] > 0.0f)) continue;
            vec2 p[3];
            chartTriangle(out, i, p);
            if (grid.overlaps(p)) return false;
            grid.hold(p);
        }
        out.area = area;
        return true;
    }

    const Topology& topo_;
    std::vector<Chart>& charts_;
    const double lengthCap_, texel_;
    const bool keepCreases_;
    const double maxStretch_ = 1.0 / std::cos(glm::radians(double(kChartAngleDegrees)));
    std::vector<int32_t> localOf_;  // scratch: a welded vertex's index in the union being built
    std::vector<uint8_t> alive_;
    std::vector<uint32_t> version_;
    std::vector<std::map<uint32_t, double>> neighbours_;
    std::vector<Rectangle> rectangles_;
    std::priority_queue<Candidate> queue_;
    std::set<uint64_t> failed_;
    std::set<uint64_t> creased_;  // pairs that meet along a crease (kMergeFoldDegrees)
};

// Skyline packing (bottom-left) of the charts' rectangles at texel size s (world units per
// texel); false when they do not fit. Charts are taken tallest first, each laid flat (its
// longer side across), each where its top lands lowest, then leftmost. Shelves left the gap
// over every chart lower than its shelf's first, and packed less (docs/atlas.md).
bool pack(std::vector<Chart>& charts, const std::vector<uint32_t>& order, double s, int width, int height) {
    struct Segment {
        int x, y, width;
    };
    std::vector<Segment> skyline{{0, 0, width}};
    for (uint32_t c : order) {
        Chart& chart = charts[c];
        // A chart e texels long, set kChartInset into its first texel, touches
        // floor(e + 2 kChartInset) + 1 texels and stays kChartInset away from the texels on
        // either side; then its padding on both sides.
        const auto texels = [&](float extent) {
            return static_cast<int>(std::floor(double(extent) / s + 2.0 * kChartInset)) + 1 + 2 * kPaddingTexels;
        };
        const int a = texels(chart.upper.x - chart.lower.x);
        const int b = texels(chart.upper.y - chart.lower.y);
        chart.orientation = -1;
        chart.turned = b > a;
        chart.size = chart.turned ? glm::ivec2(b, a) : glm::ivec2(a, b);
        const int w = chart.size.x, h = chart.size.y;
        if (w > width || h > height) return false;
        size_t bestIndex = skyline.size();
        int bestTop = std::numeric_limits<int>::max(), bestX = 0, bestY = 0;
        for (size_t i = 0; i < skyline.size(); ++i) {
            const int x = skyline[i].x;
            if (x + w > width) break;
            int y = 0;
            for (size_t j = i; j < skyline.size() && skyline[j].x < x + w; ++j) y = std::max(y, skyline[j].y);
            if (y + h <= height && y + h < bestTop) {
                bestTop = y + h;
                bestIndex = i;
                bestX = x;
                bestY = y;
            }
        }
        if (bestIndex == skyline.size()) return false;
        chart.origin = glm::ivec2(bestX, bestY);
        // The new segment replaces what it covers: the skyline left of it, the new one, the
        // skyline right of it (a segment it covers in part keeps the rest).
        std::vector<Segment> next;
        next.reserve(skyline.size() + 2);
        for (const Segment& g : skyline)
            if (g.x < bestX) next.push_back({g.x, g.y, std::min(g.x + g.width, bestX) - g.x});
        next.push_back({bestX, bestTop, w});
        for (const Segment& g : skyline) {
            const int from = std::max(g.x, bestX + w), end = g.x + g.width;
            if (end > from) next.push_back({from, g.y, end - from});
        }
        // Neighbours at one height become one segment.
        skyline.clear();
        for (const Segment& g : next) {
            if (!skyline.empty() && skyline.back().y == g.y && skyline.back().x + skyline.back().width == g.x)
                skyline.back().width += g.width;
            else
                skyline.push_back(g);
        }
    }
    return true;
}

// The extent along the other axis of one triangle (in texels) within the strip of texels i
// along `axis`, the strip widened by kTouchSlack on both sides; false when it misses the strip.
bool stripRange(const vec2 (&p)[3], int axis, int i, float& low, float& high) {
    const int other = 1 - axis;
    low = std::numeric_limits<float>::max();
    high = -low;
    const float a = float(i) - kTouchSlack, b = float(i + 1) + kTouchSlack;
    for (int k = 0; k < 3; ++k) {
        const vec2 &p0 = p[k], &p1 = p[(k + 1) % 3];
        if (p0[axis] >= a && p0[axis] <= b) {
            low = std::min(low, p0[other]);
            high = std::max(high, p0[other]);
        }
        for (const float edge : {a, b}) {
            const float d0 = p0[axis] - edge, d1 = p1[axis] - edge;
            if ((d0 < 0.0f) == (d1 < 0.0f) || d0 == d1) continue;
            const float t = d0 / (d0 - d1);
            const float at = p0[other] + t * (p1[other] - p0[other]);
            low = std::min(low, at);
            high = std::max(high, at);
        }
    }
    return low <= high;
}

// A chart's footprint at texel size s, as the texels' hull per column (along U) and per row
// (along V): [low, high] rows per column and columns per row.
struct Footprint {
    std::vector<glm::ivec2> columns, rows;
};

Footprint footprint(Chart& chart, double s) {
    const auto texels = [&](float extent) { return static_cast<int>(std::floor(double(extent) / s + 2.0 * kChartInset)) + 1; };
    chart.texels = glm::ivec2(texels(chart.upper.x - chart.lower.x), texels(chart.upper.y - chart.lower.y));
    Footprint f;
    f.columns.assign(size_t(chart.texels.x), glm::ivec2(std::numeric_limits<int>::max(), -1));
    f.rows.assign(size_t(chart.texels.y), glm::ivec2(std::numeric_limits<int>::max(), -1));
    for (size_t t = 0; t < chart.triangles.size(); ++t) {
        vec2 p[3];
        chartTriangle(chart, t, p);
        for (vec2& q : p) q = vec2((glm::dvec2(q - chart.lower)) / s + kChartInset);
        for (int axis = 0; axis < 2; ++axis) {
            std::vector<glm::ivec2>& lines = axis == 0 ? f.columns : f.rows;
            const int extent = axis == 0 ? chart.texels.y : chart.texels.x;
            const float lowest = std::min({p[0][axis], p[1][axis], p[2][axis]});
            const float highest = std::max({p[0][axis], p[1][axis], p[2][axis]});
            // Within kTouchSlack of a texel's edge a point touches the texels on both sides: a
            // corner read back from TEXCOORD_1 may land on either.
            const int first = std::max(0, int(std::floor(lowest - kTouchSlack)));
            const int last = std::min(int(lines.size()) - 1, int(std::floor(highest + kTouchSlack)));
            for (int i = first; i <= last; ++i) {
                float low, high;
                if (!stripRange(p, axis, i, low, high)) continue;
                glm::ivec2& line = lines[size_t(i)];
                line.x = std::min(line.x, std::clamp(int(std::floor(low - kTouchSlack)), 0, extent - 1));
                line.y = std::max(line.y, std::clamp(int(std::floor(high + kTouchSlack)), 0, extent - 1));
            }
        }
    }
    return f;
}

// A chart's footprint grown by its padding, in one orientation, column by column.
struct Profile {
    std::vector<int> low, high;  // rows per column from the shape's corner; high −1: an empty column
    int top = 0;                 // the highest row
};

struct Landing {
    int x = -1, y = 0;  // x −1: nowhere
    int top = std::numeric_limits<int>::max();
    long waste = std::numeric_limits<long>::max();  // rows left empty under the shape
};

// Where a shape dropped onto the atlas's columns (heights: the first free row of each) lands
// lowest, then wastes least, then lies leftmost.
Landing lowestLanding(const Profile& profile, const std::vector<int>& heights, int height) {
    Landing best;
    const int width = int(heights.size()), w = int(profile.low.size());
    if (w > width || profile.top >= height) return best;
    // The column whose footprint starts lowest bounds where the shape can land.
    size_t anchor = 0;
    for (size_t column = 1; column < profile.low.size(); ++column)
        if (profile.low[column] < profile.low[anchor]) anchor = column;
    for (int x = 0; x + w <= width; ++x) {
        // On a flat stretch of the atlas's top a shape lands as it would at the stretch's
        // ends: only positions whose left or right column meets a step are tried.
        const bool leftStep = x == 0 || heights[size_t(x)] != heights[size_t(x - 1)];
        const bool rightStep = x + w == width || heights[size_t(x + w - 1)] != heights[size_t(x + w)];
        if (!leftStep && !rightStep) continue;
        if (heights[size_t(x) + anchor] - profile.low[anchor] + profile.top > best.top) continue;
        int y = 0;
        for (int column = 0; column < w; ++column)
            if (profile.high[size_t(column)] >= 0) y = std::max(y, heights[size_t(x + column)] - profile.low[size_t(column)]);
        const int top = y + profile.top;
        if (top >= height || top > best.top) continue;
        long waste = 0;
        for (int column = 0; column < w; ++column)
            if (profile.high[size_t(column)] >= 0) waste += y + profile.low[size_t(column)] - heights[size_t(x + column)];
        if (top < best.top || waste < best.waste) best = {x, y, top, waste};
    }
    return best;
}

// Packing by profiles ("Tetris"): each chart's footprint, grown by its padding, falls down the
// atlas onto what lies below it, column by column, in whichever of four orientations and at
// whichever column its top lands lowest (then wastes least). Charts nest (a triangle's slope
// over another's) where rectangles leave a chart's corners empty; a hole under an overhang
// stays empty. False when they do not fit.
bool packByProfiles(std::vector<Chart>& charts, const std::vector<uint32_t>& order, double s,
                    int width, int height) {
    std::vector<int> heights(size_t(width), 0);  // per atlas column: the first row above every chart
    Profile profiles[4];
    for (uint32_t c : order) {
        Chart& chart = charts[c];
        const Footprint f = footprint(chart, s);
        const int nx = chart.texels.x, ny = chart.texels.y;
        for (int o = 0; o < 4; ++o) {
            // The footprint's lines in this orientation: columns, their rows, the shape's height.
            const bool transposed = o >= 2, halfTurned = o == 1 || o == 3;
            const std::vector<glm::ivec2>& lines = transposed ? f.rows : f.columns;
            const int n = int(lines.size()), extent = transposed ? nx : ny;
            const auto line = [&](int i) {
                glm::ivec2 l = lines[size_t(halfTurned ? n - 1 - i : i)];
                if (l.y < 0) return l;
                return halfTurned ? glm::ivec2(extent - 1 - l.y, extent - 1 - l.x) : l;
            };
            Profile& profile = profiles[o];
            profile.low.assign(size_t(n + 2 * kPaddingTexels), std::numeric_limits<int>::max());
            profile.high.assign(size_t(n + 2 * kPaddingTexels), -1);
            profile.top = 0;
            for (int i = 0; i < n; ++i) {
                const glm::ivec2 l = line(i);
                if (l.y < 0) continue;
                for (int d = -kPaddingTexels; d <= kPaddingTexels; ++d) {
                    const size_t column = size_t(i + d + kPaddingTexels);
                    profile.low[column] = std::min(profile.low[column], l.x);
                    profile.high[column] = std::max(profile.high[column], l.y + 2 * kPaddingTexels);
                }
            }
            for (size_t column = 0; column < profile.low.size(); ++column) profile.top = std::max(profile.top, profile.high[column]);
        }
        // The four orientations are searched side by side; the first best (lowest top, then
        // least waste, then the earlier orientation and column) wins, as in one search.
        Landing landings[4];
        tbb::parallel_for(0, 4, [&](int o) { landings[o] = lowestLanding(profiles[o], heights, height); });
        int bestOrientation = -1;
        for (int o = 0; o < 4; ++o)
            if (landings[o].x >= 0 && (bestOrientation < 0 || landings[o].top < landings[bestOrientation].top ||
                                       (landings[o].top == landings[bestOrientation].top &&
                                        landings[o].waste < landings[bestOrientation].waste)))
                bestOrientation = o;
        if (bestOrientation < 0) return false;
        const Profile& profile = profiles[bestOrientation];
        const int bestX = landings[bestOrientation].x, bestY = landings[bestOrientation].y;
        for (size_t column = 0; column < profile.low.size(); ++column)
            if (profile.high[column] >= 0)
                heights[size_t(bestX) + column] = std::max(heights[size_t(bestX) + column], bestY + profile.high[column] + 1);
        chart.orientation = bestOrientation;
        chart.origin = glm::ivec2(bestX, bestY);
    }
    return true;
}

// Stretch: a triangle's area over its flattened area, the largest over triangles of at least a
// hundredth of a texel (a sliver's projection is all rounding), the mean area-weighted over
// all; s the texel size.
void measureStretch(const Scene& scene, const std::vector<Chart>& charts, double s, LightmapUvReport& report) {
    double stretchSum = 0.0, areaSum = 0.0;
    for (const Chart& chart : charts) {
        const Mesh& mesh = scene.meshes[chart.mesh];
        for (size_t i = 0; i < chart.triangles.size(); ++i) {
            vec2 p[3];
            chartTriangle(chart, i, p);
            const double flat = area2d(p);
            const uint32_t* v = &mesh.indices[3 * size_t(chart.triangles[i])];
            const double area3 = 0.5 * double(glm::length(glm::cross(mesh.positions[v[1]] - mesh.positions[v[0]],
                                                                     mesh.positions[v[2]] - mesh.positions[v[0]])));
            if (!(flat > 0.0)) continue;
            stretchSum += area3 / flat * area3;
            areaSum += area3;
            if (area3 >= 0.01 * s * s) report.maxStretch = std::max(report.maxStretch, area3 / flat);
        }
    }
    report.meanStretch = areaSum > 0.0 ? stretchSum / areaSum : 1.0;
}

double surfaceArea(const Scene& scene, const std::vector<uint32_t>& meshes) {
    double area = 0.0;
    for (const uint32_t m : meshes) {
        const Mesh& mesh = scene.meshes[m];
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t* i = &mesh.indices[3 * t];
            area += 0.5 * double(glm::length(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]],
                                                       mesh.positions[i[2]] - mesh.positions[i[0]])));
        }
    }
    return area;
}

// The charts of every mesh given, grown, cut where wasteful and merged (at about texel size
// s), each turned to its smallest rectangle.
std::vector<Chart> sceneCharts(const Scene& scene, const std::vector<uint32_t>& unwrapped, double s, bool keepCreases,
                               size_t& grown) {
    // The side of the square the charts would fill at 60%.
    const double lengthCap = kMergeLengthShare * std::sqrt(surfaceArea(scene, unwrapped) / 0.6);
    std::vector<std::vector<Chart>> perMesh(scene.meshes.size());
    std::vector<size_t> grownPerMesh(scene.meshes.size(), 0);
    tbb::parallel_for(size_t(0), unwrapped.size(), [&](size_t i) {
        const uint32_t m = unwrapped[i];
        if (scene.meshes[m].triangleCount() == 0) return;
        const Topology topo = meshTopology(scene.meshes[m]);
        std::vector<Chart> charts = growCharts(topo, m);
        grownPerMesh[m] = charts.size();
        for (Chart& chart : charts) splitWasteful(topo, std::move(chart), s, perMesh[m]);
        ChartMerger(topo, perMesh[m], lengthCap, s, keepCreases).run();
        for (Chart& chart : perMesh[m]) measureChart(chart);
    });
    std::vector<Chart> charts;
    grown = 0;
    for (size_t m = 0; m < perMesh.size(); ++m) {
        grown += grownPerMesh[m];
        for (Chart& chart : perMesh[m]) charts.push_back(std::move(chart));
    }
    return charts;
}

int roundUpTo4(double side) { return 4 * int(std::ceil(side / 4.0 - 1e-9)); }

}  // namespace

size_t LightmapUvReport::smallChartCount() const {
    size_t count = 0;
    for (const SmallCharts& small : smallCharts) count += small.charts;
    return count;
}

LightmapUvReport generateLightmapUvs(Scene& scene, const std::vector<uint32_t>& meshes, int width, int height) {
    AtlasRequest atlas;
    atlas.width = width;
    atlas.height = height;
    return generateLightmapUvs(scene, meshes, atlas);
}

LightmapUvReport generateLightmapUvs(Scene& scene, const std::vector<uint32_t>& meshes, const AtlasRequest& atlas) {
    const bool byTexel = atlas.texelSize != 0.0;
    if (byTexel && !(atlas.texelSize > 0.0 && std::isfinite(atlas.texelSize)))
        throw SettingsError("lightmap UVs: a texel size of " + std::to_string(atlas.texelSize) +
                            " is not positive and finite");
    int width = byTexel ? atlas.maxSide : atlas.width, height = byTexel ? atlas.maxSide : atlas.height;
    if (width < 16 || height < 16 || width > 16384 || height > 16384)
        throw SettingsError("lightmap UVs: an atlas of " + std::to_string(width) + " x " + std::to_string(height) +
                            " texels is outside 16 .. 16384 a side");
    if (byTexel && (atlas.maxSide % 4 != 0 || (atlas.powerOfTwo && (atlas.maxSide & (atlas.maxSide - 1)) != 0)))
        throw SettingsError("lightmap UVs: a largest atlas side of " + std::to_string(atlas.maxSide) +
                            (atlas.powerOfTwo ? " is not a power of two" : " is not a multiple of 4"));
    for (const uint32_t m : meshes)
        if (m >= scene.meshes.size())
            throw SettingsError("lightmap UVs: mesh " + std::to_string(m) + " of a scene of " +
                                std::to_string(scene.meshes.size()));
    const auto start = std::chrono::steady_clock::now();
    LightmapUvReport report;
    report.askedTexelSize = atlas.texelSize;
    report.width = width;
    report.height = height;
    std::vector<uint32_t> unwrapped = meshes;  // once each, however often given
    std::sort(unwrapped.begin(), unwrapped.end());
    unwrapped.erase(std::unique(unwrapped.begin(), unwrapped.end()), unwrapped.end());
    // The texel size the charts are cut and merged for: the one asked, or about the one the
    // atlas will come to (its charts take about 60% of it). A power-of-two atlas is filled
    // finer than the texel asked: about as the atlas of that side, which a side asked for gives.
    const double area = std::max(surfaceArea(scene, unwrapped), 1e-30);
    const auto fillingTexel = [&](double side) { return std::sqrt(area / (0.6 * side * side)); };
    double texelGuess = byTexel ? atlas.texelSize : std::sqrt(area / (0.6 * double(width) * double(height)));
    if (byTexel && atlas.powerOfTwo) {
        double side = 16.0;
        while (side < atlas.maxSide && fillingTexel(side) > atlas.texelSize) side *= 2.0;
        texelGuess = std::min(atlas.texelSize, fillingTexel(side));
    }
    // Lays `charts` out (their uv and atlas place): the atlas's size and texel size, or false
    // where they do not fit the atlas asked at any texel size.
    struct Layout {
        bool fitted = false;
        int width = 0, height = 0;
        double texelSize = 0.0, projected = 0.0;
    };
    const auto layOut = [&](std::vector<Chart>& charts) {
        Layout out;
        int width = byTexel ? atlas.maxSide : atlas.width, height = byTexel ? atlas.maxSide : atlas.height;
        double projected = 0.0;
        for (const Chart& chart : charts) projected += chart.projectedArea;
        out.projected = projected;
        std::vector<uint32_t> order(charts.size());
        std::iota(order.begin(), order.end(), 0u);
        std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
            const float ha = std::min(charts[a].upper.x - charts[a].lower.x, charts[a].upper.y - charts[a].lower.y);
            const float hb = std::min(charts[b].upper.x - charts[b].lower.x, charts[b].upper.y - charts[b].lower.y);
            return ha > hb;
        });
        const auto fitsRectangles = [&](double s, int w, int h) { return pack(charts, order, s, w, h); };
        const auto fitsProfiles = [&](double s, int w, int h) { return packByProfiles(charts, order, s, w, h); };
        const auto fits = [&](double s, int side) { return fitsProfiles(s, side, side) || fitsRectangles(s, side, side); };
        double s = atlas.texelSize;
        bool packed = false;  // at the texel size asked
        if (byTexel && atlas.powerOfTwo) {
            // The smallest power-of-two square that holds the charts at the texel size asked, then
            // the texel size that fills it, as for an atlas asked by size.
            int side = 16;
            while (side < atlas.maxSide && double(side) * side < projected / (s * s)) side *= 2;
            while (side < atlas.maxSide && !fits(s, side)) side *= 2;
            width = height = std::min(side, atlas.maxSide);
        } else if (byTexel && (fitsRectangles(s, atlas.maxSide, atlas.maxSide) || fits(s, atlas.maxSide))) {
            // The smallest square, a multiple of 4 texels a side, that holds the charts at the
            // texel size asked; the charts' area alone bounds it from below. Rectangles (fast)
            // bracket it, then profiles refine it within kProfileBracket of theirs.
            const int least = std::max(16, roundUpTo4(std::sqrt(projected) / s)) - 4;  // never fits
            const auto smallest = [&](int lower, int upper, auto&& fitsAt) {
                while (upper - lower > 4) {
                    const int middle = roundUpTo4(0.5 * (lower + upper));
                    (fitsAt(middle) ? upper : lower) = middle;
                }
                return upper;
            };
            int upper = atlas.maxSide;
            if (fitsRectangles(s, upper, upper))
                upper = smallest(least, upper, [&](int side) { return fitsRectangles(s, side, side); });
            upper = smallest(std::max(least, roundUpTo4(kProfileBracket * upper) - 4), upper,
                             [&](int side) { return fits(s, side); });
            width = height = upper;
            if (!fitsProfiles(s, width, height)) fitsRectangles(s, width, height);
            packed = true;
        }
        if (!packed) {
            // An atlas size (or a texel size whose charts overfill the largest atlas): the smallest
            // texel size whose packing fits. Rectangles (fast) bracket it; profiles (denser,
            // slower) then refine it below the rectangles' in a few steps.
            const auto lowest = [&] { return std::sqrt(std::max(projected, 1e-30) / (double(width) * double(height))); };
            double lower = lowest();
            double upper = lower;
            for (int k = 0; k < 60 && !fitsRectangles(upper, width, height); ++k) upper *= 2.0;
            if (!fitsRectangles(upper, width, height)) return out;
            for (int k = 0; k < 24; ++k) {
                const double middle = 0.5 * (lower + upper);
                (fitsRectangles(middle, width, height) ? upper : lower) = middle;
            }
            s = upper;
            if (fitsProfiles(upper, width, height)) {
                lower = std::max(lowest(), kProfileBracket * upper);
                bool fitted = false;  // the last pack tried fitted: its layout stands
                for (int k = 0; k < kProfileSteps; ++k) {
                    const double middle = 0.5 * (lower + upper);
                    fitted = fitsProfiles(middle, width, height);
                    (fitted ? upper : lower) = middle;
                }
                s = upper;
                if (!fitted) fitsProfiles(s, width, height);
            } else {
                fitsRectangles(s, width, height);  // profiles do not nest these charts at the rectangles' size: rectangles
            }
        }
        out.fitted = true;
        out.width = width;
        out.height = height;
        out.texelSize = s;
        return out;
    };
    // Charts kept apart at hard creases, unless that costs the atlas more than
    // kCreaseTexelCost in texel size (a flat-shaded level is thousands of faces, each then a
    // chart with its padding) or does not fit at all: then merged across them as well, and said.
    std::vector<Chart> charts = sceneCharts(scene, unwrapped, texelGuess, true, report.grownCharts);
    if (charts.empty()) {
        if (byTexel) report.width = report.height = 16;
        return report;
    }
    Layout layout = layOut(charts);
    if (!layout.fitted || layout.texelSize > kCreaseTexelCost * texelGuess) {
        size_t grown = 0;
        std::vector<Chart> merged = sceneCharts(scene, unwrapped, texelGuess, false, grown);
        const Layout other = layOut(merged);
        if (other.fitted && (!layout.fitted || other.texelSize < layout.texelSize)) {
            charts = std::move(merged);
            layout = other;
            report.mergedAcrossCreases = true;
        }
    }
    if (!layout.fitted)
        throw SettingsError("lightmap UVs: " + std::to_string(charts.size()) + " charts do not fit a " +
                            std::to_string(width) + " x " + std::to_string(height) +
                            " atlas at any texel size (each takes " + std::to_string(2 * kPaddingTexels + 1) +
                            " texels of padding along each axis): ask for a larger atlas");
    const double s = layout.texelSize, projected = layout.projected;
    width = layout.width;
    height = layout.height;
    report.width = width;
    report.height = height;
    report.texelSize = s;
    report.charts = charts.size();
    report.occupancy = projected / (s * s) / (double(width) * double(height));
    measureStretch(scene, charts, s, report);
    // Charts too small for the texel size: every neighbour refused them (see the header).
    std::map<uint32_t, size_t> smallPerMesh;
    for (const Chart& chart : charts)
        if (std::min(chart.upper.x - chart.lower.x, chart.upper.y - chart.lower.y) < kSmallChartTexels * s)
            ++smallPerMesh[chart.mesh];
    for (const auto& [m, count] : smallPerMesh) report.smallCharts.push_back({scene.meshes[m].name, count});
    std::stable_sort(report.smallCharts.begin(), report.smallCharts.end(),
                     [](const SmallCharts& a, const SmallCharts& b) { return a.charts > b.charts; });

    // New vertices: one per (vertex, chart) pair, every attribute copied, uv1 in the chart.
    std::vector<std::vector<uint32_t>> chartsOf(scene.meshes.size());
    for (uint32_t c = 0; c < charts.size(); ++c) chartsOf[charts[c].mesh].push_back(c);
    tbb::parallel_for(size_t(0), scene.meshes.size(), [&](size_t m) {
        if (chartsOf[m].empty()) return;
        const Mesh& mesh = scene.meshes[m];
        Mesh out = mesh.withoutVertices();
        out.indices.assign(mesh.indices.size(), 0);
        std::unordered_map<uint64_t, uint32_t> vertexOf;  // (old vertex, chart) → new vertex
        for (uint32_t c : chartsOf[m]) {
            const Chart& chart = charts[c];
            for (size_t i = 0; i < chart.triangles.size(); ++i)
                for (int k = 0; k < 3; ++k) {
                    const size_t corner = 3 * size_t(chart.triangles[i]) + size_t(k);
                    const uint32_t old = mesh.indices[corner];
                    const auto [it, added] = vertexOf.emplace((uint64_t(old) << 32) | c, uint32_t(out.positions.size()));
                    if (added) {
                        out.appendVertexOf(mesh, old);
                        out.source.vertices.push_back(mesh.source.vertices.empty() ? old : mesh.source.vertices[old]);
                        const vec2 p = chart.coords[chart.corners[3 * i + size_t(k)]];
                        vec2 local(float((double(p.x) - chart.lower.x) / s + kChartInset),
                                   float((double(p.y) - chart.lower.y) / s + kChartInset));
                        vec2 texel;
                        if (chart.orientation >= 0) {
                            texel = placedOnAtlas(chart, local);
                        } else {
                            if (chart.turned) local = vec2(local.y, local.x);
                            texel = vec2(chart.origin) + vec2(float(kPaddingTexels)) + local;
                        }
                        out.uv1.push_back(texel / vec2(float(width), float(height)));
                    }
                    out.indices[corner] = it->second;
                }
        }
        scene.meshes[m] = std::move(out);
    });
    for (const auto& list : chartsOf) report.meshes += list.empty() ? 0 : 1;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

std::string describeLightmapUvs(const LightmapUvReport& report) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "lightmap UVs generated: %zu meshes, %zu charts (%zu grown, then merged%s) in %d x %d, texel %.3g "
                  "(scene units), charts %.0f%% of the atlas, area stretch at most %.2f (mean %.3f), %zu charts under "
                  "%g x %g texels, %.2f s",
                  report.meshes, report.charts, report.grownCharts,
                  report.mergedAcrossCreases ? " across hard edges too, to fit the atlas" : "", report.width, report.height,
                  report.texelSize,
                  100.0 * report.occupancy, report.maxStretch, report.meanStretch, report.smallChartCount(),
                  kSmallChartTexels, kSmallChartTexels, report.seconds);
    return text;
}

}  // namespace vl
