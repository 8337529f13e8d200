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

struct Chart {
    uint32_t mesh = 0;
    std::vector<uint32_t> triangles;
    vec3 axisU{1.0f, 0.0f, 0.0f}, axisV{0.0f, 1.0f, 0.0f};  // the plane it is projected onto
    vec2 lower{0.0f}, upper{0.0f};                           // its extent on those axes
    double projectedArea = 0.0;
    bool turned = false;  // packed with U along the atlas's v
    glm::ivec2 origin{0};  // texel of its rectangle's corner
    glm::ivec2 size{0};    // rectangle in texels, padding included, after `turned`
};

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
        const int a = static_cast<int>(std::ceil(double(chart.upper.x - chart.lower.x) / s)) + 2 * kPaddingTexels + 1;
        const int b = static_cast<int>(std::ceil(double(chart.upper.y - chart.lower.y) / s)) + 2 * kPaddingTexels + 1;
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
    // Where the charts' padding alone overfills the atlas (thousands of small charts), the
    // atlas doubles until the charts take at least a quarter of it.
    const auto lowest = [&] { return std::sqrt(std::max(projected, 1e-30) / (double(width) * double(height))); };
    const auto fits = [&](double s) { return pack(charts, order, s, width, height); };
    while (!fits(2.0 * lowest()) && std::max(width, height) < kMaxAtlasSide) {
        width = std::min(2 * width, kMaxAtlasSide);
        height = std::min(2 * height, kMaxAtlasSide);
    }
    double lower = lowest();
    double upper = lower;
    for (int k = 0; k < 60 && !fits(upper); ++k) upper *= 2.0;
    if (!fits(upper))
        throw Error("lightmap UVs: " + std::to_string(charts.size()) + " charts do not fit a " + std::to_string(width) +
                    " x " + std::to_string(height) + " atlas at any texel size (each takes " +
                    std::to_string(2 * kPaddingTexels + 1) + " texels of padding along each axis)");
    report.width = width;
    report.height = height;
    for (int k = 0; k < 24; ++k) {
        const double middle = 0.5 * (lower + upper);
        if (pack(charts, order, middle, width, height))
            upper = middle;
        else
            lower = middle;
    }
    const double s = upper;
    pack(charts, order, s, width, height);
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
        Mesh out = mesh;
        out.positions.clear();
        out.normals.clear();
        out.uv0.clear();
        out.colors.clear();
        out.uv1.clear();
        out.source.vertices.clear();
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
                        out.positions.push_back(p);
                        out.source.vertices.push_back(mesh.source.vertices.empty() ? old : mesh.source.vertices[old]);
                        if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[old]);
                        if (!mesh.uv0.empty()) out.uv0.push_back(mesh.uv0[old]);
                        if (!mesh.colors.empty()) out.colors.push_back(mesh.colors[old]);
                        vec2 local(float((glm::dot(p, chart.axisU) - chart.lower.x) / s),
                                   float((glm::dot(p, chart.axisV) - chart.lower.y) / s));
                        if (chart.turned) local = vec2(local.y, local.x);
                        const vec2 texel = vec2(chart.origin) + vec2(float(kPaddingTexels)) + local;
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
