// Generated lightmap UVs (unwrap/lightmap_uvs.h): charts that never share or touch texels,
// one texel size for the whole scene, bounded stretch.
#include "scene/gltf_loader.h"
#include "support/paths.h"
#include "unwrap/lightmap_uvs.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

using namespace vl;

namespace {

// Texels each triangle touches (its texel squares overlap the triangle: tested at 8 × 8 points
// per texel of its bounding box, the box's own corners included), labelled by the triangle's
// chart: the connected set of triangles sharing uv1 corners. Returns, per texel, the chart
// (−1 none, −2 two charts).
std::vector<int> chartTexels(const Scene& scene, int width, int height, int& charts) {
    // Charts: union-find over (mesh, uv1 corner) keys.
    std::vector<int> parent;
    const auto find = [&](int x) {
        while (parent[size_t(x)] != x) x = parent[size_t(x)] = parent[size_t(parent[size_t(x)])];
        return x;
    };
    std::map<std::tuple<size_t, float, float>, int> cornerId;
    std::vector<std::array<int, 3>> triangleCorners;
    std::vector<std::pair<size_t, size_t>> triangles;  // (mesh, triangle)
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            std::array<int, 3> ids;
            for (int k = 0; k < 3; ++k) {
                const vec2 uv = mesh.uv1[mesh.indices[3 * t + size_t(k)]];
                const auto [it, added] = cornerId.emplace(std::make_tuple(m, uv.x, uv.y), int(parent.size()));
                if (added) parent.push_back(int(parent.size()));
                ids[size_t(k)] = it->second;
            }
            parent[size_t(find(ids[1]))] = find(ids[0]);
            parent[size_t(find(ids[2]))] = find(ids[0]);
            triangleCorners.push_back(ids);
            triangles.emplace_back(m, t);
        }
    }
    std::map<int, int> chartOfRoot;
    std::vector<int> owner(size_t(width) * size_t(height), -1);
    for (size_t i = 0; i < triangles.size(); ++i) {
        const int root = find(triangleCorners[i][0]);
        const int chart = chartOfRoot.emplace(root, int(chartOfRoot.size())).first->second;
        const Mesh& mesh = scene.meshes[triangles[i].first];
        vec2 p[3];
        for (int k = 0; k < 3; ++k)
            p[k] = mesh.uv1[mesh.indices[3 * triangles[i].second + size_t(k)]] * vec2(float(width), float(height));
        const float area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[1].y - p[0].y) * (p[2].x - p[0].x);
        if (area == 0.0f) continue;
        const auto inside = [&](const vec2& q) {
            float s[3];
            for (int k = 0; k < 3; ++k) {
                const vec2 a = p[k], b = p[(k + 1) % 3];
                s[k] = ((b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x)) * (area > 0.0f ? 1.0f : -1.0f);
            }
            return s[0] >= 0.0f && s[1] >= 0.0f && s[2] >= 0.0f;
        };
        const vec2 lo = glm::min(p[0], glm::min(p[1], p[2])), hi = glm::max(p[0], glm::max(p[1], p[2]));
        for (int y = std::max(0, int(std::floor(lo.y))); y <= std::min(height - 1, int(std::floor(hi.y))); ++y)
            for (int x = std::max(0, int(std::floor(lo.x))); x <= std::min(width - 1, int(std::floor(hi.x))); ++x) {
                bool touched = false;
                for (int j = 0; j <= 8 && !touched; ++j)
                    for (int i2 = 0; i2 <= 8 && !touched; ++i2)
                        touched = inside(vec2(float(x) + float(i2) / 8.0f, float(y) + float(j) / 8.0f));
                // A triangle smaller than the sampling steps still touches its corners' texels.
                for (int k = 0; k < 3; ++k) touched = touched || (int(std::floor(p[k].x)) == x && int(std::floor(p[k].y)) == y);
                if (!touched) continue;
                int& o = owner[size_t(y) * size_t(width) + size_t(x)];
                o = (o == -1 || o == chart) ? chart : -2;
            }
    }
    charts = int(chartOfRoot.size());
    return owner;
}

// The least Chebyshev distance, in texels, between texels of two different charts (a large
// number when there is one chart).
int closestCharts(const std::vector<int>& owner, int width, int height) {
    int closest = 1 << 20;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const int a = owner[size_t(y) * size_t(width) + size_t(x)];
            if (a < 0) continue;
            for (int dy = -3; dy <= 3; ++dy)
                for (int dx = -3; dx <= 3; ++dx) {
                    const int u = x + dx, v = y + dy;
                    if (u < 0 || v < 0 || u >= width || v >= height) continue;
                    const int b = owner[size_t(v) * size_t(width) + size_t(u)];
                    if (b >= 0 && b != a) closest = std::min(closest, std::max(std::abs(dx), std::abs(dy)));
                }
        }
    return closest;
}

// Pairs of triangles of one mesh whose uv1 triangles overlap in area by more than a
// thousandth of a texel along every separating axis (triangles sharing an edge only touch).
// Triangles are bucketed by the texels their boxes cover.
size_t overlappingPairs(const Scene& scene, int width, int height) {
    size_t pairs = 0;
    const vec2 size{float(width), float(height)};
    for (const Mesh& mesh : scene.meshes) {
        std::map<std::pair<int, int>, std::vector<size_t>> buckets;
        const auto corners = [&](size_t t, vec2 (&p)[3]) {
            for (int k = 0; k < 3; ++k) p[k] = mesh.uv1[mesh.indices[3 * t + size_t(k)]] * size;
        };
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            vec2 p[3];
            corners(t, p);
            const vec2 lo = glm::min(p[0], glm::min(p[1], p[2])), hi = glm::max(p[0], glm::max(p[1], p[2]));
            for (int y = int(lo.y); y <= int(hi.y); ++y)
                for (int x = int(lo.x); x <= int(hi.x); ++x) buckets[{x, y}].push_back(t);
        }
        std::set<std::pair<size_t, size_t>> seen;
        for (const auto& [cell, list] : buckets)
            for (size_t i = 0; i < list.size(); ++i)
                for (size_t j = i + 1; j < list.size(); ++j) {
                    vec2 a[3], b[3];
                    corners(list[i], a);
                    corners(list[j], b);
                    bool separated = false;
                    for (const vec2* tri : {a, b})
                        for (int k = 0; k < 3 && !separated; ++k) {
                            const vec2 e = tri[(k + 1) % 3] - tri[k];
                            vec2 axis(-e.y, e.x);
                            if (!(glm::length(axis) > 0.0f)) continue;
                            axis /= glm::length(axis);
                            float loA = 1e30f, hiA = -1e30f, loB = 1e30f, hiB = -1e30f;
                            for (int q = 0; q < 3; ++q) {
                                loA = std::min(loA, glm::dot(a[q], axis));
                                hiA = std::max(hiA, glm::dot(a[q], axis));
                                loB = std::min(loB, glm::dot(b[q], axis));
                                hiB = std::max(hiB, glm::dot(b[q], axis));
                            }
                            separated = hiA <= loB + 1e-3f || hiB <= loA + 1e-3f;
                        }
                    if (!separated && seen.insert({list[i], list[j]}).second) ++pairs;
                }
    }
    return pairs;
}

void checkAtlas(Scene& scene, const LightmapUvReport& report, const std::string& what) {
    INFO(what << ": " << describeLightmapUvs(report));
    int charts = 0;
    const std::vector<int> owner = chartTexels(scene, report.width, report.height, charts);
    CHECK(std::count(owner.begin(), owner.end(), -2) == 0);  // no texel of two charts
    // Two charts' texels at least 2 × 2 padding texels apart, less a texel each side for
    // the triangles' edges inside their outer texels: at least 3 (2 empty texels between).
    CHECK(closestCharts(owner, report.width, report.height) >= 3);
    CHECK(charts == int(report.charts));
    // Within a chart too: a surface folding back under itself within the chart's cone is
    // refused, not projected over itself.
    CHECK(overlappingPairs(scene, report.width, report.height) == 0);
    // One texel size: every triangle's uv area in texels is its 3D area / s², shrunk by at
    // most cos 30° (its tilt against its chart's plane).
    const double s2 = report.texelSize * report.texelSize;
    for (const Mesh& mesh : scene.meshes) {
        REQUIRE(mesh.uv1.size() == mesh.positions.size());
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t* i = &mesh.indices[3 * t];
            const double area3 = 0.5 * glm::length(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]],
                                                               mesh.positions[i[2]] - mesh.positions[i[0]]));
            if (area3 < 4.0 * s2) continue;  // below a few texels, uv1's float rounding is a part in a thousand
            const vec2 a = mesh.uv1[i[0]] * vec2(float(report.width), float(report.height));
            const vec2 b = mesh.uv1[i[1]] * vec2(float(report.width), float(report.height));
            const vec2 c = mesh.uv1[i[2]] * vec2(float(report.width), float(report.height));
            const double texels = 0.5 * std::abs(double(b.x - a.x) * (c.y - a.y) - double(b.y - a.y) * (c.x - a.x));
            const double ratio = texels * s2 / area3;
            CHECK(ratio <= 1.0 + 1e-3);
            CHECK(ratio >= std::cos(glm::radians(double(kChartAngleDegrees))) - 1e-3);
        }
    }
}

std::vector<uint32_t> everyMesh(const Scene& scene) {
    std::vector<uint32_t> meshes(scene.meshes.size());
    std::iota(meshes.begin(), meshes.end(), 0u);
    return meshes;
}

}  // namespace

TEST_CASE("A box unwraps into its six faces, packed without overlap at one texel size", "[unwrap]") {
    VL_SKIP_WITHOUT_SHARED();
    Scene scene = loadGltf(test::sharedDir() + "/scenes/khronos-sample-assets/Models/BoxTextured/glTF/BoxTextured.gltf");
    const size_t triangles = scene.meshes[0].triangleCount();
    const LightmapUvReport report = generateLightmapUvs(scene, everyMesh(scene), 256, 256);
    CHECK(report.charts == 6);
    CHECK(report.width == 256);
    CHECK(report.maxStretch == Approx(1.0).epsilon(1e-4));  // flat faces projected flat
    // Six squares in shelves of three: at most 6 / 9 of the atlas, at least half of it.
    CHECK(report.occupancy > 0.5);
    CHECK(report.occupancy <= 6.0 / 9.0);
    CHECK(scene.meshes[0].triangleCount() == triangles);
    CHECK(scene.meshes[0].positions.size() == 24);  // each face's corners its own
    checkAtlas(scene, report, "BoxTextured");
}

TEST_CASE("Generated UVs hold on a Cornell box of ten meshes and on a level of 15,000 charts", "[unwrap]") {
    // nvpro's Cornell box (no TEXCOORD_1) in its 256² atlas; zdm2's thousands of small charts
    // in the 256² asked for too. That atlas grew to 1024² for their padding until the atlas
    // became the user's choice (issue 34): now the texel size fits the charts to the atlas,
    // and the charts that get under 2 × 2 texels are reported.
    VL_SKIP_WITHOUT_SHARED();
    Scene box = loadGltf(test::sharedDir() + "/scenes/cornellbox-nvpro/cornellBox.gltf");
    const LightmapUvReport boxReport = generateLightmapUvs(box, everyMesh(box), 256, 256);
    CHECK(boxReport.width == 256);
    CHECK(boxReport.maxStretch <= 1.0 / std::cos(glm::radians(double(kChartAngleDegrees))) + 1e-3);
    checkAtlas(box, boxReport, "nvpro Cornell box");

    Scene level = loadGltf(test::sharedDir() + "/scenes/interior-zdm2-godot/zdm2.glb");
    const LightmapUvReport levelReport = generateLightmapUvs(level, everyMesh(level), 256, 256);
    CHECK(levelReport.width == 256);
    CHECK(levelReport.height == 256);
    CHECK(levelReport.charts < levelReport.grownCharts);  // merged
    REQUIRE(levelReport.smallCharts.size() == 1);         // one mesh
    CHECK(levelReport.smallCharts[0].mesh == level.meshes[0].name);
    CHECK(levelReport.smallChartCount() > levelReport.charts / 2);  // a 2.6 m texel on a level of trim
    CHECK(levelReport.smallChartCount() <= levelReport.charts);
    checkAtlas(level, levelReport, "zdm2");

    // Issue 14's 60% on zdm2, asked for at 2048² (README): the charts' area alone, which the
    // covered texels exceed.
    Scene large = loadGltf(test::sharedDir() + "/scenes/interior-zdm2-godot/zdm2.glb");
    const LightmapUvReport largeReport = generateLightmapUvs(large, everyMesh(large), 2048, 2048);
    CHECK(largeReport.width == 2048);
    CHECK(largeReport.occupancy >= 0.60);
}

TEST_CASE("An atlas size outside 16 .. 16384 is refused by name; a scene without triangles keeps its atlas", "[unwrap]") {
    Scene scene;
    CHECK_THROWS_WITH(generateLightmapUvs(scene, {}, 8, 256), Catch::Contains("lightmap UVs") && Catch::Contains("8 x 256"));
    const LightmapUvReport report = generateLightmapUvs(scene, {}, 64, 32);
    CHECK(report.charts == 0);
    CHECK(report.width == 64);  // the bake takes this size: never 0
    CHECK(report.height == 32);
    CHECK_THROWS_WITH(generateLightmapUvs(scene, {3}, 64, 32), Catch::Contains("mesh 3 of a scene of 0"));
}

namespace {

// A mesh made in code: an nx × ny grid of quads (two triangles each) over surface(u, v),
// u, v in [0, 1], counter-clockwise about ∂/∂u × ∂/∂v.
template <typename Surface>
Mesh gridMesh(const std::string& name, int nx, int ny, Surface&& surface) {
    Mesh mesh;
    mesh.name = name;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) mesh.positions.push_back(surface(float(i) / float(nx), float(j) / float(ny)));
    const auto at = [&](int i, int j) { return uint32_t(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
            mesh.indices.insert(mesh.indices.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    return mesh;
}

// A triangle (counter-clockwise) appended to a mesh.
void addTriangle(Mesh& mesh, vec3 a, vec3 b, vec3 c) {
    const uint32_t first = uint32_t(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {a, b, c});
    mesh.indices.insert(mesh.indices.end(), {first, first + 1, first + 2});
}

}  // namespace

TEST_CASE("A sheet curved past the chart cone unrolls into one chart, metres from the origin", "[unwrap]") {
    // A corrugated sheet (slopes to 56°: 120° of normals) is developable: flattened
    // conformally it unrolls with no stretch, where projections along one normal each took a
    // 60° band of it. Three metres from the origin, as a room's furniture is: the overlap test
    // in floats there refused most neighbours (the grey-white room's cushions came out in
    // thousands of one-triangle charts).
    Scene scene;
    scene.meshes.push_back(gridMesh("sheet", 96, 24, [](float u, float v) {
        return vec3(3.0f + u, 1.0f + 0.12f * std::sin(4.0f * kPi * u), -2.0f + 1.5f * v);
    }));
    const LightmapUvReport report = generateLightmapUvs(scene, {0}, 128, 128);
    INFO(describeLightmapUvs(report));
    CHECK(report.grownCharts >= 4);
    CHECK(report.charts == 1);
    CHECK(report.maxStretch <= 1.0 / std::cos(glm::radians(double(kChartAngleDegrees))) + 1e-3);
    CHECK(report.smallCharts.empty());
    checkAtlas(scene, report, "sheet");
}

TEST_CASE("A strip folded smoothly off a face merges into its chart, a hard-edged one keeps its own; a speck no chart can take is reported by mesh", "[unwrap]") {
    // A 1 m table top with a 1 cm lip down its front edge (one mesh: they share the edge),
    // and a 5 mm speck on its own: at 64² the texel is about 1.6 cm, so the lip and the speck
    // are under 2 texels wide. Where the edge is shaded smooth (the top's and the lip's vertex
    // normals agree along it: a rounded edge) the lip unfolds into the top's chart. Where it
    // is a hard edge (each face its own normal, or no normals at all) the two are lit apart, a
    // sunlit top over a shaded front, and a texel of one chart on the fold would hold their
    // mean: the lip stays a chart of its own, reported small. The speck has no neighbour.
    for (const char* edge : {"smooth", "hard", "no normals"}) {
        DYNAMIC_SECTION(edge) {
            Scene scene;
            Mesh table = gridMesh("table", 1, 1, [](float u, float v) { return vec3(u, 0.75f, -v); });
            addTriangle(table, vec3(0.0f, 0.75f, 0.0f), vec3(0.0f, 0.74f, 0.0f), vec3(1.0f, 0.74f, 0.0f));
            addTriangle(table, vec3(0.0f, 0.75f, 0.0f), vec3(1.0f, 0.74f, 0.0f), vec3(1.0f, 0.75f, 0.0f));
            const std::string kind = edge;
            if (kind != "no normals") {
                const vec3 up(0.0f, 1.0f, 0.0f), front(0.0f, 0.0f, 1.0f), rounded = glm::normalize(up + front);
                for (const vec3& p : table.positions) {
                    const bool onEdge = p.y == 0.75f && p.z == 0.0f;
                    const bool onLip = table.normals.size() >= 4;  // the grid's 4 corners come first
                    table.normals.push_back(kind == "smooth" && onEdge ? rounded : onLip ? front : up);
                }
            }
            scene.meshes.push_back(table);
            Mesh speck;
            speck.name = "speck";
            addTriangle(speck, vec3(0.5f, 1.0f, -0.5f), vec3(0.505f, 1.0f, -0.5f), vec3(0.5f, 1.0f, -0.505f));
            scene.meshes.push_back(speck);
            const LightmapUvReport report = generateLightmapUvs(scene, {0, 1}, 64, 64);
            INFO(describeLightmapUvs(report));
            CHECK(report.grownCharts == 3);
            if (kind == "smooth") {
                CHECK(report.charts == 2);
                REQUIRE(report.smallCharts.size() == 1);
                CHECK(report.smallCharts[0].mesh == "speck");
                CHECK(report.smallChartCount() == 1);
            } else {
                CHECK(report.charts == 3);
                REQUIRE(report.smallCharts.size() == 2);
                CHECK(report.smallChartCount() == 2);
                std::vector<std::string> small;
                for (const SmallCharts& c : report.smallCharts) small.push_back(c.mesh);
                std::sort(small.begin(), small.end());
                CHECK(small == std::vector<std::string>{"speck", "table"});
            }
            checkAtlas(scene, report, std::string("table and speck, ") + edge + " edge");
        }
    }
}

TEST_CASE("A texel size gives that density in the smallest atlas that holds it; a power of two, at least that density", "[unwrap]") {
    VL_SKIP_WITHOUT_SHARED();
    const std::string path = test::sharedDir() + "/scenes/cornellbox-nvpro/cornellBox.gltf";
    const double texel = 0.05;  // the box is 10 units a side: 5 cm texels in a few hundred a side
    // The atlas that fits at the texel size, by the size asked: 4 texels less holds them only
    // at a coarser texel.
    const auto exactly = [&](int side) {
        Scene scene = loadGltf(path);
        return generateLightmapUvs(scene, everyMesh(scene), side, side);
    };
    {
        Scene scene = loadGltf(path);
        AtlasRequest request;
        request.texelSize = texel;
        const LightmapUvReport report = generateLightmapUvs(scene, everyMesh(scene), request);
        INFO(describeLightmapUvs(report));
        CHECK(report.texelSize == texel);
        CHECK(report.askedTexelSize == texel);
        CHECK(report.width == report.height);
        CHECK(report.width % 4 == 0);
        CHECK(report.width > 256);
        CHECK(exactly(report.width - 4).texelSize > texel);
        checkAtlas(scene, report, "nvpro box at 5 cm texels");
    }
    {
        Scene scene = loadGltf(path);
        AtlasRequest request;
        request.texelSize = texel;
        request.powerOfTwo = true;
        request.maxSide = kMaxAutoAtlasSide;
        const LightmapUvReport report = generateLightmapUvs(scene, everyMesh(scene), request);
        INFO(describeLightmapUvs(report));
        CHECK(report.texelSize <= texel);
        CHECK(report.width == report.height);
        CHECK((report.width & (report.width - 1)) == 0);
        CHECK(exactly(report.width / 2).texelSize > texel);
        checkAtlas(scene, report, "nvpro box, power of two");
    }
    {
        // Finer than the largest side allows: that side, at the texel size that fits.
        Scene scene = loadGltf(path);
        AtlasRequest request;
        request.texelSize = texel;
        request.maxSide = 128;
        const LightmapUvReport report = generateLightmapUvs(scene, everyMesh(scene), request);
        CHECK(report.width == 128);
        CHECK(report.texelSize > texel);
        CHECK(report.askedTexelSize == texel);
    }
}

TEST_CASE("A texel size that is not a positive length, or a largest side that rounds badly, is refused", "[unwrap]") {
    Scene scene;
    scene.meshes.push_back(gridMesh("floor", 1, 1, [](float u, float v) { return vec3(u, 0.0f, -v); }));
    for (const double texel : {-0.01, std::nan(""), double(INFINITY)}) {
        AtlasRequest request;
        request.texelSize = texel;
        CHECK_THROWS_WITH(generateLightmapUvs(scene, {0}, request), Catch::Contains("texel size"));
    }
    AtlasRequest request;
    request.texelSize = 0.01;
    request.maxSide = 1022;
    CHECK_THROWS_WITH(generateLightmapUvs(scene, {0}, request), Catch::Contains("1022") && Catch::Contains("multiple of 4"));
    request.maxSide = 1020;
    request.powerOfTwo = true;
    CHECK_THROWS_WITH(generateLightmapUvs(scene, {0}, request), Catch::Contains("power of two"));
}
