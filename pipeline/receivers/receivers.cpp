#include "receivers/receivers.h"

#include "core/error.h"
#include "scene/surface.h"
#include "trace/bvh.h"
#include "trace/bvh_traverse.h"
#include "trace/trace_scene.h"
#include "unwrap/lightmap_uvs.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
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
    if (!(texelSize >= 0.0) || !std::isfinite(texelSize))
        throw SettingsError("lightmap-texel: " + std::to_string(texelSize) +
                            " must be a length in metres per texel above 0 (0: none)");
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
        if (group.meshes.empty() && group.meshIndices.empty()) throw SettingsError(atlasLabel(group) + ": names no meshes");
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
    uint32_t localTriangle;  // the global one: its mesh's offset plus this
    uint32_t count;
    double sumB1, sumB2;
};

// Two samples of a texel are one smooth surface when their normals lie within this cosine
// (5°) and each lies in the other's plane within this slope: a tessellated curve's triangles,
// not a crease.
constexpr float kSmoothSurfaceCos = 0.9962f;
constexpr float kSmoothSurfaceSlope = 0.05f;

std::string quoted(const Scene& scene, uint32_t mesh) { return "'" + scene.meshes[mesh].name + "'"; }

// Appends one texel's samples to `out`, those that continue one smooth surface (one mesh,
// normals within kSmoothSurfaceCos of each other, each in the other's plane) as one: their
// summed weight, weighted mean normal and albedo. A finely tessellated surface puts many
// triangles in a texel, and one sample a triangle made the receivers' work and memory grow
// with the triangles, not the texels; a crease, or a texel across two surfaces, keeps a sample
// a side. The merged sample must lie on the surface: the mean of points on a curved surface
// lies under it where it bulges, by more than a ray's offset, and rays from there meet the
// surface's back (self-shadowed, or taken as buried). So where the members lie in one plane
// it takes their mean position; where they bend, the position and triangle of the member
// nearest that mean.
// The groups' working arrays, kept by the caller across a chunk's texels: no allocation a texel.
struct SmoothGroups {
    std::vector<uint32_t> groupOf;               // per sample
    std::vector<uint32_t> groupMesh, groupLead;  // per group: its mesh, its first member
    std::vector<vec3> mean;
    std::vector<float> nearest;
    std::vector<uint8_t> flat;
};

void appendSmoothSamples(std::vector<SurfaceSample>& out, const std::vector<SurfaceSample>& samples,
                         const std::vector<uint32_t>& meshes, SmoothGroups& scratch) {
    const size_t first = out.size();
    std::vector<uint32_t>& groupOf = scratch.groupOf;
    std::vector<uint32_t>& groupMesh = scratch.groupMesh;
    std::vector<uint32_t>& groupLead = scratch.groupLead;
    groupOf.resize(samples.size());
    groupMesh.clear();
    groupLead.clear();
    for (size_t k = 0; k < samples.size(); ++k) {
        const SurfaceSample& s = samples[k];
        size_t into = groupMesh.size();
        for (size_t g = 0; g < groupMesh.size() && into == groupMesh.size(); ++g) {
            const SurfaceSample& m = out[first + g];  // sums of its members until the texel is done
            const vec3 n = glm::normalize(m.normal);
            const vec3 d = s.position - m.position / m.weight;
            const float apart = glm::length(d);
            if (groupMesh[g] == meshes[k] && glm::dot(n, s.normal) >= kSmoothSurfaceCos &&
                glm::abs(glm::dot(d, n)) <= kSmoothSurfaceSlope * apart &&
                glm::abs(glm::dot(d, s.normal)) <= kSmoothSurfaceSlope * apart)
                into = g;
        }
        groupOf[k] = uint32_t(into);
        if (into == groupMesh.size()) {
            SurfaceSample m = s;
            m.position = s.weight * s.position;
            m.normal = s.weight * s.normal;
            m.albedo = s.weight * s.albedo;
            out.push_back(m);
            groupMesh.push_back(meshes[k]);
            groupLead.push_back(uint32_t(k));
            continue;
        }
        SurfaceSample& m = out[first + into];
        m.position += s.weight * s.position;
        m.normal += s.weight * s.normal;
        m.albedo += s.weight * s.albedo;
        m.weight += s.weight;
    }
    const size_t groups = groupMesh.size();
    std::vector<vec3>& mean = scratch.mean;
    std::vector<float>& nearest = scratch.nearest;
    std::vector<uint8_t>& flat = scratch.flat;
    mean.resize(groups);
    nearest.assign(groups, std::numeric_limits<float>::infinity());
    flat.assign(groups, 1);
    for (size_t g = 0; g < groups; ++g) mean[g] = out[first + g].position / out[first + g].weight;
    for (size_t k = 0; k < samples.size(); ++k) {
        const size_t g = groupOf[k];
        const SurfaceSample& s = samples[k];
        const SurfaceSample& lead = samples[groupLead[g]];
        // One plane: the same normal, and the member in its plane to float rounding.
        if (s.normal != lead.normal || glm::abs(glm::dot(s.position - lead.position, lead.normal)) >
                                           1e-5f * (1.0f + glm::length(s.position - lead.position)))
            flat[g] = 0;
        const float dist = glm::length(s.position - mean[g]);
        if (dist < nearest[g]) {
            nearest[g] = dist;
            out[first + g].triangle = s.triangle;
            out[first + g].position = s.position;  // taken as the position unless the group is flat
        }
    }
    for (size_t g = 0; g < groups; ++g) {
        SurfaceSample& m = out[first + g];
        if (flat[g]) m.position = mean[g];
        m.normal = glm::normalize(m.normal);
        m.albedo /= m.weight;
    }
}

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
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) {
                    const uint32_t texel = static_cast<uint32_t>(static_cast<size_t>(y) * W + x);
                    Fragment f{texel, m, static_cast<uint32_t>(t), 0, 0.0, 0.0};
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
                                fragments.push_back({texel, m, static_cast<uint32_t>(t), 1, w[1], w[2]});
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
    std::vector<uint32_t> fragmentBegin(texels + 1, 0), probeTotal(texels, 0);
    for (const Fragment& f : fragments) {
        ++fragmentBegin[f.texel + 1];
        probeTotal[f.texel] += f.count;
    }
    for (size_t i = 0; i < texels; ++i) fragmentBegin[i + 1] += fragmentBegin[i];
    std::vector<uint32_t> order(fragments.size());
    {
        std::vector<uint32_t> cursor(fragmentBegin.begin(), fragmentBegin.end() - 1);
        for (size_t k = 0; k < fragments.size(); ++k) order[cursor[fragments[k].texel]++] = uint32_t(k);
    }
    // Each texel's samples, built in fixed chunks of texels and joined in order: the same
    // samples at any thread count, and no array of a sample per fragment.
    constexpr size_t kChunkTexels = 4096;
    const size_t chunks = (texels + kChunkTexels - 1) / kChunkTexels;
    std::vector<std::vector<SurfaceSample>> chunkSamples(chunks);
    std::vector<uint32_t> perTexel(texels, 0);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        std::vector<SurfaceSample> texelSamples;
        std::vector<uint32_t> texelMeshes;
        SmoothGroups groups;
        std::vector<SurfaceSample>& out = chunkSamples[c];
        for (size_t texel = c * kChunkTexels; texel < std::min(texels, (c + 1) * kChunkTexels); ++texel) {
            texelSamples.clear();
            texelMeshes.clear();
            for (uint32_t k = fragmentBegin[texel]; k < fragmentBegin[texel + 1]; ++k) {
                const Fragment& f = fragments[order[k]];
                const Mesh& mesh = scene.meshes[f.mesh];
                const vec2 b(static_cast<float>(f.sumB1 / f.count), static_cast<float>(f.sumB2 / f.count));
                const SurfacePoint point = interpolateSurface(mesh, f.localTriangle, b);
                SurfaceSample s;
                s.position = point.position;
                s.normal = point.normal;
                s.albedo = glm::clamp(vec3(baseColorAt(scene, mesh, f.localTriangle, b)), vec3(0.0f), vec3(1.0f));
                s.triangle = triangleOffsets[f.mesh] + f.localTriangle;
                s.weight = static_cast<float>(static_cast<double>(f.count) / probeTotal[f.texel]);
                texelSamples.push_back(s);
                texelMeshes.push_back(f.mesh);
            }
            const size_t before = out.size();
            if (settings.samplePerTriangle) appendSmoothSamples(out, texelSamples, texelMeshes, groups);
            else out.insert(out.end(), texelSamples.begin(), texelSamples.end());
            perTexel[texel] = uint32_t(out.size() - before);
        }
    });
    std::vector<Fragment>().swap(fragments);
    std::vector<uint32_t>().swap(order);
    set.begin.assign(texels + 1, 0);
    for (size_t i = 0; i < texels; ++i) set.begin[i + 1] = set.begin[i] + perTexel[i];
    set.samples.reserve(set.begin[texels]);
    for (std::vector<SurfaceSample>& chunk : chunkSamples) {
        set.samples.insert(set.samples.end(), chunk.begin(), chunk.end());
        std::vector<SurfaceSample>().swap(chunk);
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
    for (size_t g = 0; g < groups.size(); ++g) {
        for (const uint32_t m : groups[g].meshIndices)
            if (m < groupOf.size()) groupOf[m] = static_cast<int>(g);
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

int atlasSideForTexel(const Scene& scene, const std::vector<uint32_t>& meshes, double texel, bool powerOfTwo, int maxSide) {
    double surface = 0.0, uv = 0.0;
    for (const uint32_t m : meshes) {
        const Mesh& mesh = scene.meshes[m];
        if (mesh.uv1.empty()) continue;
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t* i = &mesh.indices[3 * t];
            surface += 0.5 * double(glm::length(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]],
                                                          mesh.positions[i[2]] - mesh.positions[i[0]])));
            const vec2 a = mesh.uv1[i[0]], b = mesh.uv1[i[1]], c = mesh.uv1[i[2]];
            uv += 0.5 * std::abs(double(b.x - a.x) * (c.y - a.y) - double(b.y - a.y) * (c.x - a.x));
        }
    }
    if (!(uv > 0.0) || !(texel > 0.0)) return 0;
    const double side = std::sqrt(surface / uv) / texel;
    int rounded = 16;
    if (powerOfTwo)
        while (rounded < side && rounded < maxSide) rounded *= 2;
    else
        rounded = std::max(16, 4 * static_cast<int>(std::ceil(side / 4.0 - 1e-9)));
    return std::min(rounded, maxSide);
}

void sizeAuthoredAtlases(const Scene& scene, LightmapSettings& settings, double autoTexel, Diagnostics& diagnostics) {
    const bool byTexel = settings.texelSize > 0.0;
    if (!byTexel && !settings.autoResolution) return;
    const double texel = byTexel ? settings.texelSize : autoTexel;
    const int maxSide = byTexel ? kMaxAtlasSide : kMaxAutoAtlasSide;
    const AtlasMembers members = assignAtlasMembers(scene, settings, nullptr);
    const auto side = [&](const std::vector<uint32_t>& meshes, const std::string& atlas) {
        const int n = atlasSideForTexel(scene, meshes, texel, !byTexel, maxSide);
        if (byTexel && n == maxSide && atlasSideForTexel(scene, meshes, texel, false, 2 * maxSide) > maxSide) {
            char metres[32];
            std::snprintf(metres, sizeof metres, "%.3g", texel);
            diagnostics.warn(scene.sourcePath + ": " + atlas + " needs more than " + std::to_string(maxSide) + " x " +
                             std::to_string(maxSide) + " texels at lightmap-texel " + metres + " m: it is baked at " +
                             std::to_string(maxSide) + " x " + std::to_string(maxSide) + ", coarser than asked");
        }
        return n;
    };
    if (!members.shared.empty())
        if (const int n = side(members.shared, "the lightmap (its meshes' own TEXCOORD_1)"); n > 0) settings.width = settings.height = n;
    for (size_t g = 0; g < settings.atlases.size(); ++g) {
        AtlasGroup& group = settings.atlases[g];
        if (group.width != 0 || members.grouped[g].empty()) continue;  // a resolution of its own stands
        if (const int n = side(members.grouped[g], atlasReference(group)); n > 0) group.width = group.height = n;
    }
}

MeshesWithoutUv1 sharedAtlasMeshesWithoutUv1(const Scene& scene, const LightmapSettings& settings) {
    MeshesWithoutUv1 found;
    if (settings.atlasPerMesh) return found;
    const std::vector<int> groupOf = assignAtlasGroups(scene, settings.atlases);
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        if (groupOf[m] >= 0 || mesh.triangleCount() == 0 || scene.materialOf(mesh).emissive()) continue;
        if (mesh.uv1.empty())
            found.meshes.push_back(static_cast<uint32_t>(m));
        else
            found.othersHaveUv1 = true;
    }
    return found;
}

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

namespace {

// An emissive triangle as the film sees it: clipped to the half-space just in front of the
// camera, then projected to film coordinates (pixels, y down). Up to 4 vertices; 0 when it
// lies behind the camera. Double precision: a vertex near the camera's plane projects far out.
int filmPolygon(const CameraModel& c, const vec3* vertices, Point2 (&out)[4]) {
    const glm::dvec3 origin(c.position), forward(c.forward), right(c.right), up(c.up);
    glm::dvec3 v[3];
    double depth[3], farthest = 0.0;
    for (int k = 0; k < 3; ++k) {
        v[k] = glm::dvec3(vertices[k]) - origin;
        depth[k] = glm::dot(v[k], forward);
        farthest = std::max(farthest, depth[k]);
    }
    if (!(farthest > 0.0)) return 0;
    const double nearest = 1e-6 * farthest;
    glm::dvec3 clipped[4];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
        const int next = (k + 1) % 3;
        if (depth[k] >= nearest) clipped[n++] = v[k];
        if ((depth[k] >= nearest) != (depth[next] >= nearest)) {
            const double t = (nearest - depth[k]) / (depth[next] - depth[k]);
            clipped[n++] = v[k] + t * (v[next] - v[k]);
        }
    }
    const double sx = double(c.tanHalfFovY) * double(c.aspect), sy = double(c.tanHalfFovY);
    for (int k = 0; k < n; ++k) {
        const double f = glm::dot(clipped[k], forward);
        out[k] = {(glm::dot(clipped[k], right) / f / sx + 1.0) * 0.5 * c.width,
                  (1.0 - glm::dot(clipped[k], up) / f / sy) * 0.5 * c.height};
    }
    return n;
}

// Area of a convex polygon (either winding) inside the pixel square [x, x + 1] × [y, y + 1]:
// Sutherland–Hodgman against the square's four sides, then the shoelace formula. `inner`,
// when given, receives a point inside that part (its vertices' mean).
double areaInPixel(const Point2* polygon, int count, int x, int y, Point2* inner = nullptr) {
    Point2 a[12], b[12];
    int n = count;
    std::copy(polygon, polygon + count, a);
    const double bounds[4] = {double(x), double(x + 1), double(y), double(y + 1)};
    for (int side = 0; side < 4 && n > 0; ++side) {
        const auto inside = [&](const Point2& p) {
            const double value = side < 2 ? p.x : p.y;
            return side % 2 == 0 ? value >= bounds[side] : value <= bounds[side];
        };
        int m = 0;
        for (int k = 0; k < n; ++k) {
            const Point2& p = a[k];
            const Point2& q = a[(k + 1) % n];
            if (inside(p)) b[m++] = p;
            if (inside(p) != inside(q)) {
                const double pv = side < 2 ? p.x : p.y, qv = side < 2 ? q.x : q.y;
                const double t = (bounds[side] - pv) / (qv - pv);
                b[m++] = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
            }
        }
        n = m;
        std::copy(b, b + m, a);
    }
    double twice = 0.0;
    Point2 mean{0.0, 0.0};
    for (int k = 0; k < n; ++k) {
        twice += a[k].x * a[(k + 1) % n].y - a[(k + 1) % n].x * a[k].y;
        mean.x += a[k].x / n;
        mean.y += a[k].y / n;
    }
    if (inner) *inner = mean;
    return 0.5 * std::abs(twice);
}

bool insideConvex(const Point2* polygon, int count, const Point2& p) {
    bool positive = false, negative = false;
    for (int k = 0; k < count; ++k) {
        const double e = edgeFunction(polygon[k], polygon[(k + 1) % count], p);
        positive = positive || e > 0.0;
        negative = negative || e < 0.0;
    }
    return !(positive && negative);
}

bool uniformEmission(const TraceSceneView& s, uint32_t triangle) {
    return s.materials[s.materialIds[triangle]].emissiveTexture.texture < 0;
}

constexpr uint32_t kNoTriangle = ~0u;

}  // namespace

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
    // Per pixel: the first emissive triangle its shading rays hit (kNoTriangle: none).
    std::vector<uint32_t> firstEmitter(static_cast<size_t>(W) * static_cast<size_t>(H), kNoTriangle);
    // The sky seen directly, apart from the emitters' light, and how many rays left the scene.
    Image skySeen(W, H, 3);
    std::vector<int> skyRays(static_cast<size_t>(W) * static_cast<size_t>(H), 0);
    const float weight = 1.0f / static_cast<float>(n * n);
    tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& range) {
        for (int y = range.begin(); y < range.end(); ++y) {
            auto& samples = rows[static_cast<size_t>(y)];
            auto& counts = rowCounts[static_cast<size_t>(y)];
            for (int x = 0; x < W; ++x) {
                vec3 emission(0.0f), albedo(0.0f), sky(0.0f);
                uint32_t hits = 0, pixelSamples = 0;
                for (int j = 0; j < n; ++j)
                    for (int i = 0; i < n; ++i) {
                        const vec2 film(x + (i + 0.5f) / n, y + (j + 0.5f) / n);
                        const Ray ray = pinholeRay(camera, film);
                        Hit hit;
                        if (!intersectClosest(bv, ray, hit)) {  // the sky, seen directly
                            sky += skyRadianceAlong(sv.sky, ray.direction) * weight;
                            ++skyRays[size_t(y) * size_t(W) + size_t(x)];
                            continue;
                        }
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
                        uint32_t& first = firstEmitter[size_t(y) * size_t(W) + size_t(x)];
                        if (maxComponent(emitted) > 0.0f && first == kNoTriangle) first = hit.triangle;
                        emission += emitted * weight;
                        albedo += s.albedo * weight;
                        ++hits;
                    }
                for (size_t k = samples.size() - pixelSamples; k < samples.size(); ++k)
                    samples[k].normal = glm::normalize(samples[k].normal);
                counts.push_back(pixelSamples);
                out.emission.setRgb(x, y, emission);
                skySeen.setRgb(x, y, sky);
                out.albedo.setRgb(x, y, albedo);
                out.mask.at(x, y) = static_cast<float>(hits) * weight;
            }
        }
    });
    if (emissionSubsamplesPerAxis > n) {
        // Emitters seen directly need only primary rays, and where one covers part of a pixel
        // its share of the pixel is the pixel's value: a 2 × 2 shading grid turns a pixel a
        // quarter covered by a bright emitter into 0 or a half, and even an 8 × 8 grid moves
        // in steps of 1/8 of the emitter's radiance across a straight edge, which on an
        // emitter far brighter than the room is most of an image's squared error. So a
        // uniform emitter triangle adds its exact area inside the pixel (clipped in film
        // space) times its radiance, times the fraction of the finer grid's rays inside that
        // area that reach it (1 where nothing stands in front). Textured emitters keep the
        // grid's mean. Only pixels where the shading grid saw an emitter in the pixel or a
        // neighbour: an edge pixel whose own rays all missed has a neighbour whose rays did,
        // and that neighbour's triangle is a candidate here.
        const int ne = emissionSubsamplesPerAxis;
        tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& range) {
            struct Shot {
                Point2 film;
                uint32_t triangle;
                vec3 emitted;
            };
            std::vector<Shot> shots(static_cast<size_t>(ne * ne));
            std::vector<uint32_t> candidates;
            for (int y = range.begin(); y < range.end(); ++y)
                for (int x = 0; x < W; ++x) {
                    candidates.clear();
                    for (int v = std::max(y - 1, 0); v <= std::min(y + 1, H - 1); ++v)
                        for (int u = std::max(x - 1, 0); u <= std::min(x + 1, W - 1); ++u) {
                            const uint32_t t = firstEmitter[size_t(v) * size_t(W) + size_t(u)];
                            if (t != kNoTriangle && std::find(candidates.begin(), candidates.end(), t) == candidates.end())
                                candidates.push_back(t);
                        }
                    if (candidates.empty()) continue;
                    vec3 sampled(0.0f);  // textured emitters: the grid's mean
                    for (int j = 0; j < ne; ++j)
                        for (int i = 0; i < ne; ++i) {
                            Shot& shot = shots[size_t(j * ne + i)];
                            shot.film = {x + (i + 0.5) / ne, y + (j + 0.5) / ne};
                            shot.triangle = kNoTriangle;
                            shot.emitted = vec3(0.0f);
                            const Ray ray = pinholeRay(camera, vec2(float(shot.film.x), float(shot.film.y)));
                            Hit hit;
                            if (!intersectClosest(bv, ray, hit)) continue;
                            shot.triangle = hit.triangle;
                            shot.emitted = emissionAt(sv, surfaceAt(sv, hit.triangle, hit.b1, hit.b2), -ray.direction);
                            if (!(maxComponent(shot.emitted) > 0.0f)) continue;
                            if (!uniformEmission(sv, hit.triangle))
                                sampled += shot.emitted / static_cast<float>(ne * ne);
                            else if (std::find(candidates.begin(), candidates.end(), hit.triangle) == candidates.end())
                                candidates.push_back(hit.triangle);
                        }
                    vec3 exact(0.0f);
                    for (uint32_t t : candidates) {
                        if (!uniformEmission(sv, t)) continue;
                        Point2 polygon[4];
                        const int count = filmPolygon(camera, sv.vertices + 3 * size_t(t), polygon);
                        Point2 centre{0.0, 0.0};
                        const double area = count >= 3 ? areaInPixel(polygon, count, x, y, &centre) : 0.0;
                        if (!(area > 0.0)) continue;
                        int inside = 0, reached = 0;
                        vec3 radiance(0.0f);
                        for (const Shot& shot : shots) {
                            if (!insideConvex(polygon, count, shot.film)) continue;
                            ++inside;
                            if (shot.triangle != t) continue;
                            ++reached;
                            radiance = shot.emitted;
                        }
                        if (inside == 0) {
                            // A sliver between the grid's rays: one ray through its middle.
                            const Ray ray = pinholeRay(camera, vec2(float(centre.x), float(centre.y)));
                            Hit hit;
                            if (intersectClosest(bv, ray, hit) && hit.triangle == t) {
                                inside = reached = 1;
                                radiance = emissionAt(sv, surfaceAt(sv, hit.triangle, hit.b1, hit.b2), -ray.direction);
                            }
                        }
                        if (reached > 0) exact += radiance * static_cast<float>(area * reached / inside);
                    }
                    out.emission.setRgb(x, y, exact + sampled);
                }
        });
    }
    if (sv.sky.present() && emissionSubsamplesPerAxis > n) {
        // The sky's edges as the emitters' (above): where the shading grid's rays both left
        // the scene and met it, in a pixel or its neighbours, the finer grid measures the
        // share of the pixel that sees the sky and what it sees there, and the pixel's
        // surface samples carry the rest. A window's edge pixel half sky, half wall, read
        // from 2 × 2 rays, was 0, ½ or 1 of the sky: most of a window-lit room's image error.
        // A pixel whose shading rays all left has no surface sample to carry a share, and
        // keeps the shading grid's sky.
        const int ne = emissionSubsamplesPerAxis, all = n * n;
        tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& range) {
            for (int y = range.begin(); y < range.end(); ++y) {
                size_t first = 0;  // the pixel's samples in rows[y]
                for (int x = 0; x < W; ++x) {
                    const uint32_t count = rowCounts[size_t(y)][size_t(x)];
                    const size_t begin = first;
                    first += count;
                    const int coarse = skyRays[size_t(y) * size_t(W) + size_t(x)];
                    if (coarse == all || count == 0) continue;
                    int least = all, most = 0;
                    for (int v = std::max(y - 1, 0); v <= std::min(y + 1, H - 1); ++v)
                        for (int u = std::max(x - 1, 0); u <= std::min(x + 1, W - 1); ++u) {
                            least = std::min(least, skyRays[size_t(v) * size_t(W) + size_t(u)]);
                            most = std::max(most, skyRays[size_t(v) * size_t(W) + size_t(u)]);
                        }
                    if (most == 0 || least == all) continue;  // no sky near, or no surface near
                    vec3 sky(0.0f);
                    int left = 0;
                    for (int j = 0; j < ne; ++j)
                        for (int i = 0; i < ne; ++i) {
                            const Ray ray = pinholeRay(camera, vec2(x + (i + 0.5f) / ne, y + (j + 0.5f) / ne));
                            Hit hit;
                            if (intersectClosest(bv, ray, hit)) continue;
                            sky += skyRadianceAlong(sv.sky, ray.direction);
                            ++left;
                        }
                    const float rays = static_cast<float>(ne * ne);
                    const float surface = 1.0f - static_cast<float>(left) / rays;
                    const float scale = surface / (1.0f - static_cast<float>(coarse) / static_cast<float>(all));
                    skySeen.setRgb(x, y, sky / rays);
                    for (size_t k = begin; k < begin + count; ++k) rows[size_t(y)][k].weight *= scale;
                    out.albedo.setRgb(x, y, out.albedo.rgb(x, y) * scale);
                    out.mask.at(x, y) = surface;
                }
            }
        });
    }
    for (size_t k = 0; k < out.emission.pixels.size(); ++k) out.emission.pixels[k] += skySeen.pixels[k];
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
