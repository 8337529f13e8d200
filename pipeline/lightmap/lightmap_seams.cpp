#include "lightmap/lightmap_seams.h"

#include "lightmap/lightmap_image.h"
#include "core/aabb.h"
#include "core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <unordered_map>

namespace vl {
namespace {

// Two ends of one uv1 closer than this (texels) are the same place in the atlas.
constexpr float kSameUvTexels = 1e-3f;
// The conjugate gradients stop at this residual, relative to the right-hand side, or after
// kMaxStitchIterations; a tighter tolerance barely changes the seams' jump (docs/seams.md).
constexpr double kStitchTolerance = 1e-4;
constexpr int kMaxStitchIterations = 2000;
// Rounds of the bounded solve (below): each holds at zero what the last took below it.
constexpr int kMaxStitchRounds = 8;
// The direct and indirect images' RGB, solved side by side.
constexpr int kStitchChannels = 6;

// Vertices welded by position: equal within `eps` (a hash grid of eps cells, the 27 cells
// around a point searched in a fixed order and each cell's points in the order they came, so
// the ids do not depend on the hash's order). A cell holds its first and last point; each point
// the next of its cell: a few words a vertex, which a mesh of millions of them needs.
class PositionWeld {
public:
    explicit PositionWeld(double eps) : eps_(eps) {}
    uint32_t id(const vec3& p) {
        const std::array<int64_t, 3> cell = cellOf(p);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const auto found = cells_.find(key({cell[0] + dx, cell[1] + dy, cell[2] + dz}));
                    if (found == cells_.end()) continue;
                    for (uint32_t id = found->second.first; id != kNone; id = next_[id])
                        if (glm::length(glm::dvec3(points_[id]) - glm::dvec3(p)) <= eps_) return id;
                }
        const uint32_t id = static_cast<uint32_t>(points_.size());
        points_.push_back(p);
        next_.push_back(kNone);
        const auto [slot, added] = cells_.try_emplace(key(cell), id, id);
        if (!added) {
            next_[slot->second.second] = id;
            slot->second.second = id;
        }
        return id;
    }

private:
    static constexpr uint32_t kNone = ~0u;
    std::array<int64_t, 3> cellOf(const vec3& p) const {
        return {static_cast<int64_t>(std::floor(p.x / eps_)), static_cast<int64_t>(std::floor(p.y / eps_)),
                static_cast<int64_t>(std::floor(p.z / eps_))};
    }
    static uint64_t key(const std::array<int64_t, 3>& c) {
        uint64_t h = 1469598103934665603ull;
        for (int64_t v : c) h = (h ^ static_cast<uint64_t>(v)) * 1099511628211ull;
        return h;
    }
    double eps_;
    std::vector<vec3> points_;
    std::vector<uint32_t> next_;  // per point: the next point of its cell
    std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> cells_;  // a cell's first and last point
};

// A triangle's side on one 3D edge: the edge's ends (welded ids, lo < hi) and which corner
// of the triangle lies at each.
struct EdgeUse {
    uint32_t lo = 0, hi = 0;
    uint32_t mesh = 0, triangle = 0;
    uint8_t cornerLo = 0, cornerHi = 0, cornerOther = 0;
};

vec3 faceNormal(const Mesh& mesh, uint32_t t) {
    const vec3& a = mesh.positions[mesh.indices[3 * size_t(t)]];
    const vec3& b = mesh.positions[mesh.indices[3 * size_t(t) + 1]];
    const vec3& c = mesh.positions[mesh.indices[3 * size_t(t) + 2]];
    const vec3 n = glm::cross(b - a, c - a);
    const float length = glm::length(n);
    return length > 0.0f ? n / length : vec3(0.0f);
}

vec3 vertexNormal(const Mesh& mesh, uint32_t t, int corner) {
    const uint32_t v = mesh.indices[3 * size_t(t) + size_t(corner)];
    return mesh.normals.size() == mesh.positions.size() ? mesh.normals[v] : faceNormal(mesh, t);
}

// A bilinear read at texel coordinates p (texel centres at i + ½, clamped to the image's
// edge, as lightmap/lightmap_image.h sampleLightmap reads): four texels and their weights.
struct Footprint {
    std::array<size_t, 4> texel{};
    std::array<float, 4> weight{};
};

Footprint footprintAt(vec2 p, int width, int height) {
    const float px = std::clamp(p.x - 0.5f, -1.0f, float(width));
    const float py = std::clamp(p.y - 0.5f, -1.0f, float(height));
    const float fx0 = std::floor(px), fy0 = std::floor(py);
    const int x0 = int(fx0), y0 = int(fy0);
    const float ax = px - fx0, ay = py - fy0;
    Footprint f;
    int k = 0;
    for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx, ++k) {
            const int x = std::clamp(x0 + dx, 0, width - 1), y = std::clamp(y0 + dy, 0, height - 1);
            f.texel[size_t(k)] = size_t(y) * size_t(width) + size_t(x);
            f.weight[size_t(k)] = (dx ? ax : 1.0f - ax) * (dy ? ay : 1.0f - ay);
        }
    return f;
}

vec3 readAt(const Image& image, const Footprint& f) {
    vec3 v(0.0f);
    for (size_t k = 0; k < 4; ++k) {
        const float* texel = &image.pixels[f.texel[k] * size_t(image.channels)];
        v += f.weight[k] * vec3(texel[0], texel[1], texel[2]);
    }
    return v;
}

// The pairs read along a seam: about two per texel of its longer side.
int pairsAlong(const LightmapSeam& seam) {
    const float texels = std::max(glm::length(seam.sides[0].b - seam.sides[0].a), glm::length(seam.sides[1].b - seam.sides[1].a));
    return std::clamp(static_cast<int>(std::ceil(2.0f * texels)), 2, 4096);
}

vec2 pointOn(const SeamSide& side, float t, float inset) { return side.a + t * (side.b - side.a) + inset * side.inward; }

}  // namespace

std::vector<LightmapSeam> findLightmapSeams(const Scene& scene, const std::vector<uint32_t>& meshes, int width,
                                            int height) {
    Aabb box;
    for (uint32_t m : meshes)
        for (const vec3& p : scene.meshes[m].positions) box.extend(p);
    const double extent = box.empty() ? 0.0 : glm::length(glm::dvec3(box.upper) - glm::dvec3(box.lower));
    PositionWeld weld(std::max(1e-6 * extent, 1e-9));

    std::vector<EdgeUse> uses;
    std::vector<std::vector<uint32_t>> welded(scene.meshes.size());
    for (uint32_t m : meshes) {
        const Mesh& mesh = scene.meshes[m];
        if (mesh.uv1.empty()) continue;
        std::vector<uint32_t>& ids = welded[m];
        ids.reserve(mesh.positions.size());
        for (const vec3& p : mesh.positions) ids.push_back(weld.id(p));
        for (uint32_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t* index = &mesh.indices[3 * size_t(t)];
            if (index[0] >= mesh.uv1.size() || index[1] >= mesh.uv1.size() || index[2] >= mesh.uv1.size()) continue;
            for (int e = 0; e < 3; ++e) {
                const int i = e, j = (e + 1) % 3;
                uint32_t a = ids[index[i]], b = ids[index[j]];
                if (a == b) continue;
                EdgeUse use;
                use.mesh = m;
                use.triangle = t;
                use.cornerOther = uint8_t((e + 2) % 3);
                use.lo = std::min(a, b);
                use.hi = std::max(a, b);
                use.cornerLo = uint8_t(a < b ? i : j);
                use.cornerHi = uint8_t(a < b ? j : i);
                uses.push_back(use);
            }
        }
    }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
        return std::tie(x.lo, x.hi, x.mesh, x.triangle, x.cornerLo) < std::tie(y.lo, y.hi, y.mesh, y.triangle, y.cornerLo);
    });

    const vec2 size(static_cast<float>(width), static_cast<float>(height));
    const float smooth = std::cos(glm::radians(kSeamNormalDegrees));
    const auto texelAt = [&](const EdgeUse& use, int corner) {
        const Mesh& mesh = scene.meshes[use.mesh];
        return mesh.uv1[mesh.indices[3 * size_t(use.triangle) + size_t(corner)]] * size;
    };
    const auto sideOf = [&](const EdgeUse& use, SeamSide& side) {
        side.a = texelAt(use, use.cornerLo);
        side.b = texelAt(use, use.cornerHi);
        const vec2 edge = side.b - side.a, toOther = texelAt(use, use.cornerOther) - side.a;
        const float length = glm::length(edge);
        const float cross = edge.x * toOther.y - edge.y * toOther.x;
        // A triangle with no area in the atlas has no inside to read.
        if (!(length > 1e-6f) || !(std::abs(cross) > 1e-6f * length)) return false;
        side.inward = vec2(-edge.y, edge.x) / length;
        if (cross < 0.0f) side.inward = -side.inward;
        side.mesh = use.mesh;
        side.triangle = use.triangle;
        return true;
    };

    std::vector<LightmapSeam> seams;
    for (size_t first = 0; first < uses.size();) {
        size_t end = first + 1;
        while (end < uses.size() && uses[end].lo == uses[first].lo && uses[end].hi == uses[first].hi) ++end;
        for (size_t r = first; r < end; ++r)
            for (size_t s = r + 1; s < end; ++s) {
                const EdgeUse& x = uses[r];
                const EdgeUse& y = uses[s];
                const Mesh& mx = scene.meshes[x.mesh];
                const Mesh& my = scene.meshes[y.mesh];
                if (glm::distance(texelAt(x, x.cornerLo), texelAt(y, y.cornerLo)) < kSameUvTexels &&
                    glm::distance(texelAt(x, x.cornerHi), texelAt(y, y.cornerHi)) < kSameUvTexels)
                    continue;  // one chart's own edge
                const float facing = glm::dot(faceNormal(mx, x.triangle), faceNormal(my, y.triangle));
                if (facing <= 0.0f) continue;
                if (glm::dot(vertexNormal(mx, x.triangle, x.cornerLo), vertexNormal(my, y.triangle, y.cornerLo)) < smooth ||
                    glm::dot(vertexNormal(mx, x.triangle, x.cornerHi), vertexNormal(my, y.triangle, y.cornerHi)) < smooth)
                    continue;  // a crease
                LightmapSeam seam;
                if (!sideOf(x, seam.sides[0]) || !sideOf(y, seam.sides[1])) continue;
                const vec3& p = mx.positions[mx.indices[3 * size_t(x.triangle) + size_t(x.cornerLo)]];
                const vec3& q = mx.positions[mx.indices[3 * size_t(x.triangle) + size_t(x.cornerHi)]];
                seam.length = glm::length(glm::dvec3(q) - glm::dvec3(p));
                seam.foldDegrees = glm::degrees(std::acos(std::min(facing, 1.0f)));
                seams.push_back(seam);
            }
        first = end;
    }
    return seams;
}

SeamJump measureSeamJump(const std::vector<LightmapSeam>& seams, const Image& texels, float inset) {
    if (texels.channels < 3) throw Error("measureSeamJump: the lightmap is not RGB");
    SeamJump jump;
    for (const LightmapSeam& seam : seams) {
        ++jump.edges;
        jump.length += seam.length;
        const int n = pairsAlong(seam);
        const double w = seam.length / n;
        for (int k = 0; k < n; ++k) {
            const float t = (static_cast<float>(k) + 0.5f) / static_cast<float>(n);
            const vec3 a = readAt(texels, footprintAt(pointOn(seam.sides[0], t, inset), texels.width, texels.height));
            const vec3 b = readAt(texels, footprintAt(pointOn(seam.sides[1], t, inset), texels.width, texels.height));
            const double difference = std::abs(double(a.x) - b.x) + std::abs(double(a.y) - b.y) + std::abs(double(a.z) - b.z);
            const double level = 0.5 * ((double(a.x) + b.x) + (double(a.y) + b.y) + (double(a.z) + b.z));
            if (!(level > 0.0)) continue;
            jump.weight += w;
            jump.relativeSum += w * difference / level;
            jump.jumpSum += w * difference;
            jump.levelSum += w * level;
        }
    }
    jump.meanRelative = jump.weight > 0.0 ? jump.relativeSum / jump.weight : 0.0;
    jump.pooledRelative = jump.levelSum > 0.0 ? jump.jumpSum / jump.levelSum : 0.0;
    return jump;
}

size_t stitchLightmapSeams(const std::vector<LightmapSeam>& seams, const Image& mask, Image& direct, Image& indirect,
                           Image& total) {
    const int width = mask.width, height = mask.height;
    for (const Image* image : {&direct, &indirect, &total})
        if (image->width != width || image->height != height || image->channels < 3)
            throw Error("stitchLightmapSeams: the images are not the mask's size, or not RGB");
    if (seams.empty()) return 0;

    // The rows of the least-squares system: one per pair read, side 0's bilinear weights
    // minus side 1's, over the texels they touch (numbered in the order first met).
    std::vector<int32_t> variableOf(size_t(width) * size_t(height), -1);
    std::vector<size_t> texelOf;
    std::vector<size_t> rowStart{0};
    std::vector<std::pair<int32_t, float>> entries;
    const auto variable = [&](size_t texel) {
        if (variableOf[texel] < 0) {
            variableOf[texel] = static_cast<int32_t>(texelOf.size());
            texelOf.push_back(texel);
        }
        return variableOf[texel];
    };
    for (const LightmapSeam& seam : seams) {
        const int n = pairsAlong(seam);
        for (int k = 0; k < n; ++k) {
            const float t = (static_cast<float>(k) + 0.5f) / static_cast<float>(n);
            {
                const size_t begin = entries.size();
                for (int side = 0; side < 2; ++side) {
                    const Footprint f = footprintAt(pointOn(seam.sides[side], t, 0.0f), width, height);
                    for (size_t j = 0; j < 4; ++j) {
                        if (f.weight[j] == 0.0f) continue;
                        const int32_t v = variable(f.texel[j]);
                        const float w = side == 0 ? f.weight[j] : -f.weight[j];
                        auto same = std::find_if(entries.begin() + long(begin), entries.end(),
                                                 [&](const std::pair<int32_t, float>& e) { return e.first == v; });
                        if (same != entries.end()) same->second += w;
                        else entries.push_back({v, w});
                    }
                }
                rowStart.push_back(entries.size());
            }
        }
    }
    const size_t variables = texelOf.size(), rows = rowStart.size() - 1;
    std::vector<double> lambda(variables);
    for (size_t v = 0; v < variables; ++v)
        lambda[v] = mask.pixels[texelOf[v] * size_t(mask.channels)] > 0.5f ? kStitchCoveredWeight : kStitchPaddingWeight;

    // x = baked + d, (JᵀJ + Λ) d = −JᵀJ baked: the change, solved for all six channels side by
    // side (each its own step sizes), in double.
    constexpr int C = kStitchChannels;
    const auto baked = [&](size_t v, int c) {
        const Image& image = c < 3 ? direct : indirect;
        return double(image.pixels[texelOf[v] * size_t(image.channels) + size_t(c % 3)]);
    };
    // y = JᵀJ x (+ Λ x when withLambda).
    const auto apply = [&](const std::vector<double>& x, std::vector<double>& y, bool withLambda) {
        for (size_t v = 0; v < variables; ++v)
            for (int c = 0; c < C; ++c) y[v * C + size_t(c)] = withLambda ? lambda[v] * x[v * C + size_t(c)] : 0.0;
        for (size_t r = 0; r < rows; ++r) {
            std::array<double, C> dot{};
            for (size_t e = rowStart[r]; e < rowStart[r + 1]; ++e)
                for (int c = 0; c < C; ++c) dot[size_t(c)] += entries[e].second * x[size_t(entries[e].first) * C + size_t(c)];
            for (size_t e = rowStart[r]; e < rowStart[r + 1]; ++e)
                for (int c = 0; c < C; ++c) y[size_t(entries[e].first) * C + size_t(c)] += entries[e].second * dot[size_t(c)];
        }
    };
    // Conjugate gradients preconditioned by the diagonal (Jacobi): covered and padding texels
    // differ in λ by kStitchCoveredWeight / kStitchPaddingWeight, and a texel's share of the
    // pairs by the seams around it, so the plain method needs many more steps.
    std::vector<double> diagonal(lambda);
    for (size_t e = 0; e < entries.size(); ++e)
        diagonal[size_t(entries[e].first)] += double(entries[e].second) * double(entries[e].second);
    std::vector<double> x0(variables * C), b(variables * C), d(variables * C, 0.0), r(variables * C),
        z(variables * C), p(variables * C), q(variables * C);
    for (size_t v = 0; v < variables; ++v)
        for (int c = 0; c < C; ++c) x0[v * C + size_t(c)] = baked(v, c);
    apply(x0, b, false);
    for (double& value : b) value = -value;
    std::array<double, C> limit{};
    for (size_t i = 0; i < variables * C; ++i) limit[i % C] += b[i] * b[i];
    for (int c = 0; c < C; ++c) limit[size_t(c)] *= kStitchTolerance * kStitchTolerance;

    // Light is not negative, and a texel clamped to zero after the solve no longer meets its
    // seam: where a chart's edge crosses its last covered texel, the padding beyond takes a
    // small share of the read and must go far below zero to bring a bright side down to a
    // dark one (docs/seams.md). So the solve is bounded: each round solves for the free
    // values, and those that came out below zero are held at zero in the next, where the
    // other side's texels take the step (an active set that only grows, so the rounds end).
    std::vector<uint8_t> held(variables * C, 0);
    for (int round = 0; round < kMaxStitchRounds; ++round) {
        // r = b − A d on the free values; p, q and the step live on them too.
        apply(d, q, true);
        std::array<double, C> rr{}, rz{};
        for (size_t i = 0; i < variables * C; ++i) {
            r[i] = held[i] ? 0.0 : b[i] - q[i];
            z[i] = r[i] / diagonal[i / C];
            p[i] = z[i];
            rr[i % C] += r[i] * r[i];
            rz[i % C] += r[i] * z[i];
        }
        for (int iteration = 0; iteration < kMaxStitchIterations; ++iteration) {
            std::array<bool, C> active{};
            bool any = false;
            for (int c = 0; c < C; ++c) any = (active[size_t(c)] = rr[size_t(c)] > limit[size_t(c)]) || any;
            if (!any) break;
            apply(p, q, true);
            std::array<double, C> pq{}, alpha{}, nextRr{}, nextRz{};
            for (size_t i = 0; i < variables * C; ++i)
                if (!held[i]) pq[i % C] += p[i] * q[i];
            for (int c = 0; c < C; ++c)
                alpha[size_t(c)] = active[size_t(c)] && pq[size_t(c)] > 0.0 ? rz[size_t(c)] / pq[size_t(c)] : 0.0;
            for (size_t i = 0; i < variables * C; ++i) {
                if (held[i]) continue;
                const size_t c = i % C;
                d[i] += alpha[c] * p[i];
                r[i] -= alpha[c] * q[i];
                z[i] = r[i] / diagonal[i / C];
                nextRr[c] += r[i] * r[i];
                nextRz[c] += r[i] * z[i];
            }
            for (size_t i = 0; i < variables * C; ++i) {
                const size_t c = i % C;
                if (active[c] && !held[i]) p[i] = z[i] + (rz[c] > 0.0 ? nextRz[c] / rz[c] : 0.0) * p[i];
            }
            for (int c = 0; c < C; ++c)
                if (active[size_t(c)]) {
                    rr[size_t(c)] = nextRr[size_t(c)];
                    rz[size_t(c)] = nextRz[size_t(c)];
                }
        }
        size_t newlyHeld = 0;
        for (size_t i = 0; i < variables * C; ++i)
            if (!held[i] && x0[i] + d[i] < 0.0) {
                held[i] = 1;
                d[i] = -x0[i];
                ++newlyHeld;
            }
        if (newlyHeld == 0) break;
    }

    for (size_t v = 0; v < variables; ++v) {
        const size_t texel = texelOf[v];
        for (int c = 0; c < 3; ++c) {
            float& dv = direct.pixels[texel * size_t(direct.channels) + size_t(c)];
            float& iv = indirect.pixels[texel * size_t(indirect.channels) + size_t(c)];
            dv = std::max(0.0f, static_cast<float>(x0[v * C + size_t(c)] + d[v * C + size_t(c)]));
            iv = std::max(0.0f, static_cast<float>(x0[v * C + size_t(c) + 3] + d[v * C + size_t(c) + 3]));
            total.pixels[texel * size_t(total.channels) + size_t(c)] = dv + iv;
        }
    }
    return variables;
}

namespace {

// The solve takes two RGB images: the mask's channels 0–2 go as the first, channel 3 as the
// second's red.
void stitchShadowmask(const std::vector<LightmapSeam>& seams, const Image& mask, Image& shadowmask) {
    const int width = shadowmask.width, height = shadowmask.height;
    Image first(width, height, 3), second(width, height, 3), unused(width, height, 3);
    const size_t texels = size_t(width) * size_t(height);
    for (size_t t = 0; t < texels; ++t) {
        for (size_t c = 0; c < 3; ++c) first.pixels[3 * t + c] = shadowmask.pixels[4 * t + c];
        second.pixels[3 * t] = shadowmask.pixels[4 * t + 3];
    }
    stitchLightmapSeams(seams, mask, first, second, unused);
    for (size_t t = 0; t < texels; ++t) {
        for (size_t c = 0; c < 3; ++c) shadowmask.pixels[4 * t + c] = std::min(1.0f, first.pixels[3 * t + c]);
        shadowmask.pixels[4 * t + 3] = std::min(1.0f, second.pixels[3 * t]);
    }
}

}  // namespace

LightmapSeamReport finishLightmapSeams(const Scene& scene, const std::vector<uint32_t>& meshes, const Image& mask,
                                       Image& direct, Image& indirect, Image& total, bool stitch, Image* shadowmask) {
    LightmapSeamReport report;
    const std::vector<LightmapSeam> seams = findLightmapSeams(scene, meshes, mask.width, mask.height);
    const Image before = shippedLightmapTexels(total);
    report.before = measureSeamJump(seams, before);
    report.beforeAtEdge = measureSeamJump(seams, before, 0.0f);
    report.after = report.before;
    report.afterAtEdge = report.beforeAtEdge;
    report.stitched = stitch;
    if (!stitch || seams.empty()) return report;
    report.texelsMoved = stitchLightmapSeams(seams, mask, direct, indirect, total);
    if (shadowmask && !shadowmask->empty()) stitchShadowmask(seams, mask, *shadowmask);
    const Image after = shippedLightmapTexels(total);
    report.after = measureSeamJump(seams, after);
    report.afterAtEdge = measureSeamJump(seams, after, 0.0f);
    return report;
}

namespace {

SeamJump combine(const std::vector<LightmapSeamReport>& reports, SeamJump LightmapSeamReport::*which) {
    SeamJump sum;
    for (const LightmapSeamReport& report : reports) {
        const SeamJump& j = report.*which;
        sum.edges += j.edges;
        sum.length += j.length;
        sum.weight += j.weight;
        sum.relativeSum += j.relativeSum;
        sum.jumpSum += j.jumpSum;
        sum.levelSum += j.levelSum;
    }
    sum.meanRelative = sum.weight > 0.0 ? sum.relativeSum / sum.weight : 0.0;
    sum.pooledRelative = sum.levelSum > 0.0 ? sum.jumpSum / sum.levelSum : 0.0;
    return sum;
}

}  // namespace

LightmapSeamReport combineSeamReports(const std::vector<LightmapSeamReport>& reports) {
    LightmapSeamReport out;
    for (const LightmapSeamReport& report : reports) {
        out.stitched = out.stitched || report.stitched;
        out.texelsMoved += report.texelsMoved;
    }
    out.before = combine(reports, &LightmapSeamReport::before);
    out.after = combine(reports, &LightmapSeamReport::after);
    out.beforeAtEdge = combine(reports, &LightmapSeamReport::beforeAtEdge);
    out.afterAtEdge = combine(reports, &LightmapSeamReport::afterAtEdge);
    return out;
}

}  // namespace vl
