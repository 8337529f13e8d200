#include "bake/bake.h"

#include "bake/voxel_size.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/progress.h"
#include "cuda/launchers.h"
#include "lighting/lighting.h"
#include "lighting/surface_light.h"
#include "lightmap/dilate.h"
#include "lightmap/lightmap_image.h"
#include "scene/own_frame.h"
#include "trace/camera.h"
#include "voxel/voxelize.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <unistd.h>

namespace vl {
namespace {

// Directly seen emitters are sampled on an 8 × 8 grid per pixel (primary rays only): their
// edges are the brightest contrast in an image, and at the pixels' own 2 × 2 they held most of
// its squared error (docs/decisions.md, "Camera images: the emitter's edge").
constexpr int kEmissionSubsamples = 8;

// The sky's rays per surface point of the voxel pass by rays (2 × 2): a voxel side holds about
// four points, so it sees the sky through about 16 rays, which the gathers then average.
constexpr int kVoxelSkyStrata = 2;

double surfaceArea(const Scene& scene) {
    double area = 0.0;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const vec3& a = mesh.positions[mesh.indices[3 * t]];
            const vec3& b = mesh.positions[mesh.indices[3 * t + 1]];
            const vec3& c = mesh.positions[mesh.indices[3 * t + 2]];
            area += 0.5 * glm::length(glm::cross(b - a, c - a));
        }
    return area;
}

// A surface crosses about 1 to √3 voxels per h² of area.
double estimatedVoxels(const Scene& scene, double voxelSize) {
    return 2.0 * surfaceArea(scene) / (voxelSize * voxelSize);
}

std::string real(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", v);
    return text;
}

std::string gib(double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f GiB", bytes / (1024.0 * 1024.0 * 1024.0));
    return text;
}

Image sumRgb(const Image& a, const Image& b) {
    Image out = a;
    for (size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] += b.pixels[i];
    return out;
}

void checkLightAttenuationNames(const Scene& scene, const LightingSettings& lighting) {
    for (const auto& entry : lighting.lightAttenuation) {
        bool found = false;
        for (const Light& light : scene.lights) found = found || light.name == entry.first;
        if (!found)
            throw SettingsError(scene.sourcePath + ": attenuation is set for light '" + entry.first +
                                "', which the scene lacks");
    }
}

}  // namespace

void resolveLightBake(Scene& scene, LightBake setting) {
    std::vector<const Light*> masked;
    for (Light& light : scene.lights) {
        if (light.bake == LightBake::Unset) light.bake = setting;
        light.maskChannel = -1;
        if (light.bake != LightBake::Shadowmask) continue;
        const std::string named = "light '" + light.name + "'";
        for (const Light* earlier : masked)
            if (light.sourceLight >= 0 && earlier->sourceLight == light.sourceLight)
                throw InputError(scene.sourcePath + ": " + named + " (KHR_lights_punctual light " +
                                 std::to_string(light.sourceLight) +
                                 ") is placed by several nodes: a shadowmask channel holds one light's shadows; "
                                 "give it the bake mode \"indirect\" or \"all\"");
        if (masked.size() == size_t(kShadowmaskChannels)) {
            std::string held;
            for (const Light* earlier : masked) held += (held.empty() ? "'" : ", '") + earlier->name + "'";
            throw InputError(scene.sourcePath + ": " + named + " is a fifth shadowmask light; a shadowmask holds " +
                             std::to_string(kShadowmaskChannels) + " (" + held +
                             "): give it the bake mode \"indirect\" or \"all\"");
        }
        light.maskChannel = int(masked.size());
        masked.push_back(&light);
    }
}

double estimateBakeMemory(const Scene& scene, const BakeSettings& settings, double voxelSize) {
    // A voxel costs ~100 bytes of channels, as much again in voxelization fragments, and ~50
    // in mips. A receiver sample costs ~48 bytes, a texel or pixel ~64 per image kept. A
    // triangle ~300: the scene's own, the receivers' BVH and traced scene, and the
    // voxelization's fragments while they last (docs/speed.md, "How the stages scale").
    const double voxels = estimatedVoxels(scene, voxelSize);
    const double triangles = static_cast<double>(scene.triangleCount()) * 300.0;
    const double texels = settings.outputs.lightmaps
        ? settings.lightmap.maxTexels() *
              (48.0 * settings.lightmap.subsamplesPerAxis * settings.lightmap.subsamplesPerAxis + 64.0 * 6)
        : 0.0;
    const double pixels = settings.outputs.images
        ? static_cast<double>(settings.imageWidth) * settings.imageHeight *
              (48.0 * settings.imageSubsamples * settings.imageSubsamples + 64.0 * 8)
        : 0.0;
    return voxels * 250.0 + triangles + texels + pixels;
}

void checkSceneMemoryBudget(const Scene& scene, const BakeSettings& settings, double available) {
    const double estimate = estimateBakeMemory(scene, settings, std::numeric_limits<double>::infinity());
    if (estimate > available)
        throw SettingsError(scene.sourcePath + ": its " + std::to_string(scene.triangleCount()) +
                            " triangles, lightmaps and images alone would need about " + gib(estimate) +
                            " of memory but " + gib(available) +
                            " is available: lower lightmap-res or the image size, or split the scene");
}

void checkMemoryBudget(const Scene& scene, const BakeSettings& settings, double voxelSize) {
    const double estimate = estimateBakeMemory(scene, settings, voxelSize);
    const double voxels = estimatedVoxels(scene, voxelSize);
    const double available = availableMemoryBytes();
    if (estimate > available)
        throw SettingsError(scene.sourcePath + ": this bake would need about " + gib(estimate) + " of memory (" +
                            std::to_string(static_cast<long long>(voxels)) + " voxels at voxel size " +
                            std::to_string(voxelSize) + " m) but " + gib(available) +
                            " is available: lower resolution, lightmap-res or the image size");
}

// The name of the image of generated charts in a scene whose other meshes have their own
// TEXCOORD_1: "lightmap_generated", or with a number where an atlas group has taken that.
std::string generatedAtlasName(const LightmapSettings& settings) {
    const auto taken = [&](const std::string& name) {
        return std::any_of(settings.atlases.begin(), settings.atlases.end(),
                           [&](const AtlasGroup& group) { return group.name == name; });
    };
    std::string name = "lightmap_generated";
    for (int n = 2; taken(name); ++n) name = "lightmap_generated_" + std::to_string(n);
    return name;
}

GeneratedUvs generateSharedAtlasUvs(Scene& scene, const BakeSettings& settings, double voxelSize, Diagnostics& diagnostics) {
    GeneratedUvs out;
    LightmapSettings& lightmap = out.lightmap;
    lightmap = settings.lightmap;
    if (!settings.outputs.lightmaps) return out;
    // A texel size asked (lightmap-texel) or chosen (lightmap-res auto) sizes the atlases of
    // the meshes' own TEXCOORD_1 from their density, and the generated charts' atlas to fit.
    const double autoTexel = kAutoTexelPerVoxel * voxelSize;
    sizeAuthoredAtlases(scene, lightmap, autoTexel, diagnostics);
    // Generated UVs for the meshes of the shared atlas that have none: into the shared atlas
    // where none of its meshes has TEXCOORD_1, else into an image of their own (their charts
    // cannot share another layout's). Meshes of atlas groups, or of one image per mesh, keep
    // what they have.
    const MeshesWithoutUv1 withoutUv1 =
        settings.generateLightmapUvs ? sharedAtlasMeshesWithoutUv1(scene, settings.lightmap) : MeshesWithoutUv1{};
    if (withoutUv1.meshes.empty()) return out;
    AtlasRequest request;
    request.width = settings.lightmap.width;
    request.height = settings.lightmap.height;
    if (settings.lightmap.texelSize > 0.0) {
        request.texelSize = settings.lightmap.texelSize;
    } else if (settings.lightmap.autoResolution) {
        request.texelSize = autoTexel;
        request.maxSide = kMaxAutoAtlasSide;
        request.powerOfTwo = true;
    }
    out.report = generateLightmapUvs(scene, withoutUv1.meshes, request);
    const LightmapUvReport& uvs = *out.report;
    if (!settings.quiet) std::fprintf(stderr, "%s\n", describeLightmapUvs(uvs).c_str());
    out.layouts.resize(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) out.layouts[m].source = scene.meshes[m].source;
    for (const uint32_t m : withoutUv1.meshes)
        out.layouts[m] = {scene.meshes[m].source, scene.meshes[m].uv1, scene.meshes[m].indices};
    if (settings.lightmap.texelSize > 0.0 && uvs.texelSize > settings.lightmap.texelSize * (1.0 + 1e-9))
        diagnostics.warn(scene.sourcePath + ": the generated lightmap UVs' " + std::to_string(uvs.charts) +
                         " charts need more than " + std::to_string(uvs.width) + " x " + std::to_string(uvs.height) +
                         " texels at lightmap-texel " + real(settings.lightmap.texelSize) + " m: they are baked at " +
                         real(uvs.texelSize) + " m per texel");
    if (!uvs.smallCharts.empty()) {
        std::string meshes;
        for (size_t k = 0; k < uvs.smallCharts.size() && k < 5; ++k)
            meshes += (k ? ", " : "") + uvs.smallCharts[k].mesh + " (" + std::to_string(uvs.smallCharts[k].charts) + ")";
        if (uvs.smallCharts.size() > 5) meshes += " and " + std::to_string(uvs.smallCharts.size() - 5) + " more meshes";
        diagnostics.warn(scene.sourcePath + ": " + std::to_string(uvs.smallChartCount()) + " of the generated lightmap UVs' " +
                         std::to_string(uvs.charts) + " charts are under " + real(kSmallChartTexels) + " x " +
                         real(kSmallChartTexels) + " texels at " + real(uvs.texelSize) +
                         " m per texel, and no neighbouring chart could take them: " + meshes +
                         " (bake.json lists them; a larger lightmap-res or a smaller lightmap-texel gives them more)");
    }
    if (withoutUv1.othersHaveUv1) {
        AtlasGroup generated;
        generated.name = generatedAtlasName(lightmap);
        generated.meshIndices = withoutUv1.meshes;
        generated.width = uvs.width;
        generated.height = uvs.height;
        generated.origin = "generated lightmap UVs";
        lightmap.atlases.push_back(generated);
    } else {
        lightmap.width = uvs.width;  // the size asked, or the one sized for a texel size
        lightmap.height = uvs.height;
    }
    return out;
}

VoxelStages bakeVoxelStages(Scene& scene, const BakeSettings& settings, Diagnostics& diagnostics) {
    validateBakeSettings(settings);
    resolveLightBake(scene, settings.lightBake);
    // A volume finer than the probe limit is refused now, not after the lightmaps.
    volumeGrid(worldBox(scene), irradianceVolumeSpacing(scene, settings), scene.sourcePath);
    VoxelStages stages;
    BakeResult& result = stages.result;
    // Into its own frame before anything is sized: a resolution, the free paths' count and
    // the gather cells' alignment are then along the grid's axes.
    if (settings.voxel.ownFrame) turnToOwnFrame(scene);
    // Before the voxel size, whose rays need the scene's BVH: a scene too large for the
    // machine is refused in a moment, not after its slow stages.
    checkSceneMemoryBudget(scene, settings, availableMemoryBytes());
    result.voxelSizeChoice = timed(result.stages, "voxel size", [&] { return chooseVoxelSize(scene, settings); });
    const VoxelSizeChoice& choice = result.voxelSizeChoice;
    VoxelSettings voxelSettings = settings.voxel;
    voxelSettings.voxelSize = choice.voxelSize;
    const double voxelSize = voxelSizeFor(scene, voxelSettings);
    anchorToVoxelGrid(scene, voxelSize);
    checkMemoryBudget(scene, settings, voxelSize);
    if (!settings.quiet)
        std::fprintf(stderr, "%s\n", describeVoxelSize(choice).c_str());
    for (const std::string& warning : choice.warnings) diagnostics.warn(warning);
    checkLightAttenuationNames(scene, settings.lighting);
    if (settings.outputs.lightmaps) checkAtlasGroups(scene, settings.lightmap);
    const auto uvStart = std::chrono::steady_clock::now();
    GeneratedUvs generated = generateSharedAtlasUvs(scene, settings, voxelSize, diagnostics);
    if (generated.report) {
        result.stages.push_back(
            {"lightmap uvs", std::chrono::duration<double>(std::chrono::steady_clock::now() - uvStart).count()});
        result.lightmapUvs = generated.report;
        result.generatedLayouts = std::move(generated.layouts);
    }
    if (generated.report || settings.lightmap.autoResolution || settings.lightmap.texelSize > 0.0) {
        BakeSettings sized = settings;  // the atlases as sized for the charts or the texel size
        sized.lightmap = generated.lightmap;
        checkMemoryBudget(scene, sized, voxelSize);
    }
    stages.lightmap = std::move(generated.lightmap);
    applySkySettings(settings, scene);
    if (scene.lights.empty() && !scene.hasEmitters() && !scene.sky.present())
        diagnostics.warn(scene.sourcePath + ": the scene has no lights, no emissive materials and no sky: the bake is black");

    // Voxel lighting and receiver shading run on the GPU when the settings pick it.
    const bool onGpu = stages.onGpu = cuda::resolveDevice(settings.device, std::cerr);

    result.voxels = timed(result.stages, "voxelize", [&] {
        Progress progress("voxelize", scene.triangleCount(), settings.quiet);
        return voxelize(scene, voxelSettings, &progress);
    });
    stages.tracing = timed(result.stages, "bvh", [&] { return std::make_unique<ReceiverScene>(scene, settings.lightTrees); });
    const TraceSceneView sceneView = stages.tracing->traceScene.view();
    const BvhView bvhView = stages.tracing->bvh.view();
    // Points on the voxels' surfaces: what the voxel pass by rays lights and the final gather's
    // bright patches send from.
    const GatherInputs inputs = gatherInputs(settings);
    const GatherScene gatherScene{bvhView, sceneView};
    const bool needPoints =
        inputs.voxelsLitByRays || gatherNeedsSurfacePoints(settings.gather, inputs, sceneView.lightCount > 0);
    const VoxelSurfacePoints surfacePoints = timed(result.stages, "surface points", [&] {
        return needPoints ? voxelSurfacePoints(result.voxels, sceneView, settings.lighting.surfacePoints)
                          : VoxelSurfacePoints{};
    });
    timed(result.stages, "voxel light", [&] {
        Progress progress("voxel light", result.voxels.size(), settings.quiet);
        if (inputs.voxelsLitByRays) {
            lightVoxelsByRays(result.voxels, surfacePoints, sceneView, bvhView, kVoxelSkyStrata, &progress);
            return 0;
        }
        if (onGpu) cuda::lightVoxelsCuda(scene, result.voxels, settings.lighting);
        else lightVoxels(scene, result.voxels, settings.lighting, &progress);
        return 0;
    });
    stages.indirect = gatherIndirect(result.voxels, surfacePoints, gatherScene, settings.gather, inputs,
                                     onGpu ? &cuda::gatherDevice() : nullptr, result.stages);
    result.gatherVisibility = stages.indirect.visibility;
    result.gatherPoints = stages.indirect.cache.points().size();
    result.brightPatches = stages.indirect.bright.patches.size();
    return stages;
}

std::vector<Camera> bakeCameras(const Scene& scene, const BakeSettings& settings) {
    std::vector<Camera> cameras = scene.cameras;
    const float aspect = static_cast<float>(settings.imageWidth) / static_cast<float>(settings.imageHeight);
    if (cameras.empty()) {
        // Framed in the world's orientation, as `voxlight reference` and the bench frame it:
        // the bake has turned the scene into its own frame (scene/own_frame.h).
        const glm::mat3 toWorld(scene.frame), toLocal = glm::transpose(toWorld);
        Aabb box;
        for (const Mesh& mesh : scene.meshes)
            for (const vec3& p : mesh.positions) box.extend(toWorld * p);
        Camera camera = defaultCamera(box, aspect);
        camera.position = toLocal * camera.position;
        camera.forward = toLocal * camera.forward;
        camera.up = toLocal * camera.up;
        cameras.push_back(camera);
    }
    return cameras;
}

CameraReceivers bakeCameraReceivers(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                                    const BakeSettings& settings) {
    return buildCameraReceivers(scene, bvh, camera, settings.imageSubsamples, kEmissionSubsamples, true);
}

Image bakeLightmapImage(const TraceScene& trace, const Bvh& bvh, const CameraModel& camera, const Scene& scene,
                        const SceneTriangles& triangles, const BakeSettings& settings,
                        const std::vector<ShippedLightmap>& lightmaps) {
    return renderLightmapImage(bakeCameraReceivers(trace, bvh, camera, settings), trace, bvh, camera,
                               settings.lightmapImageSubsamples, scene, triangles, lightmaps);
}

ReceiverGather bakeReceiverGather(const ReceiverScene& tracing, const IndirectLight& light, const BakeSettings& settings,
                                  bool onGpu) {
    return ReceiverGather(tracing, light, settings.gather, settings.direct, settings.lightmapSide, settings.quiet,
                          onGpu ? &cuda::gatherDevice() : nullptr);
}

BakedImage bakeCameraImage(const ReceiverGather& gather, const ReceiverScene& tracing, const Camera& camera,
                           const BakeSettings& settings) {
    const CameraModel model = makeCameraModel(camera, settings.imageWidth, settings.imageHeight);
    const CameraReceivers receivers = bakeCameraReceivers(tracing.traceScene, tracing.bvh, model, settings);
    const ReceiverLighting lit = gather.cameraSamples(receivers.receivers);
    return {camera.name, sumRgb(sumRgb(receivers.emission, lit.directRadiance), lit.indirectRadiance),
            lit.directRadiance, lit.indirectRadiance, receivers.albedo, Image()};
}

BakedLightmap finishLightmap(const LightmapAtlas& atlas, const Image& direct, const Image& indirect, const Image& open,
                             const Scene& scene, const BakeSettings& settings, const Image& shadowmask) {
    BakedLightmap baked{atlas.name, Image(), direct, indirect, atlas.mask, atlas.coveredTexels, 0, atlas.meshes, {}, shadowmask};
    if (!shadowmask.empty() && (shadowmask.width != atlas.mask.width || shadowmask.height != atlas.mask.height ||
                                shadowmask.channels != kShadowmaskChannels))
        throw Error("finishLightmap: the shadowmask is not the atlas's size, or not RGBA");
    if (!open.pixels.empty()) {
        const SurfaceSampleSet& set = atlas.receivers;
        if (open.width != set.width || open.height != set.height)
            throw Error("finishLightmap: the open samples' weights are not the atlas's size");
        for (size_t texel = 0; texel < set.elementCount(); ++texel) {
            if (set.sampleCount(texel) == 0) continue;
            float weight = 0.0f;  // summed as the shading sums its open samples' weights
            for (uint32_t k = set.begin[texel]; k < set.begin[texel + 1]; ++k) weight += set.samples[k].weight;
            const float shown = open.pixels[texel];
            if (!(shown < weight)) continue;
            const float scale = shown > 0.0f ? weight / shown : 0.0f;
            for (int c = 0; c < 3; ++c) {
                baked.direct.pixels[3 * texel + size_t(c)] *= scale;
                baked.indirect.pixels[3 * texel + size_t(c)] *= scale;
            }
            // A shadowmask texel is a ratio over its facing samples: only a buried one changes,
            // to be filled from its neighbours.
            if (!baked.shadowmask.empty() && !(shown > 0.0f))
                for (size_t c = 0; c < size_t(kShadowmaskChannels); ++c)
                    baked.shadowmask.pixels[size_t(kShadowmaskChannels) * texel + c] = kShadowmaskUnseen;
            if (shown > 0.0f) continue;
            baked.mask.pixels[texel] = 0.0f;
            ++baked.buriedTexels;
        }
    }
    baked.total = sumRgb(baked.direct, baked.indirect);
    // Padding texels (and buried ones) take their neighbours' values, so bilinear filtering at
    // chart edges does not bleed black.
    for (Image* image : {&baked.total, &baked.direct, &baked.indirect}) dilatePadding(*image, baked.mask);
    if (!baked.shadowmask.empty()) fillUnseenShadowmask(baked.shadowmask, baked.mask);
    baked.seams = finishLightmapSeams(scene, atlas.meshes, baked.mask, baked.direct, baked.indirect, baked.total,
                                      settings.lightmapStitch, &baked.shadowmask);
    return baked;
}

bool makesLightmapImages(const BakeSettings& settings) {
    return settings.outputs.lightmapImage && settings.outputs.lightmaps && settings.outputs.images;
}

void addLightmapImages(const Scene& scene, const ReceiverScene& tracing, const BakeSettings& settings,
                       BakeResult& result) {
    std::vector<ShippedLightmap> shipped;
    for (const BakedLightmap& lightmap : result.lightmaps)
        shipped.push_back({lightmap.meshes, shippedLightmapTexels(lightmap.total), shippedShadowmask(lightmap.shadowmask)});
    const std::vector<Camera> cameras = bakeCameras(scene, settings);
    for (size_t c = 0; c < cameras.size() && c < result.images.size(); ++c) {
        const CameraModel model = makeCameraModel(cameras[c], settings.imageWidth, settings.imageHeight);
        result.images[c].lightmapped =
            bakeLightmapImage(tracing.traceScene, tracing.bvh, model, scene, tracing.triangles, settings, shipped);
    }
}

double irradianceVolumeSpacing(const Scene& scene, const BakeSettings& settings) {
    if (!lightsVolume(settings) || settings.irradianceVolume.spacing == 0.0) return 0.0;
    if (settings.irradianceVolume.spacing > 0.0) return settings.irradianceVolume.spacing;
    const WorldBox box = worldBox(scene);
    if (box.empty()) return 0.0;
    const glm::dvec3 size = box.hi - box.lo;
    const double longest = std::max({size.x, size.y, size.z});
    if (!(longest > 0.0)) return kAutoVolumeSpacing;
    // Coarser by 10% at a time until the grid holds kAutoVolumeProbes or fewer.
    double spacing = std::min(kAutoVolumeSpacing, longest / kAutoVolumeProbesAlong);
    while (volumeProbeCount(box, spacing) > kAutoVolumeProbes) spacing *= 1.1;
    return spacing;
}

void addIrradianceVolume(const Scene& scene, const ReceiverScene& tracing, const ReceiverGather& gather,
                         const BakeSettings& settings, BakeResult& result) {
    IrradianceVolumeSettings volume = settings.irradianceVolume;
    volume.spacing = irradianceVolumeSpacing(scene, settings);
    if (!(volume.spacing > 0.0)) return;
    timed(result.stages, "irradiance volume", [&] {
        result.volume = bakeIrradianceVolume(scene, tracing, gather, volume, settings.quiet);
        return 0;
    });
}

BakeResult bake(Scene scene, const BakeSettings& settings, Diagnostics& diagnostics) {
    VoxelStages stages = bakeVoxelStages(scene, settings, diagnostics);
    BakeResult& result = stages.result;
    const ReceiverGather receivers = bakeReceiverGather(*stages.tracing, stages.indirect, settings, stages.onGpu);
    if (settings.outputs.lightmaps) {
        timed(result.stages, "lightmaps", [&] {
            for (const LightmapAtlas& atlas : buildLightmapReceivers(scene, stages.lightmap, diagnostics)) {
                const ReceiverLighting lit = receivers.atlasRows(atlas, 0, atlas.receivers.height);
                result.lightmaps.push_back(
                    finishLightmap(atlas, lit.direct, lit.indirect, lit.open, scene, settings, lit.shadowmask));
            }
            return 0;
        });
    }
    if (settings.outputs.images) {
        timed(result.stages, "images", [&] {
            for (const Camera& camera : bakeCameras(scene, settings))
                result.images.push_back(bakeCameraImage(receivers, *stages.tracing, camera, settings));
            return 0;
        });
    }
    if (makesLightmapImages(settings))
        timed(result.stages, "lightmap image", [&] {
            addLightmapImages(scene, *stages.tracing, settings, result);
            return 0;
        });
    addIrradianceVolume(scene, *stages.tracing, receivers, settings, result);
    result.mips = std::move(stages.indirect.mips);
    return std::move(result);
}

}  // namespace vl
