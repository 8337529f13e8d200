#include "lighting/lighting.h"

#include "core/error.h"
#include "core/progress.h"
#include "core/sampling.h"
#include "core/shared_edge.h"
#include "lighting/lighting_kernels.h"
#include "scene/surface.h"
#include "voxel/index_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <sstream>
#include <vector>

namespace vl {

namespace {

using lighting::EmitterSample;
using lighting::EmitterTriangle;
using lighting::KernelLight;

constexpr int kMaxEmitterStrata = 64;

std::string lightLabel(const Scene& scene, size_t index) {
    const Light& light = scene.lights[index];
    std::ostringstream out;
    out << scene.sourcePath << ": light " << index;
    if (!light.name.empty()) out << " '" << light.name << "'";
    return out.str();
}

bool finite(const vec3& v) { return isFinite(v); }

void validateCoefficients(const AttenuationCoefficients& k, const std::string& what) {
    const bool ok = std::isfinite(k.constant) && std::isfinite(k.linear) && std::isfinite(k.quadratic) &&
                    k.constant >= 0.0f && k.linear >= 0.0f && k.quadratic >= 0.0f &&
                    k.constant + k.linear + k.quadratic > 0.0f;
    if (!ok) {
        std::ostringstream out;
        out << what << ": K_c, K_l, K_q = " << k.constant << ", " << k.linear << ", " << k.quadratic
            << " must be finite, non-negative and not all zero";
        throw SettingsError(out.str());
    }
}

void validateSettings(const Scene& scene, const LightingSettings& settings) {
    if (settings.emitterStrata < 1 || settings.emitterStrata > kMaxEmitterStrata)
        throw SettingsError("lighting: emitter strata " + std::to_string(settings.emitterStrata) +
                            " is outside [1, " + std::to_string(kMaxEmitterStrata) + "]");
    if (settings.threads < 0)
        throw SettingsError("lighting: threads " + std::to_string(settings.threads) + " must be 0 (all) or more");
    if (settings.attenuation) validateCoefficients(*settings.attenuation, "lighting: attenuation");
    for (const auto& entry : settings.lightAttenuation) {
        const std::string& name = entry.first;  // a structured binding cannot be captured before C++20 (clang)
        validateCoefficients(entry.second, "lighting: attenuation of light '" + name + "'");
        const bool known = std::any_of(scene.lights.begin(), scene.lights.end(),
                                       [&](const Light& light) { return light.name == name; });
        if (!known)
            throw SettingsError("lighting: attenuation set for light '" + name + "', but " +
                                (scene.sourcePath.empty() ? std::string("the scene") : scene.sourcePath) +
                                " has no light of that name");
    }
}

void validateVoxels(const VoxelScene& voxels) {
    const size_t n = voxels.size();
    if (!(voxels.voxelSize > 0.0) || !std::isfinite(voxels.voxelSize))
        throw InputError("lighting: voxel size " + std::to_string(voxels.voxelSize) + " of '" + voxels.sourceScene +
                         "' must be positive");
    auto require = [&](size_t size, const char* channel) {
        if (size != n)
            throw InputError("lighting: channel '" + std::string(channel) + "' has " + std::to_string(size) +
                             " values for " + std::to_string(n) + " voxels");
    };
    require(voxels.albedo.size(), "albedo");
    require(voxels.normal.size(), "normal");
    require(voxels.axisWeights.size(), "axis weights");
    require(voxels.opacity.size(), "opacity");
    require(voxels.solid.size(), "solid");
    for (size_t i = 0; i < n; ++i) {
        bool ok = finite(voxels.albedo[i]) && finite(voxels.normal[i]) && std::isfinite(voxels.opacity[i]);
        for (float w : voxels.axisWeights[i]) ok = ok && std::isfinite(w) && w >= 0.0f;
        if (!ok) {
            const ivec3 c = voxels.coords[i];
            throw InputError("lighting: voxel (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ", " +
                             std::to_string(c.z) + ") has a non-finite albedo, normal, opacity or axis weight");
        }
    }
}

std::vector<KernelLight> kernelLights(const Scene& scene, const LightingSettings& settings, float h) {
    std::vector<KernelLight> lights;
    lights.reserve(scene.lights.size());
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& light = scene.lights[i];
        const vec3 intensity = light.radiantIntensity();
        if (!finite(intensity) || light.intensity < 0.0f || glm::min(light.color.x, glm::min(light.color.y, light.color.z)) < 0.0f)
            throw InputError(lightLabel(scene, i) + " has a negative or non-finite colour or intensity");
        if (!finite(light.position))
            throw InputError(lightLabel(scene, i) + " has a non-finite position");
        if (!std::isfinite(light.range) || light.range < 0.0f)
            throw InputError(lightLabel(scene, i) + " has a negative or non-finite range");
        KernelLight k;
        k.intensity = intensity;
        k.position = light.position / h;
        k.range = light.range;
        if (light.type != LightType::Point) {
            const float length = glm::length(light.direction);
            if (!finite(light.direction) || !(length > 0.0f) || !std::isfinite(length))
                throw InputError(lightLabel(scene, i) + " has no valid direction");
            k.direction = light.direction / length;
        }
        switch (light.type) {
        case LightType::Point: k.type = lighting::kPointLight; break;
        case LightType::Directional:
            k.type = lighting::kDirectionalLight;
            if (!(light.angularDiameter >= 0.0f && light.angularDiameter <= 0.5f * kPi))
                throw InputError(lightLabel(scene, i) + " has an angular diameter outside 0..90°");
            k.cosHalfAngle = std::cos(0.5f * light.angularDiameter);
            break;
        case LightType::Spot: {
            k.type = lighting::kSpotLight;
            if (!std::isfinite(light.innerConeAngle) || !std::isfinite(light.outerConeAngle) ||
                light.innerConeAngle < 0.0f || light.outerConeAngle < 0.0f)
                throw InputError(lightLabel(scene, i) + " has invalid cone angles");
            const float cosOuter = std::cos(light.outerConeAngle);
            const float cosInner = std::cos(light.innerConeAngle);
            // KHR_lights_punctual's reference formulation.
            k.spotScale = 1.0f / std::max(0.001f, cosInner - cosOuter);
            k.spotOffset = -cosOuter * k.spotScale;
            break;
        }
        }
        std::optional<AttenuationCoefficients> coefficients = settings.attenuation;
        if (auto it = settings.lightAttenuation.find(light.name); it != settings.lightAttenuation.end())
            coefficients = it->second;
        if (coefficients) {
            k.paperAttenuation = 1;
            k.kc = coefficients->constant;
            k.kl = coefficients->linear;
            k.kq = coefficients->quadratic;
        }
        lights.push_back(k);
    }
    return lights;
}

struct Emitters {
    std::vector<EmitterTriangle> triangles;
    std::vector<EmitterSample> samples;
};

// Whether triangles a and b of one uniform emitter are the two halves of a quad: an edge in
// common and b's other corner in a's plane (within a thousandth of a voxel; index space).
bool halvesOfAQuad(const EmitterTriangle& a, const EmitterTriangle& b) {
    const vec3 va[3] = {a.v0, a.v1, a.v2};
    const vec3 vb[3] = {b.v0, b.v1, b.v2};
    const SharedEdge e = sharedEdge(va, vb);
    return e.shared == 2 && glm::dot(a.normal, b.normal) > 0.9999f &&
           std::abs(glm::dot(a.normal, vb[e.ownB] - a.v0)) < 1e-3f;
}

// The patches of every emissive mesh (lighting_kernels.h EmitterTriangle). A textured
// patch gets its n×n samples here, each stratum jittered once (seeded by the triangle's
// running number) where its texture is read: every sample stands for A/n² of the triangle.
// Uniform patches are sampled per voxel in the kernel.
Emitters emitterSamples(const Scene& scene, int strata, float h) {
    Emitters emitters;
    uint64_t triangleId = 0;
    const float share = 1.0f / static_cast<float>(strata * strata);
    for (const Mesh& mesh : scene.meshes) {
        const Material& material = scene.materialOf(mesh);
        if (!material.emissive()) continue;
        const bool uniform = !material.emissiveTexture.valid();
        if (uniform && !finite(material.emission()))
            throw InputError(scene.sourcePath + ": mesh '" + mesh.name + "' has a non-finite emission");
        if (uniform && !(maxComponent(material.emission()) > 0.0f)) {
            triangleId += mesh.triangleCount();
            continue;
        }
        std::vector<EmitterTriangle> triangles;
        for (size_t t = 0; t < mesh.triangleCount(); ++t, ++triangleId) {
            const vec3 p0 = mesh.positions[mesh.indices[3 * t]];
            const vec3 p1 = mesh.positions[mesh.indices[3 * t + 1]];
            const vec3 p2 = mesh.positions[mesh.indices[3 * t + 2]];
            const vec3 cross = glm::cross(p1 - p0, p2 - p0);
            const float doubleArea = glm::length(cross);
            if (!(doubleArea > 0.0f) || !std::isfinite(doubleArea)) continue;
            EmitterTriangle tri;
            tri.v0 = p0 / h;
            tri.v1 = p1 / h;
            tri.v2 = p2 / h;
            tri.normal = cross / doubleArea;
            tri.area = 0.5f * doubleArea;
            tri.uniform = uniform ? 1 : 0;
            tri.radiance = material.emission();
            tri.doubleSided = material.doubleSided ? 1 : 0;
            if (uniform) {
                const bool secondHalf = !triangles.empty() && triangles.back().patchSize == 1 &&
                                        halvesOfAQuad(triangles.back(), tri);
                if (secondHalf) {
                    triangles.back().patchSize = 2;
                    tri.patchSize = 0;
                }
                triangles.push_back(tri);
                continue;
            }
            tri.firstSample = static_cast<uint32_t>(emitters.samples.size());
            const float sampleArea = tri.area * share;
            for (int sy = 0; sy < strata; ++sy) {
                for (int sx = 0; sx < strata; ++sx) {
                    const vec2 b =
                        sampleUniformTriangle(jitteredStratum(triangleId, 0, strata, sx, sy, lighting::kEmitterJitterSalt));
                    const vec3 Le = emissionAt(scene, mesh, t, b);
                    if (!finite(Le))
                        throw InputError(scene.sourcePath + ": mesh '" + mesh.name + "' triangle " + std::to_string(t) +
                                         " has a non-finite emission");
                    if (!(maxComponent(Le) > 0.0f)) continue;
                    EmitterSample sample;
                    sample.position = ((1.0f - b.x - b.y) * p0 + b.x * p1 + b.y * p2) / h;
                    sample.power = Le * sampleArea;
                    emitters.samples.push_back(sample);
                }
            }
            tri.sampleCount = static_cast<uint32_t>(emitters.samples.size()) - tri.firstSample;
            if (tri.sampleCount > 0) triangles.push_back(tri);
        }
        emitters.triangles.insert(emitters.triangles.end(), triangles.begin(), triangles.end());
    }
    return emitters;
}

int kernelWeighting(NormalWeighting mode) {
    switch (mode) {
    case NormalWeighting::Lambert: return lighting::kWeightLambert;
    case NormalWeighting::Villegas: return lighting::kWeightVillegas;
    case NormalWeighting::SixAxis: return lighting::kWeightSixAxis;
    }
    return lighting::kWeightSixAxis;
}

}  // namespace

const char* toString(NormalWeighting mode) {
    switch (mode) {
    case NormalWeighting::Lambert: return "lambert";
    case NormalWeighting::Villegas: return "villegas";
    case NormalWeighting::SixAxis: return "six-axis";
    }
    return "six-axis";
}

NormalWeighting parseNormalWeighting(const std::string& name) {
    if (name == "lambert") return NormalWeighting::Lambert;
    if (name == "villegas") return NormalWeighting::Villegas;
    if (name == "six-axis") return NormalWeighting::SixAxis;
    throw SettingsError("normal weights '" + name + "': expected lambert, villegas or six-axis");
}

LightingStats lightVoxels(const Scene& scene, VoxelScene& voxels, const LightingSettings& settings, Progress* progress) {
    return lightVoxels(scene, voxels, settings, progress, nullptr);
}

LightingStats lightVoxels(const Scene& scene, VoxelScene& voxels, const LightingSettings& settings, Progress* progress,
                          VoxelKernelRunner runner) {
    const auto start = std::chrono::steady_clock::now();
    validateSettings(scene, settings);
    validateVoxels(voxels);
    const size_t n = voxels.size();
    const float h = static_cast<float>(voxels.voxelSize);

    const std::vector<KernelLight> lights = kernelLights(scene, settings, h);
    const Emitters emitters = emitterSamples(scene, settings.emitterStrata, h);

    LightingStats stats;
    stats.voxels = n;
    stats.lights = lights.size();
    stats.emitterTriangles = emitters.triangles.size();
    stats.emitterSamples = emitters.samples.size();
    voxels.radiance.assign(n, vec3(0.0f));
    voxels.faceRadiance.assign(n, FaceRadiance{});
    voxels.occlusion.assign(n, 0.0f);
    if (n == 0) return stats;

    const auto handle = buildIndexGrid(voxels);
    lighting::LightingView view;
    view.grid = handle.grid<int32_t>();
    if (!view.grid) throw Error("lighting: the index grid could not be built");
    view.coords = voxels.coords.data();
    view.albedo = voxels.albedo.data();
    view.normal = voxels.normal.data();
    view.axisWeights = voxels.axisWeights.front().data();
    view.opacity = voxels.opacity.data();
    view.solid = voxels.solid.data();
    view.surfaceOffset = voxels.surfaceOffset.size() == n ? voxels.surfaceOffset.data() : nullptr;
    view.boundsMin = voxels.coords.front();
    view.boundsMax = voxels.coords.front();
    for (const ivec3& c : voxels.coords) {
        view.boundsMin = glm::min(view.boundsMin, c);
        view.boundsMax = glm::max(view.boundsMax, c);
    }
    view.voxelSize = h;
    view.lights = lights.data();
    view.lightCount = static_cast<uint32_t>(lights.size());
    view.emitters = emitters.triangles.data();
    view.emitterCount = static_cast<uint32_t>(emitters.triangles.size());
    view.emitterSamples = emitters.samples.data();
    view.emitterStrata = settings.emitterStrata;
    view.normalWeighting = kernelWeighting(settings.normalWeights);
    view.visibility = settings.visibility ? 1 : 0;
    const bool hierarchical = settings.traversal == VisibilityTraversal::Hdda;

    const auto store = [&](size_t i, const lighting::VoxelLighting& result) {
        voxels.radiance[i] = result.radiance;
        for (int f = 0; f < 6; ++f) voxels.faceRadiance[i][size_t(f)] = result.faceRadiance[f];
        voxels.occlusion[i] = result.occlusion;
    };
    std::atomic<uint64_t> evaluations{0};
    std::atomic<uint64_t> steps{0};
    auto runnerPass = [&] {
        std::vector<lighting::VoxelLighting> results(n);
        lighting::KernelStats local;
        runner(view, static_cast<uint32_t>(n), hierarchical, results.data(), local);
        for (size_t i = 0; i < n; ++i) {
            store(i, results[i]);
        }
        evaluations += local.evaluations;
        steps += local.steps;
        if (progress) progress->advance(n);
    };
    auto pass = [&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& range) {
            lighting::IndexAccessor accessor = view.grid->getAccessor();
            lighting::KernelStats local;
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const uint32_t index = static_cast<uint32_t>(i);
                const lighting::VoxelLighting result =
                    hierarchical ? lighting::shadeVoxel<true>(view, accessor, index, local)
                                 : lighting::shadeVoxel<false>(view, accessor, index, local);
                store(i, result);
            }
            evaluations += local.evaluations;
            steps += local.steps;
            if (progress) progress->advance(range.size());
        });
    };
    if (runner) {
        runnerPass();
    } else if (settings.threads > 0) {
        tbb::task_arena arena(settings.threads);
        arena.execute(pass);
    } else {
        pass();
    }

    stats.voxelLightEvaluations = evaluations;
    stats.visibilitySteps = steps;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return stats;
}

}  // namespace vl
