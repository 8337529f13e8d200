#include "voxel/voxelize.h"

#include "core/error.h"
#include "scene/surface.h"
#include "voxel/triangle_box.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace vl {
namespace {

constexpr int kKeyBits = 21;  // per axis in a packed voxel key
constexpr int64_t kMaxAxisVoxels = int64_t(1) << kKeyBits;
constexpr double kMaxPieces = 2147483648.0;  // 2^31

std::string sceneLabel(const Scene& scene) {
    return scene.sourcePath.empty() ? std::string("scene") : scene.sourcePath;
}

dvec3 toVoxelUnits(const vec3& p, double h) { return dvec3(p) / h; }

// One triangle of the scene, by mesh and index within it.
struct TriangleRef {
    uint32_t mesh;
    uint32_t triangle;
};

// What the reduction needs of a triangle besides its fragments.
struct TriangleInfo {
    vec3 normal;       // unit geometric normal (winding)
    bool doubleSided;
};

// One (voxel, triangle) piece: what the reduction sums, in voxel units.
struct Fragment {
    uint64_t key;       // packed voxel coordinate, ordered like (x, y, z)
    uint32_t triangle;  // global triangle id: the tie-break that fixes the summation order
    float coverage;     // visible piece area / h²
    vec3 centroid;      // the piece's centroid relative to the voxel's centre (voxel units)
    vec3 albedo;        // coverage-weighted mean over the piece
    vec3 emission;
};

bool fragmentOrder(const Fragment& a, const Fragment& b) {
    return a.key != b.key ? a.key < b.key : a.triangle < b.triangle;
}

// Packs voxel coordinates relative to the scene's lowest voxel into one sortable key.
struct KeyPacker {
    ivec3 origin;
    uint64_t pack(const ivec3& c) const {
        const ivec3 d = c - origin;
        return (uint64_t(uint32_t(d.x)) << (2 * kKeyBits)) | (uint64_t(uint32_t(d.y)) << kKeyBits) |
               uint64_t(uint32_t(d.z));
    }
    ivec3 unpack(uint64_t key) const {
        const uint64_t mask = (uint64_t(1) << kKeyBits) - 1;
        return origin + ivec3(int((key >> (2 * kKeyBits)) & mask), int((key >> kKeyBits) & mask), int(key & mask));
    }
};

// Per-mesh material facts that decide how much sampling a piece needs.
struct MeshShading {
    const Mesh* mesh = nullptr;
    const Material* material = nullptr;
    bool constantBase = true;      // no base colour texture and no COLOR_0
    bool constantEmission = true;  // no emissive texture
    vec3 baseColor{1.0f};
    float baseAlpha = 1.0f;
    vec3 emission{0.0f};
    float transmissionFactor = 1.0f;  // 1 − transmission

    float visibility(float alpha) const {
        switch (material->alphaMode) {
            case AlphaMode::Opaque: return 1.0f;
            case AlphaMode::Mask: return alpha >= material->alphaCutoff ? 1.0f : 0.0f;
            case AlphaMode::Blend: return glm::clamp(alpha, 0.0f, 1.0f);
        }
        return 1.0f;
    }
};

struct PieceShading {
    double coverage = 0.0;  // visible area, voxel units
    dvec3 albedo{0.0};      // coverage-weighted sums
    dvec3 emission{0.0};
};

// Area centroid of a clipped piece (a convex polygon): its fan triangles' centroids weighted
// by their areas; the vertices' mean for a piece without area.
dvec3 pieceCentroid(const ClipPolygon& piece) {
    dvec3 sum(0.0), mean(0.0);
    double area = 0.0;
    for (int k = 0; k < piece.count; ++k) mean += piece.position[k] / double(piece.count);
    for (int k = 1; k + 1 < piece.count; ++k) {
        const double a = 0.5 * glm::length(glm::cross(piece.position[k] - piece.position[0],
                                                     piece.position[k + 1] - piece.position[0]));
        sum += a * (piece.position[0] + piece.position[k] + piece.position[k + 1]) / 3.0;
        area += a;
    }
    return area > 0.0 ? sum / area : mean;
}

// Samples the material over a clipped piece (voxel units, so a voxel face has area 1):
// texelSamples² points per unit area spread over the fan triangles of the piece, at least
// one per fan triangle, each at the centroid of one of the k² congruent sub-triangles of a
// k-fold subdivision (an equal-area quadrature, exact for linear colours). A sliver that
// clips a voxel's corner needs no more samples than its size.
PieceShading shadePiece(const Scene& scene, const MeshShading& shading, uint32_t triangle,
                        const ClipPolygon& piece, double pieceArea, const dvec3& n, int samplesPerAxis,
                        bool withEmission) {
    PieceShading out;
    const bool sampleBase = !shading.constantBase;
    const bool sampleEmission = withEmission && !shading.constantEmission;
    if (!sampleBase && !sampleEmission) {
        const double visible = pieceArea * shading.visibility(shading.baseAlpha) * shading.transmissionFactor;
        out.coverage = visible;
        out.albedo = visible * dvec3(shading.baseColor);
        out.emission = visible * dvec3(shading.emission);
        return out;
    }
    for (int t = 1; t + 1 < piece.count; ++t) {
        const dvec3& p0 = piece.position[0];
        const double fanArea =
            0.5 * glm::dot(n, glm::cross(piece.position[t] - p0, piece.position[t + 1] - p0));
        if (!(fanArea > 0.0)) continue;
        const int k = std::max(1, static_cast<int>(std::lround(samplesPerAxis * std::sqrt(fanArea))));
        const double weight = fanArea / (double(k) * k);
        const dvec2 b0 = piece.barycentric[0];
        const dvec2 bu = piece.barycentric[t] - b0;
        const dvec2 bv = piece.barycentric[t + 1] - b0;
        auto sampleAt = [&](double u, double v) {
            const vec2 bary(b0 + u * bu + v * bv);
            vec3 albedo = shading.baseColor;
            float alpha = shading.baseAlpha;
            if (sampleBase) {
                const vec4 base = baseColorAt(scene, *shading.mesh, triangle, bary);
                albedo = vec3(base);
                alpha = base.w;
            }
            const double visible = weight * shading.visibility(alpha) * shading.transmissionFactor;
            if (visible <= 0.0) return;
            out.coverage += visible;
            out.albedo += visible * dvec3(albedo);
            if (withEmission) {
                const vec3 e = sampleEmission ? emissionAt(scene, *shading.mesh, triangle, bary) : shading.emission;
                out.emission += visible * dvec3(e);
            }
        };
        const double inv = 1.0 / k;
        for (int i = 0; i < k; ++i)
            for (int j = 0; i + j < k; ++j) {
                sampleAt((i + 1.0 / 3.0) * inv, (j + 1.0 / 3.0) * inv);  // upright sub-triangle
                if (i + j + 1 < k) sampleAt((i + 2.0 / 3.0) * inv, (j + 2.0 / 3.0) * inv);  // inverted one
            }
    }
    return out;
}

struct Bounds {
    dvec3 lower, upper;  // voxel units
};

Bounds voxelBounds(const Scene& scene, double h) {
    Bounds b{dvec3(std::numeric_limits<double>::infinity()), dvec3(-std::numeric_limits<double>::infinity())};
    for (const Mesh& mesh : scene.meshes)
        for (uint32_t index : mesh.indices) {
            const dvec3 q = toVoxelUnits(mesh.positions[index], h);
            b.lower = glm::min(b.lower, q);
            b.upper = glm::max(b.upper, q);
        }
    return b;
}

// Closed meshes for fillInterior: after welding vertices by exact position, every directed
// edge has its reverse exactly once (a watertight, consistently oriented surface).
bool isClosedMesh(const Mesh& mesh) {
    if (mesh.triangleCount() == 0) return false;
    auto positionKey = [](const vec3& p) {
        uint32_t bits[3];
        std::memcpy(bits, &p, sizeof(bits));
        return (uint64_t(bits[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(bits[1]) * 0xC2B2AE3D27D4EB4Full) ^
               (uint64_t(bits[2]) * 0x165667B19E3779F9ull);
    };
    std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;  // hash → welded ids
    std::vector<vec3> welded;
    std::vector<uint32_t> weldedOf(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const vec3& p = mesh.positions[v];
        auto& bucket = buckets[positionKey(p)];
        uint32_t id = UINT32_MAX;
        for (uint32_t candidate : bucket)
            if (welded[candidate] == p) id = candidate;
        if (id == UINT32_MAX) {
            id = static_cast<uint32_t>(welded.size());
            welded.push_back(p);
            bucket.push_back(id);
        }
        weldedOf[v] = id;
    }
    std::unordered_map<uint64_t, int> directed;  // (a, b) → count of a→b minus count of b→a
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t v[3] = {weldedOf[mesh.indices[3 * t]], weldedOf[mesh.indices[3 * t + 1]],
                               weldedOf[mesh.indices[3 * t + 2]]};
        for (int e = 0; e < 3; ++e) {
            const uint32_t a = v[e], b = v[(e + 1) % 3];
            if (a == b) return false;
            const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
            directed[key] += a < b ? 1 : -1;
        }
    }
    for (const auto& [key, balance] : directed)
        if (balance != 0) return false;
    return true;
}

// fillInterior. A ray along +z through every voxel column centre (i, j) crosses the closed
// meshes; the winding number (+1 entering against an outward normal, −1 leaving) is
// positive inside, so a room modelled facing inward is not filled. Shared edges are
// counted once: each edge function is evaluated with its endpoints in a canonical order,
// and a point exactly on an edge belongs to the triangle on one fixed side of it.
struct InsideVoxel {
    uint64_t key;
    vec3 albedo;  // baseColorFactor of the surface the column entered through
};

std::vector<InsideVoxel> voxelsInsideClosedMeshes(const Scene& scene, const std::vector<TriangleRef>& triangles,
                                                  const std::vector<TriangleInfo>& info,
                                                  const std::vector<MeshShading>& shading, const KeyPacker& packer,
                                                  double h) {
    struct Crossing {
        uint64_t column;
        double z;
        uint32_t triangle;
        int delta;
    };
    std::vector<uint8_t> closed(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) closed[m] = isClosedMesh(scene.meshes[m]);

    // Edge function of the directed edge a→b at (x, y), from canonically ordered endpoints,
    // and whether the order was swapped.
    auto edge = [](const dvec3& a, const dvec3& b, double x, double y) {
        const bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
        const dvec3& s = swap ? b : a;
        const dvec3& e = swap ? a : b;
        const double w = (e.x - s.x) * (y - s.y) - (e.y - s.y) * (x - s.x);
        return std::make_pair(swap ? -w : w, swap);
    };
    tbb::enumerable_thread_specific<std::vector<Crossing>> perThread;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 256), [&](const tbb::blocked_range<size_t>& range) {
        auto& crossings = perThread.local();
        for (size_t id = range.begin(); id != range.end(); ++id) {
            const TriangleRef ref = triangles[id];
            if (!closed[ref.mesh] || info[id].normal.z == 0.0f) continue;
            const Mesh& mesh = scene.meshes[ref.mesh];
            const dvec3 q[3] = {toVoxelUnits(mesh.positions[mesh.indices[3 * ref.triangle]], h),
                                toVoxelUnits(mesh.positions[mesh.indices[3 * ref.triangle + 1]], h),
                                toVoxelUnits(mesh.positions[mesh.indices[3 * ref.triangle + 2]], h)};
            const double orientation =
                (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[1].y - q[0].y) * (q[2].x - q[0].x);
            if (orientation == 0.0) continue;
            const double sign = orientation > 0.0 ? 1.0 : -1.0;
            const dvec3 lo = glm::min(q[0], glm::min(q[1], q[2]));
            const dvec3 hi = glm::max(q[0], glm::max(q[1], q[2]));
            const int delta = info[id].normal.z < 0.0f ? 1 : -1;
            const dvec3 n(info[id].normal);
            for (int i = static_cast<int>(std::ceil(lo.x)); i <= static_cast<int>(std::floor(hi.x)); ++i)
                for (int j = static_cast<int>(std::ceil(lo.y)); j <= static_cast<int>(std::floor(hi.y)); ++j) {
                    bool inside = true;
                    for (int e = 0; e < 3 && inside; ++e) {
                        const auto [w, swapped] = edge(q[e], q[(e + 1) % 3], i, j);
                        const double ws = sign * w;
                        inside = ws > 0.0 || (ws == 0.0 && (swapped != (sign < 0.0)));
                    }
                    if (!inside) continue;
                    const double z = q[0].z - (n.x * (i - q[0].x) + n.y * (j - q[0].y)) / n.z;
                    crossings.push_back({packer.pack(ivec3(i, j, packer.origin.z)), z, static_cast<uint32_t>(id), delta});
                }
        }
    });
    std::vector<Crossing> crossings;
    for (auto& local : perThread) crossings.insert(crossings.end(), local.begin(), local.end());
    // (column, z, triangle) is unique: the order, and so the output, is thread-independent.
    tbb::parallel_sort(crossings.begin(), crossings.end(), [](const Crossing& a, const Crossing& b) {
        if (a.column != b.column) return a.column < b.column;
        if (a.z != b.z) return a.z < b.z;
        return a.triangle < b.triangle;
    });

    // Voxel centres strictly between a crossing that leaves the winding positive and the
    // next one; in key order, as columns and z both increase.
    std::vector<InsideVoxel> inside;
    for (size_t c = 0; c < crossings.size();) {
        size_t end = c;
        while (end < crossings.size() && crossings[end].column == crossings[c].column) ++end;
        const ivec3 column = packer.unpack(crossings[c].column);
        int winding = 0;
        for (size_t x = c; x + 1 < end; ++x) {
            winding += crossings[x].delta;
            if (winding <= 0) continue;
            const int k0 = static_cast<int>(std::floor(crossings[x].z)) + 1;
            const int k1 = static_cast<int>(std::ceil(crossings[x + 1].z)) - 1;
            const vec3 albedo = shading[triangles[crossings[x].triangle].mesh].baseColor;
            for (int k = k0; k <= k1; ++k) inside.push_back({packer.pack(ivec3(column.x, column.y, k)), albedo});
        }
        c = end;
    }
    return inside;
}

// Surface voxels whose centre is inside become solid (α = 1, their surface attributes
// kept); inside voxels the surface does not reach are added. Returns how many were added.
size_t mergeInside(VoxelScene& voxels, const std::vector<InsideVoxel>& inside, const KeyPacker& packer) {
    const bool withEmission = !voxels.emission.empty();
    VoxelScene merged;
    const size_t reserve = voxels.size() + inside.size();
    merged.coords.reserve(reserve);
    merged.albedo.reserve(reserve);
    merged.normal.reserve(reserve);
    merged.axisWeights.reserve(reserve);
    merged.opacity.reserve(reserve);
    merged.solid.reserve(reserve);
    merged.surfaceOffset.reserve(reserve);
    if (withEmission) merged.emission.reserve(reserve);
    auto copySurface = [&](size_t v, bool isInside) {
        merged.coords.push_back(voxels.coords[v]);
        merged.albedo.push_back(voxels.albedo[v]);
        merged.normal.push_back(voxels.normal[v]);
        merged.axisWeights.push_back(voxels.axisWeights[v]);
        if (withEmission) merged.emission.push_back(voxels.emission[v]);
        merged.opacity.push_back(isInside ? 1.0f : voxels.opacity[v]);
        merged.solid.push_back(isInside ? 1 : voxels.solid[v]);
        merged.surfaceOffset.push_back(voxels.surfaceOffset[v]);
    };
    size_t s = 0, added = 0;
    for (const InsideVoxel& iv : inside) {
        while (s < voxels.size() && packer.pack(voxels.coords[s]) < iv.key) copySurface(s++, false);
        if (s < voxels.size() && packer.pack(voxels.coords[s]) == iv.key) {
            copySurface(s++, true);
            continue;
        }
        merged.coords.push_back(packer.unpack(iv.key));
        merged.albedo.push_back(iv.albedo);
        merged.normal.push_back(vec3(0.0f));
        merged.axisWeights.push_back(AxisWeights{0, 0, 0, 0, 0, 0});
        if (withEmission) merged.emission.push_back(vec3(0.0f));
        merged.opacity.push_back(1.0f);
        merged.solid.push_back(1);
        merged.surfaceOffset.push_back(vec3(0.0f));
        ++added;
    }
    while (s < voxels.size()) copySurface(s++, false);
    voxels.coords = std::move(merged.coords);
    voxels.albedo = std::move(merged.albedo);
    voxels.normal = std::move(merged.normal);
    voxels.axisWeights = std::move(merged.axisWeights);
    voxels.emission = std::move(merged.emission);
    voxels.opacity = std::move(merged.opacity);
    voxels.solid = std::move(merged.solid);
    voxels.surfaceOffset = std::move(merged.surfaceOffset);
    return added;
}

}  // namespace

void anchorToVoxelGrid(Scene& scene, double voxelSize) {
    const Aabb box = scene.bounds();
    if (box.empty()) return;
    scene.moveOrigin(scene.origin + scene.frame * (glm::dvec3(box.centre()) + glm::dvec3(0.5 * voxelSize)));
}

double voxelSizeFor(const Scene& scene, const VoxelSettings& settings) {
    if (settings.texelSamples < 1 || settings.texelSamples > 64)
        throw SettingsError("voxelize: texelSamples must be in [1, 64], got " + std::to_string(settings.texelSamples));
    if (!std::isfinite(settings.voxelSize) || settings.voxelSize < 0.0) {
        std::ostringstream message;
        message << "voxelize: voxel size must be a positive number of metres, got " << settings.voxelSize;
        throw SettingsError(message.str());
    }
    if (settings.voxelSize == 0.0 && settings.resolution <= 0)
        throw SettingsError("voxelize: resolution must be at least 1 voxel along the longest axis, got " +
                            std::to_string(settings.resolution));

    size_t triangles = 0;
    for (const Mesh& mesh : scene.meshes) {
        for (size_t v = 0; v < mesh.positions.size(); ++v)
            if (!isFinite(mesh.positions[v])) {
                std::ostringstream message;
                message << sceneLabel(scene) << ": mesh '" << mesh.name << "' position " << v << " is not finite";
                throw InputError(message.str());
            }
        for (uint32_t index : mesh.indices)
            if (index >= mesh.positions.size())
                throw InputError(sceneLabel(scene) + ": mesh '" + mesh.name + "' index " + std::to_string(index) +
                                 " is out of range");
        triangles += mesh.triangleCount();
    }
    if (triangles == 0) throw InputError(sceneLabel(scene) + ": no triangles to voxelize");

    const Aabb box = scene.bounds();
    double h = settings.voxelSize;
    if (h == 0.0) {
        const vec3 extent = box.extent();
        const double longest = std::max<double>(extent.x, std::max<double>(extent.y, extent.z));
        if (!(longest > 0.0))
            throw InputError(sceneLabel(scene) + ": the scene's bounds are a single point; give a voxel size");
        // An odd count: with the box centred on a voxel corner (anchorToVoxelGrid) the box's
        // faces along its longest axis then fall on voxel centres, not on the faces between
        // two voxels, where rounding puts a wall in one voxel layer or both, and a scaled or
        // rotated copy of a scene bakes apart from the original (docs/decisions.md, "The
        // scene's own frame").
        const int voxels = settings.resolution % 2 == 1 ? settings.resolution : std::max(settings.resolution - 1, 1);
        h = longest / voxels;
    }
    if (!(h > 0.0) || !std::isfinite(h)) throw SettingsError("voxelize: voxel size underflows to zero");

    const Bounds bounds = voxelBounds(scene, h);
    for (int a = 0; a < 3; ++a) {
        const double span = bounds.upper[a] - bounds.lower[a] + 3.0;
        if (!(span < double(kMaxAxisVoxels))) {
            std::ostringstream message;
            message << "voxelize: voxel size " << h << " m gives " << span << " voxels along axis " << "xyz"[a]
                    << " (at most " << kMaxAxisVoxels << ")";
            throw SettingsError(message.str());
        }
    }
    // A generous bound on the pieces a triangle can cut: its area over the voxel face, its
    // perimeter in voxels (pieces along the edges) and one for the vertex.
    double pieces = 0.0;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const dvec3 q0 = toVoxelUnits(mesh.positions[mesh.indices[3 * t]], h);
            const dvec3 q1 = toVoxelUnits(mesh.positions[mesh.indices[3 * t + 1]], h);
            const dvec3 q2 = toVoxelUnits(mesh.positions[mesh.indices[3 * t + 2]], h);
            const double area = 0.5 * glm::length(glm::cross(q1 - q0, q2 - q0));
            const double perimeter = glm::length(q1 - q0) + glm::length(q2 - q1) + glm::length(q0 - q2);
            pieces += 1.8 * area + 2.0 * perimeter + 1.0;
        }
    if (pieces > kMaxPieces) {
        std::ostringstream message;
        message << "voxelize: voxel size " << h << " m would cut the scene's surface into about " << pieces
                << " voxel pieces (at most 2^31); use a larger voxel size or a lower resolution";
        throw SettingsError(message.str());
    }
    return h;
}

VoxelScene voxelize(const Scene& scene, const VoxelSettings& settings, Progress* progress, VoxelizeStats* stats) {
    const double h = voxelSizeFor(scene, settings);
    const bool withEmission = scene.hasEmitters();

    VoxelScene out;
    out.voxelSize = h;
    out.origin = scene.origin;
    out.frame = scene.frame;
    out.sourceScene = scene.sourcePath;
    {
        std::ostringstream text;
        text.precision(9);
        text << "voxelSize=" << h << " resolution=" << (settings.voxelSize > 0.0 ? 0 : settings.resolution)
             << " fillInterior=" << (settings.fillInterior ? "true" : "false")
             << " texelSamples=" << settings.texelSamples;
        out.settings = text.str();
    }

    // Global triangle ids in mesh order; the reduction sums in this order.
    std::vector<MeshShading> shading(scene.meshes.size());
    std::vector<TriangleRef> triangles;
    triangles.reserve(scene.triangleCount());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        const Material& material = scene.materialOf(mesh);
        MeshShading& s = shading[m];
        s.mesh = &mesh;
        s.material = &material;
        // Uniform COLOR_0 (exporters often write all white) folds into the factor: the piece
        // then needs no sampling and a uniform colour comes out exactly.
        const bool uniformColors = std::all_of(mesh.colors.begin(), mesh.colors.end(),
                                               [&](const vec4& c) { return c == mesh.colors.front(); });
        const vec4 base = material.baseColorFactor * (mesh.colors.empty() ? vec4(1.0f) : mesh.colors.front());
        s.constantBase = !material.baseColorTexture.valid() && uniformColors;
        s.constantEmission = !material.emissiveTexture.valid();
        s.baseColor = vec3(base);
        s.baseAlpha = base.w;
        s.emission = material.emission();
        s.transmissionFactor = glm::clamp(1.0f - material.transmission, 0.0f, 1.0f);
        for (size_t t = 0; t < mesh.triangleCount(); ++t)
            triangles.push_back({static_cast<uint32_t>(m), static_cast<uint32_t>(t)});
    }

    const Bounds bounds = voxelBounds(scene, h);
    KeyPacker packer;
    for (int a = 0; a < 3; ++a) packer.origin[a] = static_cast<int>(std::ceil(bounds.lower[a] - 0.5)) - 1;

    std::vector<TriangleInfo> info(triangles.size());
    tbb::enumerable_thread_specific<std::vector<Fragment>> perThread;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 64), [&](const tbb::blocked_range<size_t>& range) {
        std::vector<Fragment>& fragments = perThread.local();
        for (size_t id = range.begin(); id != range.end(); ++id) {
            const TriangleRef ref = triangles[id];
            const MeshShading& s = shading[ref.mesh];
            const Mesh& mesh = *s.mesh;
            const vec3& p0 = mesh.positions[mesh.indices[3 * ref.triangle]];
            const vec3& p1 = mesh.positions[mesh.indices[3 * ref.triangle + 1]];
            const vec3& p2 = mesh.positions[mesh.indices[3 * ref.triangle + 2]];
            const dvec3 cross = glm::cross(dvec3(p1) - dvec3(p0), dvec3(p2) - dvec3(p0));
            const double length = glm::length(cross);
            info[id] = {vec3(0.0f), s.material->doubleSided};
            if (!(length > 0.0)) continue;  // zero area: no surface to voxelize
            const dvec3 n = cross / length;
            info[id].normal = vec3(n);
            forEachVoxelPiece(toVoxelUnits(p0, h), toVoxelUnits(p1, h), toVoxelUnits(p2, h), n,
                              [&](const ivec3& voxel, const ClipPolygon& piece, double area) {
                                  const PieceShading shade = shadePiece(scene, s, ref.triangle, piece, area, n,
                                                                        settings.texelSamples, withEmission);
                                  if (!(shade.coverage > 0.0)) return;
                                  Fragment f;
                                  f.key = packer.pack(voxel);
                                  f.triangle = static_cast<uint32_t>(id);
                                  f.coverage = static_cast<float>(shade.coverage);
                                  f.centroid = vec3(pieceCentroid(piece) - dvec3(voxel));
                                  f.albedo = vec3(shade.albedo / shade.coverage);
                                  f.emission = vec3(shade.emission / shade.coverage);
                                  fragments.push_back(f);
                              });
        }
        if (progress) progress->advance(range.size());
    });

    std::vector<Fragment> fragments;
    {
        size_t total = 0;
        for (const auto& local : perThread) total += local.size();
        fragments.reserve(total);
        for (auto& local : perThread) {
            fragments.insert(fragments.end(), local.begin(), local.end());
            std::vector<Fragment>().swap(local);
        }
    }
    // (key, triangle) pairs are unique, so any sort gives the same order.
    tbb::parallel_sort(fragments.begin(), fragments.end(), fragmentOrder);

    std::vector<size_t> runStart;
    for (size_t f = 0; f < fragments.size(); ++f)
        if (f == 0 || fragments[f].key != fragments[f - 1].key) runStart.push_back(f);
    runStart.push_back(fragments.size());
    const size_t voxelCount = runStart.size() - 1;

    out.coords.resize(voxelCount);
    out.albedo.resize(voxelCount);
    out.normal.resize(voxelCount);
    out.axisWeights.resize(voxelCount);
    out.opacity.resize(voxelCount);
    out.solid.resize(voxelCount);
    out.surfaceOffset.resize(voxelCount);
    if (withEmission) out.emission.resize(voxelCount);
    std::vector<double> voxelArea(voxelCount);

    tbb::parallel_for(tbb::blocked_range<size_t>(0, voxelCount, 256), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t v = range.begin(); v != range.end(); ++v) {
            double coverage = 0.0;
            dvec3 albedo(0.0), emission(0.0), normal(0.0), centroid(0.0);
            double axis[6] = {0, 0, 0, 0, 0, 0};
            for (size_t f = runStart[v]; f < runStart[v + 1]; ++f) {
                const Fragment& frag = fragments[f];
                const TriangleInfo& tri = info[frag.triangle];
                const double c = frag.coverage;
                coverage += c;
                albedo += c * dvec3(frag.albedo);
                centroid += c * dvec3(frag.centroid);
                emission += c * dvec3(frag.emission);
                normal += c * dvec3(tri.normal);
                for (int a = 0; a < 3; ++a) {
                    const double na = tri.normal[a];
                    if (tri.doubleSided) {
                        axis[2 * a] += c * std::fabs(na);
                        axis[2 * a + 1] += c * std::fabs(na);
                    } else {
                        axis[2 * a] += c * std::max(na, 0.0);
                        axis[2 * a + 1] += c * std::max(-na, 0.0);
                    }
                }
            }
            out.coords[v] = packer.unpack(fragments[runStart[v]].key);
            out.albedo[v] = vec3(albedo / coverage);
            out.surfaceOffset[v] = glm::clamp(vec3(centroid / coverage), vec3(-0.5f), vec3(0.5f));
            if (withEmission) out.emission[v] = vec3(emission / coverage);
            const double normalLength = glm::length(normal);
            out.normal[v] = normalLength > 1e-6 * coverage ? vec3(normal / normalLength) : vec3(0.0f);
            for (int face = 0; face < 6; ++face) out.axisWeights[v][face] = static_cast<float>(axis[face]);
            const float alpha = static_cast<float>(std::min(1.0, coverage));
            out.opacity[v] = alpha;
            out.solid[v] = alpha >= 1.0f ? 1 : 0;
            voxelArea[v] = coverage;
        }
    });

    if (stats) {
        stats->triangles = 0;
        for (const TriangleInfo& t : info) stats->triangles += t.normal != vec3(0.0f) ? 1 : 0;
        stats->fragments = fragments.size();
        double area = 0.0;
        for (double a : voxelArea) area += a;
        stats->surfaceArea = area * h * h;
    }
    std::vector<Fragment>().swap(fragments);

    size_t interior = 0;
    if (settings.fillInterior) {
        const std::vector<InsideVoxel> inside = voxelsInsideClosedMeshes(scene, triangles, info, shading, packer, h);
        interior = mergeInside(out, inside, packer);
    }

    if (stats) {
        stats->interiorVoxels = interior;
        const size_t perVoxel = sizeof(ivec3) + sizeof(vec3) * (withEmission ? 3 : 2) + sizeof(AxisWeights) +
                                sizeof(float) + sizeof(uint8_t);
        stats->channelBytes = double(out.size()) * perVoxel;
        ivec3 lower(INT32_MAX), upper(INT32_MIN);
        for (const ivec3& c : out.coords) {
            lower = glm::min(lower, c);
            upper = glm::max(upper, c);
        }
        const double denseVoxels =
            out.size() ? double(upper.x - lower.x + 1) * double(upper.y - lower.y + 1) * double(upper.z - lower.z + 1) : 0.0;
        stats->denseBytes = denseVoxels * (perVoxel - sizeof(ivec3));
    }
    return out;
}

}  // namespace vl
