#include "unwrap/lightmap_uvs.h"

#include "core/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>
#include <unordered_map>

namespace vl {

namespace {

// How far (in texels) a chart's corners stay from the edges of the texels its padding begins
// at: beyond a float uv's rounding at kMaxAtlasSide (2^-24 × 8192 = 5e-4 texel), so no corner
// read back from TEXCOORD_1 lands in the padding.
constexpr double kChartInset = 1.0 / 256.0;
constexpr float kTouchSlack = 1.0f / 512.0f;
// The texel size by profiles is searched within [kProfileBracket, 1] of the rectangles' (on
// zdm2 it comes out at 0.93 of it) in kProfileSteps bisections: to 0.6% of it.
constexpr double kProfileBracket = 0.8;
constexpr int kProfileSteps = 5;

struct Chart {
    uint32_t mesh = 0;
    std::vector<uint32_t> triangles;
    vec3 axisU{1.0f, 0.0f, 0.0f}, axisV{0.0f, 1.0f, 0.0f};  // the plane it is projected onto
    vec2 lower{0.0f}, upper{0.0f};                           // its extent on those axes
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

// A point, and triangle t of `mesh`, on a chart's plane.
vec2 onChart(const Chart& chart, const vec3& p) { return vec2(glm::dot(p, chart.axisU), glm::dot(p, chart.axisV)); }

void chartTriangle(const Mesh& mesh, const Chart& chart, uint32_t t, vec2 (&p)[3]) {
    for (int k = 0; k < 3; ++k) p[k] = onChart(chart, mesh.positions[mesh.indices[3 * size_t(t) + size_t(k)]]);
}

double area2d(const vec2 (&p)[3]) {
    return 0.5 * std::abs(double(p[1].x - p[0].x) * (p[2].y - p[0].y) - double(p[1].y - p[0].y) * (p[2].x - p[0].x));
}

uint64_t edgeKey(uint32_t a, uint32_t b) {
    if (a > b) std::swap(a, b);
    return (uint64_t(a) << 32) | b;
}

struct PositionHash {
    size_t operator()(const vec3& p) const {
        uint32_t bits[3];
        std::memcpy(bits, &p, sizeof bits);
        return (size_t(bits[0]) * 73856093u) ^ (size_t(bits[1]) * 19349663u) ^ (size_t(bits[2]) * 83492791u);
    }
};

// Whether two triangles of a plane overlap in area: no edge normal of either separates them
// by more than `slack` (triangles that share an edge or a corner only touch).
bool overlapIn2d(const vec2 (&a)[3], const vec2 (&b)[3], float slack) {
    const vec2* sides[2] = {a, b};
    for (const vec2* tri : sides)
        for (int k = 0; k < 3; ++k) {
            const vec2 edge = tri[(k + 1) % 3] - tri[k];
            const vec2 axis(-edge.y, edge.x);
            const float length = glm::length(axis);
            if (!(length > 0.0f)) continue;
            float loA = std::numeric_limits<float>::max(), hiA = -loA, loB = loA, hiB = -loA;
            for (int j = 0; j < 3; ++j) {
                const float pa = glm::dot(a[j], axis) / length, pb = glm::dot(b[j], axis) / length;
                loA = std::min(loA, pa);
                hiA = std::max(hiA, pa);
                loB = std::min(loB, pb);
                hiB = std::max(hiB, pb);
            }
            if (hiA <= loB + slack || hiB <= loA + slack) return false;
        }
    return true;
}

// The charts of one mesh (see the header).
std::vector<Chart> meshCharts(const Mesh& mesh, uint32_t meshIndex) {
    const size_t triangles = mesh.triangleCount();
    // Vertices welded by position: glTF splits them at every seam of its other attributes.
    std::unordered_map<vec3, uint32_t, PositionHash> welded;
    std::vector<uint32_t> weldedId(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v)
        weldedId[v] = welded.emplace(mesh.positions[v], uint32_t(welded.size())).first->second;
    std::unordered_map<uint64_t, std::vector<uint32_t>> edges;
    std::vector<vec3> normal(triangles);
    std::vector<float> area(triangles);
    for (uint32_t t = 0; t < triangles; ++t) {
        const uint32_t* i = &mesh.indices[3 * size_t(t)];
        const vec3 cross = glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]], mesh.positions[i[2]] - mesh.positions[i[0]]);
        area[t] = 0.5f * glm::length(cross);
        normal[t] = area[t] > 0.0f ? cross / (2.0f * area[t]) : vec3(0.0f);
        for (int k = 0; k < 3; ++k) edges[edgeKey(weldedId[i[k]], weldedId[i[(k + 1) % 3]])].push_back(t);
    }
    std::vector<uint32_t> order(triangles);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return area[a] > area[b]; });
    const float minCos = std::cos(glm::radians(kChartAngleDegrees));
    std::vector<int32_t> chartOf(triangles, -1);
    std::vector<Chart> charts;
    std::vector<uint32_t> queue;
    // A chart refuses a triangle whose projection would overlap one it holds (a surface that
    // folds back under itself within the cone: zdm2 had 6,886 overlapping sub-texel points
    // without this); the refused triangle starts or joins another chart. The chart's
    // triangles are found by a grid of cells about twice a triangle's size.
    double totalArea = 0.0;
    for (float a : area) totalArea += a;
    const float cell = std::max(1e-12f, 2.0f * std::sqrt(float(totalArea / double(std::max<size_t>(triangles, 1)))));
    const float slack = 1e-5f * cell;
    std::unordered_map<uint64_t, std::vector<uint32_t>> grid;  // the current chart's triangles by cell
    const auto cellKey = [](int x, int y) { return (uint64_t(uint32_t(x)) << 32) | uint32_t(y); };
    const auto cells = [&](const vec2 (&p)[3], auto&& visit) {
        const vec2 lo = glm::min(p[0], glm::min(p[1], p[2])) / cell, hi = glm::max(p[0], glm::max(p[1], p[2])) / cell;
        for (int y = int(std::floor(lo.y)); y <= int(std::floor(hi.y)); ++y)
            for (int x = int(std::floor(lo.x)); x <= int(std::floor(hi.x)); ++x) visit(cellKey(x, y));
    };
    const auto overlapsChart = [&](uint32_t t, const Chart& chart) {
        if (!(area[t] > 0.0f)) return false;
        vec2 p[3];
        chartTriangle(mesh, chart, t, p);
        bool overlaps = false;
        cells(p, [&](uint64_t key) {
            if (overlaps) return;
            const auto it = grid.find(key);
            if (it == grid.end()) return;
            for (uint32_t other : it->second) {
                vec2 o[3];
                chartTriangle(mesh, chart, other, o);
                if (overlapIn2d(p, o, slack)) {
                    overlaps = true;
                    return;
                }
            }
        });
        return overlaps;
    };
    const auto hold = [&](uint32_t t, const Chart& chart) {
        if (!(area[t] > 0.0f)) return;
        vec2 p[3];
        chartTriangle(mesh, chart, t, p);
        cells(p, [&](uint64_t key) { grid[key].push_back(t); });
    };
    for (uint32_t seed : order) {
        if (chartOf[seed] >= 0) continue;
        const int32_t c = static_cast<int32_t>(charts.size());
        charts.emplace_back();
        Chart& chart = charts.back();
        chart.mesh = meshIndex;
        const vec3 n = glm::length(normal[seed]) > 0.0f ? normal[seed] : vec3(0.0f, 0.0f, 1.0f);
        orthonormalBasis(n, chart.axisU, chart.axisV);
        chartOf[seed] = c;
        queue.assign(1, seed);
        grid.clear();
        hold(seed, chart);
        for (size_t q = 0; q < queue.size(); ++q) {
            const uint32_t t = queue[q];
            chart.triangles.push_back(t);
            const uint32_t* i = &mesh.indices[3 * size_t(t)];
            for (int k = 0; k < 3; ++k)
                for (uint32_t other : edges[edgeKey(weldedId[i[k]], weldedId[i[(k + 1) % 3]])]) {
                    if (chartOf[other] >= 0) continue;
                    // A zero-area triangle projects to nothing wherever it goes.
                    if (area[other] > 0.0f && !(glm::dot(normal[other], n) >= minCos)) continue;
                    if (overlapsChart(other, chart)) continue;
                    chartOf[other] = c;
                    hold(other, chart);
                    queue.push_back(other);
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

// Projects a chart onto its plane, turned so that its bounding rectangle is the smallest (a
// side of that rectangle lies along an edge of the chart's convex hull: Freeman and Shapira
// 1975), and measures it. A principal-axes turn put a square wall at 45° (its corners'
// spread is the same along every axis) and doubled its rectangle.
void measureChart(const Mesh& mesh, Chart& chart) {
    std::vector<vec2> corners;
    corners.reserve(3 * chart.triangles.size());
    for (uint32_t t : chart.triangles)
        for (int k = 0; k < 3; ++k) corners.push_back(onChart(chart, mesh.positions[mesh.indices[3 * size_t(t) + size_t(k)]]));
    const std::vector<vec2> hull = convexHull(std::move(corners));
    float angle = 0.0f;
    double best = std::numeric_limits<double>::max();
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
        if (area < best * (1.0 - 1e-6)) {  // ties keep the first edge: the same turn on every run
            best = area;
            angle = a;
        }
    }
    const vec3 u = std::cos(angle) * chart.axisU + std::sin(angle) * chart.axisV;
    const vec3 v = -std::sin(angle) * chart.axisU + std::cos(angle) * chart.axisV;
    chart.axisU = u;
    chart.axisV = v;
    chart.lower = vec2(std::numeric_limits<float>::max());
    chart.upper = vec2(-std::numeric_limits<float>::max());
    for (uint32_t t : chart.triangles) {
        vec2 p[3];
        chartTriangle(mesh, chart, t, p);
        for (const vec2& corner : p) {
            chart.lower = glm::min(chart.lower, corner);
            chart.upper = glm::max(chart.upper, corner);
        }
        chart.projectedArea += area2d(p);
    }
}

// Skyline packing (bottom-left) of the charts' rectangles at texel size s (world units per
// texel); false when they do not fit. Charts are taken tallest first, each laid flat (its
// longer side across), each where its top lands lowest, then leftmost. Shelves left the gap
// over every chart lower than its shelf's first: charts took 49% of the atlas on nvpro's
// Cornell box and 37% on zdm2, against 58% and 40% by the skyline.
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

Footprint footprint(const Mesh& mesh, Chart& chart, double s) {
    const auto texels = [&](float extent) { return static_cast<int>(std::floor(double(extent) / s + 2.0 * kChartInset)) + 1; };
    chart.texels = glm::ivec2(texels(chart.upper.x - chart.lower.x), texels(chart.upper.y - chart.lower.y));
    Footprint f;
    f.columns.assign(size_t(chart.texels.x), glm::ivec2(std::numeric_limits<int>::max(), -1));
    f.rows.assign(size_t(chart.texels.y), glm::ivec2(std::numeric_limits<int>::max(), -1));
    for (uint32_t t : chart.triangles) {
        vec2 p[3];
        chartTriangle(mesh, chart, t, p);
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
bool packByProfiles(const Scene& scene, std::vector<Chart>& charts, const std::vector<uint32_t>& order, double s,
                    int width, int height) {
    std::vector<int> heights(size_t(width), 0);  // per atlas column: the first row above every chart
    Profile profiles[4];
    for (uint32_t c : order) {
        Chart& chart = charts[c];
        const Footprint f = footprint(scene.meshes[chart.mesh], chart, s);
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

// Stretch: a triangle's area over its projected area, the largest over triangles of at least
// a hundredth of a texel (a sliver's projection is all rounding), the mean area-weighted over
// all; s the texel size.
void measureStretch(const Scene& scene, const std::vector<Chart>& charts, double s, LightmapUvReport& report) {
    double stretchSum = 0.0, areaSum = 0.0;
    for (const Chart& chart : charts) {
        const Mesh& mesh = scene.meshes[chart.mesh];
        for (uint32_t t : chart.triangles) {
            vec2 p[3];
            chartTriangle(mesh, chart, t, p);
            const double flat = area2d(p);
            const uint32_t* i = &mesh.indices[3 * size_t(t)];
            const double area3 = 0.5 * double(glm::length(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]],
                                                                     mesh.positions[i[2]] - mesh.positions[i[0]])));
            if (!(flat > 0.0)) continue;
            stretchSum += area3 / flat * area3;
            areaSum += area3;
            if (area3 >= 0.01 * s * s) report.maxStretch = std::max(report.maxStretch, area3 / flat);
        }
    }
    report.meanStretch = areaSum > 0.0 ? stretchSum / areaSum : 1.0;
}

}  // namespace

LightmapUvReport generateLightmapUvs(Scene& scene, const std::vector<uint32_t>& meshes, int width, int height) {
    if (width < 16 || height < 16 || width > 16384 || height > 16384)
        throw SettingsError("lightmap UVs: an atlas of " + std::to_string(width) + " x " + std::to_string(height) +
                            " texels is outside 16 .. 16384 a side");
    for (const uint32_t m : meshes)
        if (m >= scene.meshes.size())
            throw SettingsError("lightmap UVs: mesh " + std::to_string(m) + " of a scene of " +
                                std::to_string(scene.meshes.size()));
    const auto start = std::chrono::steady_clock::now();
    LightmapUvReport report;
    report.width = width;
    report.height = height;
    std::vector<std::vector<Chart>> perMesh(scene.meshes.size());
    std::vector<uint32_t> unwrapped = meshes;  // once each, however often given
    std::sort(unwrapped.begin(), unwrapped.end());
    unwrapped.erase(std::unique(unwrapped.begin(), unwrapped.end()), unwrapped.end());
    tbb::parallel_for(size_t(0), unwrapped.size(), [&](size_t i) {
        const uint32_t m = unwrapped[i];
        if (scene.meshes[m].triangleCount() > 0) perMesh[m] = meshCharts(scene.meshes[m], m);
    });
    std::vector<Chart> charts;
    for (auto& list : perMesh)
        for (Chart& chart : list) charts.push_back(std::move(chart));
    if (charts.empty()) return report;
    double projected = 0.0;
    for (Chart& chart : charts) {
        measureChart(scene.meshes[chart.mesh], chart);
        projected += chart.projectedArea;
    }

    std::vector<uint32_t> order(charts.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const float ha = std::min(charts[a].upper.x - charts[a].lower.x, charts[a].upper.y - charts[a].lower.y);
        const float hb = std::min(charts[b].upper.x - charts[b].lower.x, charts[b].upper.y - charts[b].lower.y);
        return ha > hb;
    });
    // The smallest texel size whose packing fits: the charts' area alone bounds it from below.
    // Rectangles (fast) choose the atlas and bracket the texel size; profiles (denser, slower)
    // then refine it below the rectangles' in a few steps. Where the charts' padding alone
    // overfills the atlas (thousands of small charts), the atlas doubles until the charts take
    // at least a quarter of it.
    const auto lowest = [&] { return std::sqrt(std::max(projected, 1e-30) / (double(width) * double(height))); };
    const auto fitsRectangles = [&](double s) { return pack(charts, order, s, width, height); };
    const auto fitsProfiles = [&](double s) { return packByProfiles(scene, charts, order, s, width, height); };
    while (!fitsRectangles(2.0 * lowest()) && std::max(width, height) < kMaxAtlasSide) {
        width = std::min(2 * width, kMaxAtlasSide);
        height = std::min(2 * height, kMaxAtlasSide);
    }
    double lower = lowest();
    double upper = lower;
    for (int k = 0; k < 60 && !fitsRectangles(upper); ++k) upper *= 2.0;
    if (!fitsRectangles(upper))
        throw Error("lightmap UVs: " + std::to_string(charts.size()) + " charts do not fit a " + std::to_string(width) +
                    " x " + std::to_string(height) + " atlas at any texel size (each takes " +
                    std::to_string(2 * kPaddingTexels + 1) + " texels of padding along each axis)");
    report.width = width;
    report.height = height;
    for (int k = 0; k < 24; ++k) {
        const double middle = 0.5 * (lower + upper);
        if (fitsRectangles(middle))
            upper = middle;
        else
            lower = middle;
    }
    double s = upper;
    if (fitsProfiles(upper)) {
        lower = std::max(lowest(), kProfileBracket * upper);
        bool packed = false;  // the last pack tried fitted: its layout stands
        for (int k = 0; k < kProfileSteps; ++k) {
            const double middle = 0.5 * (lower + upper);
            packed = fitsProfiles(middle);
            (packed ? upper : lower) = middle;
        }
        s = upper;
        if (!packed) fitsProfiles(s);
    } else {
        fitsRectangles(s);  // profiles do not nest these charts at the rectangles' size: rectangles
    }
    report.texelSize = s;
    report.charts = charts.size();
    report.occupancy = projected / (s * s) / (double(width) * double(height));
    measureStretch(scene, charts, s, report);

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
            for (uint32_t t : chart.triangles)
                for (int k = 0; k < 3; ++k) {
                    const uint32_t old = mesh.indices[3 * size_t(t) + size_t(k)];
                    const auto [it, added] = vertexOf.emplace((uint64_t(old) << 32) | c, uint32_t(out.positions.size()));
                    if (added) {
                        const vec3& p = mesh.positions[old];
                        out.appendVertexOf(mesh, old);
                        out.source.vertices.push_back(mesh.source.vertices.empty() ? old : mesh.source.vertices[old]);
                        vec2 local(float((glm::dot(p, chart.axisU) - chart.lower.x) / s + kChartInset),
                                   float((glm::dot(p, chart.axisV) - chart.lower.y) / s + kChartInset));
                        vec2 texel;
                        if (chart.orientation >= 0) {
                            texel = placedOnAtlas(chart, local);
                        } else {
                            if (chart.turned) local = vec2(local.y, local.x);
                            texel = vec2(chart.origin) + vec2(float(kPaddingTexels)) + local;
                        }
                        out.uv1.push_back(texel / vec2(float(width), float(height)));
                    }
                    out.indices[3 * size_t(t) + size_t(k)] = it->second;
                }
        }
        scene.meshes[m] = std::move(out);
    });
    for (const auto& list : chartsOf) report.meshes += list.empty() ? 0 : 1;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

std::string describeLightmapUvs(const LightmapUvReport& report) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "lightmap UVs generated: %zu meshes, %zu charts in %d x %d, texel %.3g (scene units), charts %.0f%% "
                  "of the atlas, area stretch at most %.2f (mean %.3f), %.2f s",
                  report.meshes, report.charts, report.width, report.height, report.texelSize, 100.0 * report.occupancy,
                  report.maxStretch, report.meanStretch, report.seconds);
    return text;
}

}  // namespace vl
