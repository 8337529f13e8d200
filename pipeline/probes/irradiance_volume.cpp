#include "probes/irradiance_volume.h"

#include "core/error.h"
#include "core/progress.h"
#include "core/text.h"
#include "lighting/direct_light.h"
#include "trace/bvh_traverse.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vl {
namespace {

// Probes are lit in batches, so progress moves and the fans' memory stays bounded.
constexpr size_t kProbesPerBatch = 4096;
// Stratified directions over a sun's disk where its nine test points disagree.
constexpr int kSunStrata = 8;

// Whether at least kProbeBackfaceShare of kProbeInsideRays rays from p, spread over the sphere,
// hit a surface from behind (its interpolated normal along the ray, as shade_element.h isBuried
// tells a buried texel).
bool insideGeometry(const TraceSceneView& scene, const BvhView& bvh, const vec3& p) {
    constexpr float golden = 2.39996322972865332f;  // π(3 − √5)
    int behind = 0;
    for (int r = 0; r < kProbeInsideRays; ++r) {
        const float z = 1.0f - (2.0f * float(r) + 1.0f) / float(kProbeInsideRays);
        const float radius = std::sqrt(std::max(0.0f, 1.0f - z * z));
        Ray ray;
        ray.origin = p;
        ray.direction = vec3(radius * std::cos(golden * float(r)), radius * std::sin(golden * float(r)), z);
        Hit hit;
        if (!intersectClosest(bvh, ray, hit)) continue;
        const vec3* n = scene.normals + 3 * size_t(hit.triangle);
        const vec3 normal = (1.0f - hit.b1 - hit.b2) * n[0] + hit.b1 * n[1] + hit.b2 * n[2];
        if (glm::dot(normal, ray.direction) > 0.0f) ++behind;
    }
    return float(behind) >= kProbeBackfaceShare * float(kProbeInsideRays);
}

// The punctual lights a lightmap holds, seen from p (local frame), added to A and B (local
// axes) as the exact SH projection of a light from direction ω with irradiance E at normal
// incidence: E(n) = E·max(0, n·ω) projects to E/4 + (E/2) ω·n.
// `apart`: per light, its sun channel, or −1 for a light projected here.
void addPunctualLights(const TraceSceneView& scene, const BvhView& bvh, const vec3& p, uint64_t seed,
                       const std::vector<int>& apart, vec3& mean, std::array<vec3, 3>& gradient,
                       std::array<float, kVolumeSuns>& sunVisibility) {
    for (uint32_t i = 0; i < scene.lightCount; ++i) {
        const TraceLight& light = scene.lights[i];
        if (apart[i] >= 0) {
            sunVisibility[size_t(apart[i])] = lightVisibility(bvh, light, p, -light.direction, kSunStrata, seed, i);
            continue;
        }
        if (light.engineDrawn) continue;
        vec3 toward;
        if (light.type == TraceLightType::Directional) {
            toward = -light.direction;
        } else {
            const vec3 d = light.position - p;
            if (!(glm::dot(d, d) > 0.0f)) continue;
            toward = glm::normalize(d);
        }
        const PunctualArrival arrival = punctualArrival(light, p, toward, toward, vec2(0.0f));
        if (!(maxComponent(arrival.irradiance) > 0.0f)) continue;
        const float seen = lightVisibility(bvh, light, p, toward, kSunStrata, seed, i);
        if (!(seen > 0.0f)) continue;
        const vec3 e = seen * arrival.irradiance * kInvPi;
        mean += 0.25f * e;
        for (int axis = 0; axis < 3; ++axis) gradient[size_t(axis)] += 0.5f * e * toward[axis];
    }
}

}  // namespace

WorldBox worldBox(const Scene& scene) {
    WorldBox box;
    for (const Mesh& mesh : scene.meshes)
        for (const vec3& p : mesh.positions) {
            const glm::dvec3 world = scene.origin + scene.frame * glm::dvec3(p);
            box.lo = glm::min(box.lo, world);
            box.hi = glm::max(box.hi, world);
        }
    return box;
}

namespace {

// Cells `spacing` wide along one axis of the box: at least one.
double cellsAlong(const WorldBox& box, int axis, double spacing) {
    return std::max(1.0, std::ceil((box.hi[axis] - box.lo[axis]) / spacing - 1e-9));
}

}  // namespace

double volumeProbeCount(const WorldBox& box, double spacing) {
    if (box.empty() || !(spacing > 0.0)) return 0.0;
    return cellsAlong(box, 0, spacing) * cellsAlong(box, 1, spacing) * cellsAlong(box, 2, spacing);
}

VolumeGrid volumeGrid(const WorldBox& box, double spacing, const std::string& sceneName) {
    VolumeGrid grid;
    if (box.empty() || !(spacing > 0.0)) return grid;
    const glm::dvec3 &lo = box.lo, &hi = box.hi;
    // At the centres of the cells, so no probe lies on the box's walls.
    double total = 1.0;
    for (int axis = 0; axis < 3; ++axis) {
        const double cells = cellsAlong(box, axis, spacing);
        if (!((total *= cells) <= double(kMaxVolumeProbes)))
            throw SettingsError(sceneName + ": irradiance-volume " + numberText(spacing) +
                                " m would place more than " + std::to_string(kMaxVolumeProbes) +
                                " probes over the scene's bounds: give a larger spacing");
        grid.counts[axis] = int(cells);
        grid.spacing[axis] = spacing;
        grid.origin[axis] = 0.5 * (lo[axis] + hi[axis]) - 0.5 * (cells - 1.0) * spacing;
    }
    return grid;
}

IrradianceVolume bakeIrradianceVolume(const Scene& scene, const ReceiverScene& tracing, const ReceiverGather& gather,
                                      const IrradianceVolumeSettings& settings, bool quiet) {
    IrradianceVolume volume;
    const VolumeGrid grid = volumeGrid(worldBox(scene), settings.spacing, scene.sourcePath);
    if (grid.probes() == 0) return volume;
    volume.origin = grid.origin;
    volume.spacing = grid.spacing;
    volume.counts = grid.counts;
    const size_t count = grid.probes();
    volume.mean.assign(count, vec3(0.0f));
    volume.gradient.assign(count, {vec3(0.0f), vec3(0.0f), vec3(0.0f)});
    volume.valid.assign(count, 0);

    const glm::dmat3 toLocal = glm::transpose(scene.frame);
    std::vector<vec3> normals;  // world ±x, ±y, ±z in the local frame
    for (int axis = 0; axis < 3; ++axis)
        for (const double sign : {1.0, -1.0}) {
            glm::dvec3 n(0.0);
            n[axis] = sign;
            normals.push_back(vec3(toLocal * n));
        }
    const glm::mat3 toWorld(scene.frame);
    const TraceSceneView sceneView = tracing.traceScene.view();
    const BvhView bvh = tracing.bvh.view();
    std::vector<int> apart(sceneView.lightCount, -1);
    for (uint32_t i = 0; i < sceneView.lightCount && volume.suns.size() < size_t(kVolumeSuns); ++i) {
        const TraceLight& light = sceneView.lights[i];
        if (light.type != TraceLightType::Directional) continue;
        const vec3 toward = -light.direction;
        const PunctualArrival arrival = punctualArrival(light, vec3(0.0f), toward, toward, vec2(0.0f));
        apart[i] = int(volume.suns.size());
        volume.suns.push_back({glm::normalize(toWorld * light.direction), arrival.irradiance * kInvPi, light.engineDrawn != 0});
    }
    volume.sunVisibility.assign(volume.suns.empty() ? 0 : count, {});
    std::vector<vec3> local(count);
    for (int j = 0; j < volume.counts.y; ++j)
        for (int k = 0; k < volume.counts.z; ++k)
            for (int i = 0; i < volume.counts.x; ++i)
                local[volume.index(i, j, k)] = vec3(toLocal * (volume.position(i, j, k) - scene.origin));
    Progress progress("irradiance volume", count, quiet);
    for (size_t first = 0; first < count; first += kProbesPerBatch) {
        const size_t last = std::min(count, first + kProbesPerBatch);
        const std::vector<vec3> batch(local.begin() + long(first), local.begin() + long(last));
        const std::vector<vec3> lit = gather.openPoints(batch, normals, settings.raysPerAxis, first);
        tbb::parallel_for(first, last, [&](size_t probe) {
            const vec3* e = lit.data() + (probe - first) * normals.size();
            vec3 mean = (e[0] + e[1] + e[2] + e[3] + e[4] + e[5]) * (kInvPi / 6.0f);
            std::array<vec3, 3> local3{};
            std::array<float, kVolumeSuns> seen{};
            addPunctualLights(sceneView, bvh, local[probe], uint64_t(probe), apart, mean, local3, seen);
            if (!volume.suns.empty()) volume.sunVisibility[probe] = seen;
            volume.mean[probe] = mean;
            // The lights' part turned to the world's axes; the fans' part is along them already.
            for (int axis = 0; axis < 3; ++axis) {
                vec3 g = (e[2 * axis] - e[2 * axis + 1]) * (0.5f * kInvPi);
                for (int c = 0; c < 3; ++c) g[c] += (toWorld * vec3(local3[0][c], local3[1][c], local3[2][c]))[axis];
                volume.gradient[probe][size_t(axis)] = g;
            }
            volume.valid[probe] = insideGeometry(sceneView, bvh, local[probe]) ? 0 : 1;
        });
        progress.advance(last - first);
    }
    progress.finish();
    return volume;
}

vec3 volumeIrradiance(const IrradianceVolume& volume, const glm::dvec3& point, const vec3& normal) {
    if (volume.empty()) return vec3(0.0f);
    glm::dvec3 cell = (point - volume.origin) / volume.spacing;
    glm::ivec3 base;
    glm::dvec3 f;
    for (int axis = 0; axis < 3; ++axis) {
        const double top = double(volume.counts[axis] - 1);
        cell[axis] = std::clamp(cell[axis], 0.0, top);
        base[axis] = std::min(int(std::floor(cell[axis])), std::max(0, volume.counts[axis] - 2));
        f[axis] = volume.counts[axis] > 1 ? cell[axis] - double(base[axis]) : 0.0;
    }
    std::array<float, kVolumeSuns> seen{};
    const auto blend = [&](bool validOnly, vec3& mean, std::array<vec3, 3>& gradient) {
        double sum = 0.0;
        mean = vec3(0.0f);
        gradient = {vec3(0.0f), vec3(0.0f), vec3(0.0f)};
        seen = {};
        for (int corner = 0; corner < 8; ++corner) {
            const glm::ivec3 step((corner & 1), (corner >> 1) & 1, (corner >> 2) & 1);
            const glm::ivec3 at = glm::min(base + step, volume.counts - 1);
            double w = 1.0;
            for (int axis = 0; axis < 3; ++axis) w *= step[axis] ? f[axis] : 1.0 - f[axis];
            const size_t probe = volume.index(at.x, at.y, at.z);
            if (validOnly && !volume.valid[probe]) continue;
            // A valid probe keeps a sliver of weight where its trilinear share is 0: a point
            // clamped onto a face of invalid probes still reads the valid ones behind it.
            if (validOnly) w = std::max(w, 1e-6);
            sum += w;
            mean += float(w) * volume.mean[probe];
            for (size_t axis = 0; axis < 3; ++axis) gradient[axis] += float(w) * volume.gradient[probe][axis];
            for (size_t s = 0; s < volume.suns.size(); ++s) seen[s] += float(w) * volume.sunVisibility[probe][s];
        }
        if (!(sum > 0.0)) return false;
        mean /= float(sum);
        for (vec3& g : gradient) g /= float(sum);
        for (float& v : seen) v /= float(sum);
        return true;
    };
    vec3 a;
    std::array<vec3, 3> b;
    if (!blend(true, a, b)) blend(false, a, b);
    vec3 out(0.0f);
    for (int c = 0; c < 3; ++c) {
        // Hazel's non-linear L1 (docs/irradiance-volume.md): R0 = A, R1 = B/2.
        const vec3 r1 = 0.5f * vec3(b[0][c], b[1][c], b[2][c]);
        const float r0 = a[c], length = glm::length(r1);
        if (!(r0 > 0.0f)) continue;
        if (!(length > 1e-6f * r0)) {
            out[c] = r0;
            continue;
        }
        const float r = std::min(1.0f, length / r0);
        const float q = 0.5f * (1.0f + glm::dot(r1 / length, normal));
        const float p = 1.0f + 2.0f * r, k = (1.0f - r) / (1.0f + r);
        out[c] = r0 * (k + (1.0f - k) * (p + 1.0f) * std::pow(std::max(q, 0.0f), p));
    }
    for (size_t s = 0; s < volume.suns.size(); ++s)
        out += seen[s] * std::max(0.0f, -glm::dot(normal, volume.suns[s].direction)) * volume.suns[s].irradiance;
    return out;
}

ExportedIrradianceVolume encodeIrradianceVolume(const IrradianceVolume& volume) {
    ExportedIrradianceVolume out;
    out.origin = volume.origin;
    out.spacing = volume.spacing;
    out.counts = volume.counts;
    const int width = volume.counts.x, height = volume.counts.y * volume.counts.z;
    Image mean(width, height, 3);
    for (size_t p = 0; p < volume.probeCount(); ++p)
        for (int c = 0; c < 3; ++c) mean.pixels[3 * p + size_t(c)] = volume.mean[p][c];
    out.mean = encodeRgbm(mean);
    // B/A of the mean as stored, so a reader's A × B/A is the B baked.
    const Image stored = decodeRgbm(out.mean);
    for (size_t axis = 0; axis < 3; ++axis) {
        std::vector<uint8_t>& bytes = out.gradient[axis];
        bytes.resize(3 * volume.probeCount());
        for (size_t p = 0; p < volume.probeCount(); ++p)
            for (int c = 0; c < 3; ++c) {
                const float a = stored.pixels[3 * p + size_t(c)];
                const float ratio = a > 0.0f ? std::clamp(volume.gradient[p][axis][c] / a, -2.0f, 2.0f) : 0.0f;
                bytes[3 * p + size_t(c)] = uint8_t(std::lround(127.0f + 63.5f * ratio));
            }
    }
    out.valid.resize(volume.probeCount());
    for (size_t p = 0; p < volume.probeCount(); ++p) out.valid[p] = volume.valid[p] ? 255 : 0;
    for (const IrradianceVolume::Sun& sun : volume.suns) out.suns.push_back({sun.direction, sun.irradiance, sun.drawnByEngine});
    if (!volume.suns.empty()) {
        out.sunVisibility.assign(4 * volume.probeCount(), 255);  // channels without a sun: 1
        for (size_t p = 0; p < volume.probeCount(); ++p)
            for (size_t s = 0; s < volume.suns.size(); ++s)
                out.sunVisibility[4 * p + s] =
                    uint8_t(std::lround(std::clamp(volume.sunVisibility[p][s], 0.0f, 1.0f) * 255.0f));
    }
    return out;
}

IrradianceVolume decodeIrradianceVolume(const ExportedIrradianceVolume& encoded) {
    IrradianceVolume volume;
    volume.origin = encoded.origin;
    volume.spacing = encoded.spacing;
    volume.counts = encoded.counts;
    const Image mean = decodeRgbm(encoded.mean);
    const size_t probes = size_t(encoded.counts.x) * size_t(encoded.counts.y) * size_t(encoded.counts.z);
    volume.mean.resize(probes);
    volume.gradient.resize(probes);
    volume.valid.resize(probes);
    for (size_t p = 0; p < probes; ++p) {
        for (int c = 0; c < 3; ++c) volume.mean[p][c] = mean.pixels[3 * p + size_t(c)];
        for (size_t axis = 0; axis < 3; ++axis)
            for (int c = 0; c < 3; ++c)
                volume.gradient[p][axis][c] =
                    volume.mean[p][c] * 2.0f * (float(encoded.gradient[axis][3 * p + size_t(c)]) - 127.0f) / 127.0f;
        volume.valid[p] = encoded.valid[p] > 127 ? 1 : 0;
    }
    for (const ExportedIrradianceVolume::Sun& sun : encoded.suns)
        volume.suns.push_back({sun.direction, sun.irradiance, sun.drawnByEngine});
    if (!volume.suns.empty()) {
        volume.sunVisibility.assign(probes, {});
        for (size_t p = 0; p < probes; ++p)
            for (size_t s = 0; s < volume.suns.size(); ++s)
                volume.sunVisibility[p][s] = float(encoded.sunVisibility[4 * p + s]) / 255.0f;
    }
    return volume;
}

}  // namespace vl
