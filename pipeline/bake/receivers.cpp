#include "bake/receivers.h"

#include "core/error.h"
#include "scene/surface.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/trace_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <map>
#include <utility>

namespace vl {

void LightmapSettings::validate() const {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw SettingsError("lightmap-res: " + std::to_string(width) + " x " + std::to_string(height) +
                            " is outside 1..16384");
    if (subsamplesPerAxis < 1 || subsamplesPerAxis > 8)
        throw SettingsError("lightmap-subsamples: " + std::to_string(subsamplesPerAxis) + " is outside 1..8");
}

namespace {

struct Point2 {
    double x, y;
};

// Edge function of the directed edge a→b at p (positive to the left in a y-down frame for
// a positively wound triangle). Evaluated in one canonical vertex order, so the reversed
// edge of the neighbouring triangle gets exactly the negated value: a probe on or next to
// a seam is owned by exactly one side.
double edgeFunction(Point2 a, Point2 b, Point2 p) {
    const bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
    if (swap) std::swap(a, b);
    const double e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    return swap ? -e : e;
}

// Tie rule for a probe exactly on edge a→b: the reversed edge gets the opposite answer.
bool ownsEdge(Point2 a, Point2 b) {
    const double dy = b.y - a.y, dx = b.x - a.x;
    return dy > 0.0 || (dy == 0.0 && dx < 0.0);
}

bool insideEdge(double e, Point2 a, Point2 b) { return e > 0.0 || (e == 0.0 && ownsEdge(a, b)); }

// A covered part of one texel by one triangle: the probes it covers (count, barycentric sums).
struct Fragment {
    uint32_t texel;
    uint32_t mesh;
    uint32_t localTriangle;
    uint32_t globalTriangle;
    uint32_t count;
    double sumB1, sumB2;
};

std::string quoted(const Scene& scene, uint32_t mesh) { return "'" + scene.meshes[mesh].name + "'"; }

LightmapAtlas rasterizeAtlas(const Scene& scene, const std::vector<uint32_t>& meshes,
                             const std::vector<uint32_t>& triangleOffsets, const LightmapSettings& settings,
                             const std::string& name, Diagnostics& diagnostics) {
    const int W = settings.width, H = settings.height, n = settings.subsamplesPerAxis;
    const size_t texels = static_cast<size_t>(W) * H;
    std::vector<uint64_t> probeBits(texels, 0);
    std::vector<int32_t> firstMesh(texels, -1);
    std::map<std::pair<uint32_t, uint32_t>, size_t> overlaps;
    std::vector<Fragment> fragments;
    size_t overlapping = 0;

    for (uint32_t m : meshes) {
        const Mesh& mesh = scene.meshes[m];
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t* idx = &mesh.indices[3 * t];
            Point2 P[3];
            bool finite = true;
            for (int k = 0; k < 3; ++k) {
                const vec2 uv = idx[k] < mesh.uv1.size() ? mesh.uv1[idx[k]] : vec2(NAN);
                finite = finite && std::isfinite(uv.x) && std::isfinite(uv.y);
                P[k] = {static_cast<double>(uv.x) * W, static_cast<double>(uv.y) * H};
            }
            if (!finite) {
                diagnostics.warn(scene.sourcePath + ": mesh '" + mesh.name + "' triangle " + std::to_string(t) +
                                 ": TEXCOORD_1 is not finite; left out of the lightmap");
                continue;
            }
            // Wind positively (edge functions ≥ 0 inside); remember where v1 and v2 went.
            int order[3] = {0, 1, 2};
            const double area2 = (P[1].x - P[0].x) * (P[2].y - P[0].y) - (P[1].y - P[0].y) * (P[2].x - P[0].x);
            if (area2 == 0.0) continue;  // no area in texel space: covers nothing
            if (area2 < 0.0) std::swap(order[1], order[2]);
            const Point2 A = P[order[0]], B = P[order[1]], C = P[order[2]];
            const double area = std::abs(area2);
            const int x0 = std::max(0, static_cast<int>(std::floor(std::min({A.x, B.x, C.x}))));
            const int y0 = std::max(0, static_cast<int>(std::floor(std::min({A.y, B.y, C.y}))));
            const int x1 = std::min(W - 1, static_cast<int>(std::floor(std::max({A.x, B.x, C.x}))));
            const int y1 = std::min(H - 1, static_cast<int>(std::floor(std::max({A.y, B.y, C.y}))));
            const uint32_t global = triangleOffsets[m] + static_cast<uint32_t>(t);
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) {
                    const uint32_t texel = static_cast<uint32_t>(static_cast<size_t>(y) * W + x);
                    Fragment f{texel, m, static_cast<uint32_t>(t), global, 0, 0.0, 0.0};
                    for (int j = 0; j < n; ++j)
                        for (int i = 0; i < n; ++i) {
                            const Point2 p{x + (i + 0.5) / n, y + (j + 0.5) / n};
                            const double eA = edgeFunction(B, C, p);  // weight of A
                            const double eB = edgeFunction(C, A, p);  // weight of B
                            const double eC = edgeFunction(A, B, p);  // weight of C
                            if (!insideEdge(eA, B, C) || !insideEdge(eB, C, A) || !insideEdge(eC, A, B)) continue;
                            double w[3];
                            w[order[0]] = eA / area;
                            w[order[1]] = eB / area;
                            w[order[2]] = eC / area;
                            const uint64_t bit = uint64_t(1) << (j * n + i);
                            if (probeBits[texel] & bit) {
                                ++overlapping;
                                ++overlaps[{static_cast<uint32_t>(firstMesh[texel]), m}];
                            }
                            probeBits[texel] |= bit;
                            if (firstMesh[texel] < 0) firstMesh[texel] = static_cast<int32_t>(m);
                            if (settings.samplePerTriangle) {
                                ++f.count;
                                f.sumB1 += w[1];
                                f.sumB2 += w[2];
                            } else {
                                fragments.push_back({texel, m, static_cast<uint32_t>(t), global, 1, w[1], w[2]});
                            }
                        }
                    if (f.count > 0) fragments.push_back(f);
                }
        }
    }

    for (const auto& [pair, count] : overlaps) {
        if (pair.first == pair.second)
            diagnostics.warn(scene.sourcePath + ": mesh " + quoted(scene, pair.first) + " overlaps itself in TEXCOORD_1 (" +
                             std::to_string(count) + " sub-texel points): those texels average the overlapping triangles");
        else
            diagnostics.warn(scene.sourcePath + ": meshes " + quoted(scene, pair.first) + " and " +
                             quoted(scene, pair.second) + " overlap in the shared TEXCOORD_1 atlas (" +
                             std::to_string(count) +
                             " sub-texel points): those texels average both; bake one image per mesh if they are "
                             "separate lightmaps");
    }

    // Group by texel (stable counting sort: mesh, then triangle, then probe order).
    LightmapAtlas atlas;
    atlas.name = name;
    atlas.meshes = meshes;
    atlas.overlappingProbes = overlapping;
    SurfaceSampleSet& set = atlas.receivers;
    set.width = W;
    set.height = H;
    set.begin.assign(texels + 1, 0);
    std::vector<uint32_t> probeTotal(texels, 0);
    for (const Fragment& f : fragments) {
        ++set.begin[f.texel + 1];
        probeTotal[f.texel] += f.count;
    }
    for (size_t i = 0; i < texels; ++i) set.begin[i + 1] += set.begin[i];
    set.samples.resize(fragments.size());
    std::vector<uint32_t> cursor(set.begin.begin(), set.begin.end() - 1);
    for (const Fragment& f : fragments) {
        const Mesh& mesh = scene.meshes[f.mesh];
        const vec2 b(static_cast<float>(f.sumB1 / f.count), static_cast<float>(f.sumB2 / f.count));
        const SurfacePoint point = interpolateSurface(mesh, f.localTriangle, b);
        SurfaceSample s;
        s.position = point.position;
        s.normal = point.normal;
        s.albedo = glm::clamp(vec3(baseColorAt(scene, mesh, f.localTriangle, b)), vec3(0.0f), vec3(1.0f));
        s.triangle = f.globalTriangle;
        s.weight = static_cast<float>(static_cast<double>(f.count) / probeTotal[f.texel]);
        set.samples[cursor[f.texel]++] = s;
    }
    atlas.mask = Image(W, H, 1, 0.0f);
    for (size_t i = 0; i < texels; ++i)
        if (set.covered(i)) {
            atlas.mask.pixels[i] = 1.0f;
            ++atlas.coveredTexels;
        }
    return atlas;
}

}  // namespace

std::vector<LightmapAtlas> buildLightmapReceivers(const Scene& scene, const LightmapSettings& settings,
                                                  Diagnostics& diagnostics) {
    settings.validate();
    std::vector<uint32_t> triangleOffsets(scene.meshes.size() + 1, 0);
    for (size_t m = 0; m < scene.meshes.size(); ++m)
        triangleOffsets[m + 1] = triangleOffsets[m] + static_cast<uint32_t>(scene.meshes[m].triangleCount());

    std::vector<uint32_t> baked;
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        if (mesh.triangleCount() == 0 || scene.materialOf(mesh).emissive()) continue;  // emitters are not baked
        if (mesh.uv1.empty()) {
            diagnostics.warn(scene.sourcePath + ": mesh '" + mesh.name +
                             "' has no TEXCOORD_1: it is not in the lightmap");
            continue;
        }
        baked.push_back(static_cast<uint32_t>(m));
    }
    std::vector<LightmapAtlas> atlases;
    if (baked.empty()) return atlases;
    if (settings.atlasPerMesh) {
        for (uint32_t m : baked)
            atlases.push_back(rasterizeAtlas(scene, {m}, triangleOffsets, settings, scene.meshes[m].name, diagnostics));
    } else {
        atlases.push_back(rasterizeAtlas(scene, baked, triangleOffsets, settings, "lightmap", diagnostics));
    }
    return atlases;
}

CameraReceivers buildCameraReceivers(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                                     int subsamplesPerAxis, int emissionSubsamplesPerAxis) {
    if (subsamplesPerAxis < 1 || subsamplesPerAxis > 16)
        throw SettingsError("camera-subsamples: " + std::to_string(subsamplesPerAxis) + " is outside 1..16");
    const int W = camera.width, H = camera.height, n = subsamplesPerAxis;
    const TraceSceneView sv = scene.view();
    const BvhView bv = bvh.view();
    CameraReceivers out;
    out.emission = Image(W, H, 3);
    out.albedo = Image(W, H, 3);
    out.mask = Image(W, H, 1);
    std::vector<std::vector<SurfaceSample>> rows(static_cast<size_t>(H));
    std::vector<std::vector<uint32_t>> rowCounts(static_cast<size_t>(H));
    const float weight = 1.0f / static_cast<float>(n * n);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& range) {
        for (int y = range.begin(); y < range.end(); ++y) {
            auto& samples = rows[static_cast<size_t>(y)];
            auto& counts = rowCounts[static_cast<size_t>(y)];
            for (int x = 0; x < W; ++x) {
                vec3 emission(0.0f), albedo(0.0f);
                uint32_t hits = 0;
                for (int j = 0; j < n; ++j)
                    for (int i = 0; i < n; ++i) {
                        const vec2 film(x + (i + 0.5f) / n, y + (j + 0.5f) / n);
                        const Ray ray = pinholeRay(camera, film);
                        Hit hit;
                        if (!intersectClosest(bv, ray, hit)) continue;
                        const SurfaceHit h = surfaceAt(sv, hit.triangle, hit.b1, hit.b2);
                        const bool front = glm::dot(h.geometricNormal, ray.direction) <= 0.0f;
                        vec3 normal = front ? h.shadingNormal : -h.shadingNormal;
                        const vec3 ng = front ? h.geometricNormal : -h.geometricNormal;
                        if (glm::dot(normal, ng) <= 0.0f) normal = ng;
                        SurfaceSample s;
                        s.position = h.position;
                        s.normal = normal;
                        s.albedo = baseColorAt(sv, h);
                        s.triangle = hit.triangle;
                        s.weight = weight;
                        samples.push_back(s);
                        emission += emissionAt(sv, h, -ray.direction) * weight;
                        albedo += s.albedo * weight;
                        ++hits;
                    }
                if (emissionSubsamplesPerAxis > n) {
                    // Emitters seen directly need only primary rays: sample their edges finer
                    // than the shading grid (a 2 × 2 grid turns a pixel a quarter covered by
                    // a bright emitter into 0 or a half).
                    const int ne = emissionSubsamplesPerAxis;
                    emission = vec3(0.0f);
                    for (int j = 0; j < ne; ++j)
                        for (int i = 0; i < ne; ++i) {
                            const Ray ray = pinholeRay(camera, vec2(x + (i + 0.5f) / ne, y + (j + 0.5f) / ne));
                            Hit hit;
                            if (intersectClosest(bv, ray, hit))
                                emission += emissionAt(sv, surfaceAt(sv, hit.triangle, hit.b1, hit.b2), -ray.direction);
                        }
                    emission /= static_cast<float>(ne * ne);
                }
                counts.push_back(hits);
                out.emission.setRgb(x, y, emission);
                out.albedo.setRgb(x, y, albedo);
                out.mask.at(x, y) = static_cast<float>(hits) * weight;
            }
        }
    });
    SurfaceSampleSet& set = out.receivers;
    set.width = W;
    set.height = H;
    set.begin.assign(static_cast<size_t>(W) * H + 1, 0);
    size_t element = 0;
    for (int y = 0; y < H; ++y) {
        for (uint32_t count : rowCounts[static_cast<size_t>(y)]) {
            set.begin[element + 1] = set.begin[element] + count;
            ++element;
        }
        set.samples.insert(set.samples.end(), rows[static_cast<size_t>(y)].begin(), rows[static_cast<size_t>(y)].end());
    }
    return out;
}

}  // namespace vl
