#include "bake/receivers.h"

#include "core/error.h"
#include "scene/surface.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/trace_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <utility>

namespace vl {

namespace {

// "job.json: atlases[0]: atlas 'walls'", to begin a message.
std::string atlasLabel(const AtlasGroup& group) {
    return (group.origin.empty() ? "" : group.origin + ": ") + "atlas '" + group.name + "'";
}

// "atlas 'walls' (job.json: atlases[0])", within a sentence.
std::string atlasReference(const AtlasGroup& group) {
    return "atlas '" + group.name + "'" + (group.origin.empty() ? "" : " (" + group.origin + ")");
}

std::string lowercase(std::string text) {
    for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return text;
}

bool endsWith(const std::string& text, const std::string& suffix) {
    return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The name is the file stem of <name>.exr, <name>_direct.exr, …, beside image.exr: it must
// be a file name on every system and must not read as another output's file.
void checkAtlasName(const AtlasGroup& group) {
    bool safe = !group.name.empty() && group.name.size() <= 64;
    for (char c : group.name) safe = safe && (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_');
    if (!safe)
        throw SettingsError(atlasLabel(group) +
                            ": an atlas name must be 1 to 64 letters, digits, '-' or '_' (it names the files)");
    const std::string lower = lowercase(group.name);
    for (const char* part : {"_direct", "_indirect", "_mask"})
        if (endsWith(lower, part))
            throw SettingsError(atlasLabel(group) + ": an atlas name must not end in '" + part +
                                "', the suffix of an atlas's " + (part + 1) + " file");
    if (lower == "image" || lower.rfind("image_", 0) == 0)
        throw SettingsError(atlasLabel(group) + ": atlas names 'image' and 'image_…' are the camera images' files");
}

}  // namespace

void LightmapSettings::validate() const {
    if (width < 1 || height < 1 || width > kMaxLightmapResolution || height > kMaxLightmapResolution)
        throw SettingsError("lightmap-res: " + std::to_string(width) + " x " + std::to_string(height) + " is outside 1.." +
                            std::to_string(kMaxLightmapResolution));
    if (subsamplesPerAxis < 1 || subsamplesPerAxis > 8)
        throw SettingsError("lightmap-subsamples: " + std::to_string(subsamplesPerAxis) + " is outside 1..8");
    if (!atlases.empty() && atlasPerMesh)
        throw SettingsError(atlasLabel(atlases.front()) +
                            ": atlas groups and one atlas per mesh exclude each other; give one or the other");
    std::map<std::string, const AtlasGroup*> byName;      // lower case: one file system may not tell case
    std::map<std::string, const AtlasGroup*> groupOfMesh;
    for (const AtlasGroup& group : atlases) {
        checkAtlasName(group);
        const auto [named, fresh] = byName.emplace(lowercase(group.name), &group);
        if (!fresh) throw SettingsError(atlasLabel(group) + ": the name is taken by " + atlasReference(*named->second));
        const bool sharedResolution = group.width == 0 && group.height == 0;
        if (!sharedResolution && (group.width < 1 || group.height < 1 || group.width > kMaxLightmapResolution ||
                                  group.height > kMaxLightmapResolution))
            throw SettingsError(atlasLabel(group) + ": resolution " + std::to_string(group.width) + " x " +
                                std::to_string(group.height) + " is outside 1.." + std::to_string(kMaxLightmapResolution) +
                                " (the range of lightmap-res)");
        if (group.meshes.empty()) throw SettingsError(atlasLabel(group) + ": names no meshes");
        for (const std::string& mesh : group.meshes) {
            const auto [owner, first] = groupOfMesh.emplace(mesh, &group);
            if (!first && owner->second != &group)
                throw SettingsError(atlasLabel(group) + ": mesh '" + mesh + "' is already in " +
                                    atlasReference(*owner->second) + "; a mesh bakes into one atlas");
        }
    }
}

double LightmapSettings::maxTexels() const {
    double texels = static_cast<double>(width) * height;
    for (const AtlasGroup& group : atlases)
        texels += group.width == 0 ? static_cast<double>(width) * height : static_cast<double>(group.width) * group.height;
    return texels;
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
                             const std::string& name, int W, int H, Diagnostics& diagnostics) {
    const int n = settings.subsamplesPerAxis;
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
                             quoted(scene, pair.second) + " overlap in the TEXCOORD_1 atlas '" + name + "' (" +
                             std::to_string(count) +
                             " sub-texel points): those texels average both; give them separate atlases if they are "
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

// The glTF mesh a loaded mesh comes from: its name without the "/<primitive>" the loader adds.
std::string gltfMeshName(const std::string& name) {
    const size_t slash = name.rfind('/');
    if (slash == std::string::npos || slash + 1 == name.size()) return name;
    for (size_t i = slash + 1; i < name.size(); ++i)
        if (!std::isdigit(static_cast<unsigned char>(name[i]))) return name;
    return name.substr(0, slash);
}

bool namesMesh(const std::string& entry, const Mesh& mesh) {
    return entry == mesh.name || (!mesh.node.empty() && entry == mesh.node) || entry == gltfMeshName(mesh.name);
}

std::string namesInScene(const Scene& scene) {
    std::vector<std::string> names;
    for (const Mesh& mesh : scene.meshes)
        for (const std::string& name : {mesh.node, gltfMeshName(mesh.name)})
            if (!name.empty() && std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    constexpr size_t kListed = 16;
    std::string list;
    for (size_t i = 0; i < std::min(names.size(), kListed); ++i) list += (i ? ", " : "") + names[i];
    if (names.size() > kListed) list += ", … (" + std::to_string(names.size()) + " in all)";
    return list;
}

// Which group bakes each scene mesh (-1: the shared atlas).
std::vector<int> assignAtlasGroups(const Scene& scene, const std::vector<AtlasGroup>& groups) {
    std::vector<int> groupOf(scene.meshes.size(), -1);
    for (size_t g = 0; g < groups.size(); ++g)
        for (const std::string& entry : groups[g].meshes) {
            bool found = false;
            for (size_t m = 0; m < scene.meshes.size(); ++m) {
                if (!namesMesh(entry, scene.meshes[m])) continue;
                found = true;
                // Two different names (a node and its mesh) can select one mesh.
                const int owner = groupOf[m];
                if (owner >= 0 && owner != static_cast<int>(g))
                    throw SettingsError(atlasLabel(groups[g]) + ": '" + entry + "' selects mesh '" + scene.meshes[m].name +
                                        "', which " + atlasReference(groups[static_cast<size_t>(owner)]) +
                                        " already holds; a mesh bakes into one atlas");
                groupOf[m] = static_cast<int>(g);
            }
            if (!found)
                throw SettingsError(atlasLabel(groups[g]) + ": " + scene.sourcePath + " has no node or mesh named '" +
                                    entry + "' (it has: " + namesInScene(scene) + ")");
        }
    return groupOf;
}

std::string meshList(const Scene& scene, const std::vector<uint32_t>& meshes) {
    std::string list;
    for (uint32_t m : meshes) list += (list.empty() ? "" : ", ") + quoted(scene, m);
    return list;
}

struct AtlasMembers {
    std::vector<uint32_t> shared;                // meshes of the shared atlas (or of one image each)
    std::vector<std::vector<uint32_t>> grouped;  // per atlas group
};

// Meshes that are not baked (emitters, meshes without TEXCOORD_1) are left out, with a
// warning when `diagnostics` is given.
AtlasMembers assignAtlasMembers(const Scene& scene, const LightmapSettings& settings, Diagnostics* diagnostics) {
    const std::vector<int> groupOf = assignAtlasGroups(scene, settings.atlases);
    AtlasMembers members;
    members.grouped.resize(settings.atlases.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        const int group = groupOf[m];
        const auto leftOut = [&](const std::string& why) {
            if (!diagnostics) return;
            const std::string atlas =
                group < 0 ? "the lightmap" : atlasReference(settings.atlases[static_cast<size_t>(group)]);
            diagnostics->warn(scene.sourcePath + ": mesh '" + mesh.name + "' " + why + ": it is not in " + atlas);
        };
        if (mesh.triangleCount() == 0 || scene.materialOf(mesh).emissive()) {
            if (group >= 0) leftOut("is emissive, and emitters are not baked");  // silent unless asked for by name
            continue;
        }
        if (mesh.uv1.empty()) {
            leftOut("has no TEXCOORD_1");
            continue;
        }
        (group < 0 ? members.shared : members.grouped[static_cast<size_t>(group)]).push_back(static_cast<uint32_t>(m));
    }
    if (!members.shared.empty() && !settings.atlasPerMesh)
        for (const AtlasGroup& group : settings.atlases)
            if (group.name == "lightmap")
                throw SettingsError(atlasLabel(group) + ": 'lightmap' is the shared atlas of the meshes no group names (" +
                                    meshList(scene, members.shared) +
                                    "): name the group otherwise or add those meshes to it");
    return members;
}

}  // namespace

void checkAtlasGroups(const Scene& scene, const LightmapSettings& settings) {
    settings.validate();
    assignAtlasMembers(scene, settings, nullptr);
}

std::vector<LightmapAtlas> buildLightmapReceivers(const Scene& scene, const LightmapSettings& settings,
                                                  Diagnostics& diagnostics) {
    settings.validate();
    std::vector<uint32_t> triangleOffsets(scene.meshes.size() + 1, 0);
    for (size_t m = 0; m < scene.meshes.size(); ++m)
        triangleOffsets[m + 1] = triangleOffsets[m] + static_cast<uint32_t>(scene.meshes[m].triangleCount());

    const AtlasMembers members = assignAtlasMembers(scene, settings, &diagnostics);
    std::vector<LightmapAtlas> atlases;
    if (settings.atlasPerMesh) {
        for (uint32_t m : members.shared)
            atlases.push_back(rasterizeAtlas(scene, {m}, triangleOffsets, settings, scene.meshes[m].name, settings.width,
                                             settings.height, diagnostics));
        return atlases;
    }
    if (!members.shared.empty())
        atlases.push_back(rasterizeAtlas(scene, members.shared, triangleOffsets, settings, "lightmap", settings.width,
                                         settings.height, diagnostics));
    for (size_t g = 0; g < settings.atlases.size(); ++g) {
        const AtlasGroup& group = settings.atlases[g];
        if (members.grouped[g].empty()) {
            diagnostics.warn(scene.sourcePath + ": " + atlasReference(group) + " has no mesh to bake: no image for it");
            continue;
        }
        const bool sharedResolution = group.width == 0 && group.height == 0;
        atlases.push_back(rasterizeAtlas(scene, members.grouped[g], triangleOffsets, settings, group.name,
                                         sharedResolution ? settings.width : group.width,
                                         sharedResolution ? settings.height : group.height, diagnostics));
    }
    return atlases;
}

CameraReceivers buildCameraReceivers(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                                     int subsamplesPerAxis, int emissionSubsamplesPerAxis, bool samplePerTriangle) {
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
    std::vector<uint8_t> seesEmitter(static_cast<size_t>(W) * static_cast<size_t>(H), 0);
    const float weight = 1.0f / static_cast<float>(n * n);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& range) {
        for (int y = range.begin(); y < range.end(); ++y) {
            auto& samples = rows[static_cast<size_t>(y)];
            auto& counts = rowCounts[static_cast<size_t>(y)];
            for (int x = 0; x < W; ++x) {
                vec3 emission(0.0f), albedo(0.0f);
                uint32_t hits = 0, pixelSamples = 0;
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
                        // One sample per triangle the pixel sees: its rays' hits merged.
                        bool merged = false;
                        if (samplePerTriangle)
                            for (size_t k = samples.size() - pixelSamples; k < samples.size() && !merged; ++k)
                                if (samples[k].triangle == s.triangle) {
                                    SurfaceSample& m = samples[k];
                                    const float total = m.weight + s.weight;
                                    m.position = (m.weight * m.position + s.weight * s.position) / total;
                                    m.normal += s.normal;
                                    m.albedo = (m.weight * m.albedo + s.weight * s.albedo) / total;
                                    m.weight = total;
                                    merged = true;
                                }
                        if (!merged) {
                            samples.push_back(s);
                            ++pixelSamples;
                        }
                        const vec3 emitted = emissionAt(sv, h, -ray.direction);
                        if (maxComponent(emitted) > 0.0f) seesEmitter[size_t(y) * size_t(W) + size_t(x)] = 1;
                        emission += emitted * weight;
                        albedo += s.albedo * weight;
                        ++hits;
                    }
                for (size_t k = samples.size() - pixelSamples; k < samples.size(); ++k)
                    samples[k].normal = glm::normalize(samples[k].normal);
                counts.push_back(pixelSamples);
                out.emission.setRgb(x, y, emission);
                out.albedo.setRgb(x, y, albedo);
                out.mask.at(x, y) = static_cast<float>(hits) * weight;
            }
        }
    });
    if (emissionSubsamplesPerAxis > n) {
        // Emitters seen directly need only primary rays: sample their edges finer than the
        // shading grid (a 2 × 2 grid turns a pixel a quarter covered by a bright emitter into
        // 0 or a half). Only where the shading grid saw an emitter in the pixel or a
        // neighbour: an edge pixel whose own rays all missed the emitter has a neighbour
        // whose rays did (an emitter narrower than the rays' spacing everywhere can still be
        // missed), and elsewhere the finer grid found nothing to add.
        const int ne = emissionSubsamplesPerAxis;
        const auto nearEmitter = [&](int x, int y) {
            for (int v = std::max(y - 1, 0); v <= std::min(y + 1, H - 1); ++v)
                for (int u = std::max(x - 1, 0); u <= std::min(x + 1, W - 1); ++u)
                    if (seesEmitter[size_t(v) * size_t(W) + size_t(u)]) return true;
            return false;
        };
        tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& range) {
            for (int y = range.begin(); y < range.end(); ++y)
                for (int x = 0; x < W; ++x) {
                    if (!nearEmitter(x, y)) continue;
                    vec3 emission(0.0f);
                    for (int j = 0; j < ne; ++j)
                        for (int i = 0; i < ne; ++i) {
                            const Ray ray = pinholeRay(camera, vec2(x + (i + 0.5f) / ne, y + (j + 0.5f) / ne));
                            Hit hit;
                            if (intersectClosest(bv, ray, hit))
                                emission += emissionAt(sv, surfaceAt(sv, hit.triangle, hit.b1, hit.b2), -ray.direction);
                        }
                    out.emission.setRgb(x, y, emission / static_cast<float>(ne * ne));
                }
        });
    }
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
