#include "gather/gather.h"

#include "core/error.h"
#include "core/progress.h"
#include "gather/bounces.h"
#include "gather/shadowmask.h"
#include "gather/texel_gather.h"
#include "lighting/surface_light.h"

#include <cstdio>
#include <string>
#include <utility>

namespace vl {
namespace {

bool hasPunctualLights(const GatherScene& scene) { return scene.scene.lightCount > 0; }

// The final gather's split of the voxels' light: its bright patches, gathered by shadow rays,
// and, where the records' rays take the lights at their hits, the lights' own reflection.
BrightPatchSplit splitGatherLight(const VoxelScene& voxels, const VoxelSurfacePoints& surfacePoints,
                                  const GatherScene& scene, const GatherSettings& settings, const GatherInputs& inputs) {
    const bool punctual = hasPunctualLights(scene);
    BrightPatchSplit split = splitBrightPatches(voxels, surfacePoints, gatherBrightPatches(settings, inputs, punctual));
    if (takesLightsAtHits(settings, inputs, punctual))
        split.lightsAtHits = punctualFaceRadiance(voxels, surfacePoints, scene.scene, scene.bvh);
    return split;
}

// The final gather's points: one per surface side of each cell at gatherLevel, on the open part
// of their layer (probed by rays), linked over `mips`.
IrradianceCache finalGatherPoints(const VoxelScene& voxels, const RadianceMips& mips, const GatherScene& scene,
                                  const GatherSettings& settings) {
    IrradianceCache cache(voxels, settings.gatherLevel, &scene);
    cache.link(mips.view());
    return cache;
}

}  // namespace

bool gatherNeedsSurfacePoints(const GatherSettings& settings, const GatherInputs& inputs, bool punctualLights) {
    const bool finalGather = settings.gatherLevel >= 0 && inputs.receivers;
    return finalGather && (gatherBrightPatches(settings, inputs, punctualLights).factor > 0.0f ||
                           takesLightsAtHits(settings, inputs, punctualLights));
}

IndirectLight gatherIndirect(VoxelScene& voxels, const VoxelSurfacePoints& surfacePoints, const GatherScene& scene,
                             const GatherSettings& settings, const GatherInputs& inputs, const GatherDevice* device,
                             std::vector<StageTime>& stages) {
    IndirectLight out;
    const bool finalGather = settings.gatherLevel >= 0 && inputs.receivers;
    const bool gathers = settings.bounces > 0 || finalGather;
    // The bounces' points, placed and probed here: the probe of what their rays meet chooses
    // between rays and cones (gather_visibility.h).
    IrradianceCache bouncePoints;
    out.visibility = timed(stages, "visibility", [&] {
        if (gathers) {
            bouncePoints = IrradianceCache(voxels, settings.bounceGatherLevel, &scene);
            return chooseGatherVisibility(settings.visibility, bouncePoints, scene.bvh, scene.scene);
        }
        GatherVisibilityChoice none;
        none.setBy = "nothing gathers (no bounces and no final gather)";
        return none;
    });
    if (!inputs.quiet && gathers) std::fprintf(stderr, "%s\n", describeGatherVisibility(out.visibility).c_str());
    const bool byRays = out.visibility.visibility == GatherVisibility::Rays;

    BounceSettings bounce;
    bounce.bounces = settings.bounces;
    bounce.gatherLevel = settings.bounceGatherLevel;
    bounce.tail = settings.bounceTail ? BounceTail::Geometric : BounceTail::None;
    bounce.cone = bounceConeSettings(settings);
    bounce.byRays = byRays;
    bounce.raysPerAxis = settings.bounceRays;
    bounce.skyDrawsPerAxis = inputs.skyStrata;
    bounce.skyLit = !inputs.voxelsLitByRays;
    Bounced bounced = timed(stages, "bounces", [&] {
        Progress progress("bounces", uint64_t(settings.bounces) * voxels.size(), inputs.quiet);
        return propagateBounces(voxels, bounce, &scene, std::move(bouncePoints), &progress);
    });
    // The bounces' points serve the final gather where they lie at its level.
    const bool reusePoints = bounced.mips.levelCount() > 0 && settings.bounceGatherLevel == settings.gatherLevel;
    out.mips = timed(stages, "mips", [&] {
        if (bounced.mips.levelCount() > 0) return std::move(bounced.mips);
        return buildRadianceMipsFor(voxels, byRays ? MipReaders::RaysOnly : MipReaders::Cones);
    });

    if (finalGather) {
        timed(stages, "gather", [&] {
            // The bright patches leave the light the gather reads (the rays read faces, the
            // cones the mips), and come back after.
            out.bright = splitGatherLight(voxels, surfacePoints, scene, settings, inputs);
            const BrightPatchSplit& split = out.bright;
            const bool relight = !split.patches.empty() && !byRays;
            if (relight) out.mips.relight(voxels, split.restRadiance, split.restFaces);
            IrradianceCache& cache = out.cache;
            cache = reusePoints ? std::move(bounced.points) : finalGatherPoints(voxels, out.mips, scene, settings);
            if (byRays) cache.setRaysPerAxis(settings.gatherRays);
            const MipView mipView = out.mips.view();
            Progress progress("gather", cache.points().size(), inputs.quiet);
            const std::vector<FaceRadiance>& light = split.patches.empty() ? voxels.faceRadiance : split.restFaces;
            // The bounces' rays, when they are the final gather's (the same points and as many
            // rays), are not traced again: their transport maps the cache's points first.
            if (byRays && reusePoints && settings.bounceRays == settings.gatherRays) {
                std::vector<vec3> irradiance = applyTransport(bounced.transport, light);
                irradiance.resize(cache.points().size());
                cache.setIrradiance(std::move(irradiance));
                progress.advance(cache.points().size());
            } else if (byRays)
                cache.setIrradiance(gatherByRays(cache.points(), mipView, light, scene.bvh, scene.scene,
                                                 settings.gatherRays, &progress));
            else if (device)
                cache.setIrradiance(device->gatherCones(cache.points(), mipView, settings.cone, settings.gatherTurns));
            else
                cache.gather(mipView, settings.cone, settings.gatherTurns, &progress);
            if (!split.patches.empty()) {
                std::vector<vec3> irradiance = cache.irradiance();
                const float h = static_cast<float>(voxels.voxelSize);
                std::vector<vec3> origins;  // where each point's gather starts
                if (byRays) {
                    origins = fanOrigins(cache.points(), h, scene.bvh, scene.scene);
                } else {
                    origins.reserve(cache.points().size());  // the cones' apex
                    for (const GatherPoint& point : cache.points())
                        origins.push_back(coneApex(point.position, point.normal, settings.cone, h));
                }
                addBrightPatchIrradiance(cache.points(), origins, split, scene.bvh, settings.brightPatches.samples,
                                         irradiance);
                cache.setIrradiance(std::move(irradiance));
            }
            if (relight) out.mips.relight(voxels, voxels.radiance, voxels.faceRadiance);
            return 0;
        });
    }
    // Receivers with no gather points to interpolate (gather level −1) trace their own cones,
    // through every level of the mips.
    if (out.cache.points().empty()) out.mips.addParentLevels();
    return out;
}

RadianceMips receiverMips(const VoxelScene& voxels, GatherVisibility visibility, bool gathered) {
    const bool byRays = visibility == GatherVisibility::Rays && gathered;
    return buildRadianceMipsFor(voxels, byRays ? MipReaders::RaysOnly : MipReaders::Cones);
}

IndirectLight restoreIndirectLight(const VoxelScene& voxels, const GatherVisibilityChoice& visibility,
                                   const std::vector<vec3>* gathered, const VoxelSurfacePoints& surfacePoints,
                                   const GatherScene& scene, const GatherSettings& settings, const GatherInputs& inputs) {
    IndirectLight out;
    out.visibility = visibility;
    out.mips = receiverMips(voxels, visibility.visibility, gathered != nullptr);
    if (!gathered) return out;
    out.cache = finalGatherPoints(voxels, out.mips, scene, settings);
    if (gathered->size() != out.cache.points().size())
        throw InputError("the final gather holds " + std::to_string(gathered->size()) + " points' light, its voxels give " +
                         std::to_string(out.cache.points().size()) + " points");
    out.cache.setIrradiance(*gathered);
    if (visibility.visibility == GatherVisibility::Rays) out.cache.setRaysPerAxis(settings.gatherRays);
    out.bright = splitGatherLight(voxels, surfacePoints, scene, settings, inputs);
    return out;
}

ReceiverGather::ReceiverGather(const ReceiverScene& tracing, const IndirectLight& light, const GatherSettings& settings,
                               const DirectLightSettings& direct, LightmapSide side, bool quiet,
                               const GatherDevice* device)
    : tracing_(tracing),
      light_(light),
      settings_(settings),
      direct_(direct),
      side_(side),
      quiet_(quiet),
      device_(device),
      mipView_(light.mips.view()),
      cacheView_(light.cache.view(mipView_)),
      gathered_(settings.gatherLevel >= 0 ? &cacheView_ : nullptr) {}

bool ReceiverGather::texelGather() const {
    return settings_.lightmapGather == LightmapGather::Texels && !device_ && gathered_ && gathered_->raysPerAxis > 0;
}

ReceiverLighting ReceiverGather::atlasRows(const LightmapAtlas& given, int rowBegin, int rowEnd) const {
    LightmapAtlas inside;
    if (side_ == LightmapSide::Inside) {
        inside = given;
        orientLightmapSamples(inside.receivers, tracing_.bvh.view(), tracing_.traceScene.view(), tracing_.viewpoints);
    }
    const LightmapAtlas& atlas = side_ == LightmapSide::Inside ? inside : given;
    const SurfaceSampleSet& receivers = atlas.receivers;
    const size_t first = static_cast<size_t>(rowBegin) * static_cast<size_t>(receivers.width);
    const size_t last = static_cast<size_t>(rowEnd) * static_cast<size_t>(receivers.width);
    Progress progress("lightmap " + atlas.name, last - first, quiet_);
    const TraceSceneView scene = tracing_.traceScene.view();
    const BvhView bvh = tracing_.bvh.view();
    // A lightmap leaves out the direct light of the lights an engine draws (LightBake::Indirect,
    // Shadowmask); a shadowmask light's visibility goes into its own image.
    DirectLightSettings baked = direct_;
    baked.engineDrawnLights = false;
    Image shadowmask = shadowmaskTexels(receivers, scene, bvh, first, last);
    ReceiverLighting lit;
    if (device_) {
        // The device lights whole atlases; rows outside the band are cleared.
        lit = device_->shadeReceivers(receivers, scene, bvh, &mipView_, gathered_, settings_.cone, baked, true);
        for (Image* image : {&lit.direct, &lit.indirect, &lit.directRadiance, &lit.indirectRadiance})
            for (size_t k = 0; k < image->pixels.size(); ++k) {
                const size_t element = k / 3;
                if (element < first || element >= last) image->pixels[k] = 0.0f;
            }
        for (size_t element = 0; element < lit.open.pixels.size(); ++element)
            if (element < first || element >= last) lit.open.pixels[element] = 0.0f;
    } else if (texelGather()) {
        // Lights and emitters per sample; the sky and the indirect light from the atlas's own
        // records (texel_gather.h). An image sky's sun casts shadows as sharp as a light's,
        // which the records' lattice and filter would blur: it stays per sample.
        const bool skyInRecords = !scene.sky.hasImage();
        DirectLightSettings direct = baked;
        direct.skyAtSamples = !skyInRecords;
        lit = shadeReceivers(receivers, scene, bvh, nullptr, nullptr, settings_.cone, direct, true, &progress, first, last);
        progress.finish();
        TexelGatherSettings texels;
        texels.spacing = settings_.texelGatherSpacing;
        texels.raysPerAxis = settings_.texelGatherRays;
        texels.seed = uint64_t(settings_.lightmapSeed);
        texels.brightSamples = settings_.brightPatches.samples;
        texels.skyDrawsPerAxis = direct_.skyStrata;
        texels.filterPasses = settings_.lightmapFilterPasses;
        texels.gradients = settings_.lightmapGradients;
        texels.direct = direct_;  // every light: what tells a record is open
        texels.direct.skyAtSamples = false;
        texels.gatherSky = skyInRecords;
        const BrightPatchSplit& bright = light_.bright;
        if (!bright.lightsAtHits.empty()) texels.lightsAtHits = &bright.lightsAtHits;
        // The near field traces a hit's light on from the full faces: not where bright patches
        // took part of their light away (the gather itself needs the lights at hits).
        if (bright.patches.empty()) texels.nearField = settings_.nearFieldVoxels * mipView_.voxelSize;
        const TexelGather gathered =
            gatherAtlasTexels(atlas, rowBegin, rowEnd, &lit.direct, mipView_, bright.restFaces, bright, bvh, scene, texels);
        for (size_t k = 0; k < lit.direct.pixels.size(); ++k) lit.direct.pixels[k] += gathered.sky.pixels[k];
        lit.indirect = gathered.indirect;
        lit.open = gathered.open;
        lit.shadowmask = std::move(shadowmask);
        return lit;  // a lightmap's reflected light (directRadiance, indirectRadiance) is not read
    } else {
        lit = shadeReceivers(receivers, scene, bvh, &mipView_, gathered_, settings_.cone, baked, true, &progress, first,
                             last);
    }
    progress.finish();
    lit.shadowmask = std::move(shadowmask);
    return lit;
}

ReceiverLighting ReceiverGather::cameraSamples(const SurfaceSampleSet& receivers) const {
    Progress progress("image", receivers.elementCount(), quiet_);
    const TraceSceneView scene = tracing_.traceScene.view();
    const BvhView bvh = tracing_.bvh.view();
    const ReceiverLighting lit =
        device_ ? device_->shadeReceivers(receivers, scene, bvh, &mipView_, gathered_, settings_.cone, direct_, false)
                : shadeReceivers(receivers, scene, bvh, &mipView_, gathered_, settings_.cone, direct_, false, &progress);
    progress.finish();
    return lit;
}

}  // namespace vl
