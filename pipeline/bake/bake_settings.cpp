#include "bake/bake_settings.h"

#include "gather/irradiance_cache.h"
#include "core/error.h"
#include "core/text.h"
#include "scene/scene.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <utility>

namespace vl {
const SettingsTable<BakeSettings>& bakeSettingsTable() {
    using S = BakeSettings;
    static const SettingsTable<BakeSettings> table = {
        // Voxelization
        {"resolution", "voxels along the scene's longest axis (default: chosen from the scene, see bake.json)",
         [](S& s, const std::string& v) { s.voxel.resolution = parseIntSetting("resolution", v, 1, 1 << 21); }},
        {"voxel-size", "voxel edge in metres; overrides resolution (default: chosen from the scene)",
         [](S& s, const std::string& v) { s.voxel.voxelSize = parseRealSetting("voxel-size", v, 1e-9, 1e9); }},
        {"fill-interior", "mark voxels inside closed meshes solid (default false)",
         [](S& s, const std::string& v) { s.voxel.fillInterior = parseBoolSetting("fill-interior", v); }},
        {"grid-frame", "the voxel grid's axes: own (along the scene's walls, its own frame) or world (default own)",
         [](S& s, const std::string& v) {
             if (v != "own" && v != "world")
                 throw SettingsError("setting grid-frame = '" + v + "' is not one of own, world");
             s.voxel.ownFrame = v == "own";
         }},
        {"texel-samples", "texture samples per axis over each voxel's surface piece (default 4)",
         [](S& s, const std::string& v) { s.voxel.texelSamples = parseIntSetting("texel-samples", v, 1, 64); }},
        // Voxel direct lighting
        {"normal-weights", "voxel normal weighting: lambert, villegas or six-axis (default lambert)",
         [](S& s, const std::string& v) { s.lighting.normalWeights = parseNormalWeighting(v); }},
        {"attenuation", "K_c,K_l,K_q of the paper's eq. 18 for every punctual light (default: glTF inverse square)",
         [](S& s, const std::string& v) {
             AttenuationCoefficients k;
             char c1 = 0, c2 = 0;
             std::istringstream in(v);
             if (!(in >> k.constant >> c1 >> k.linear >> c2 >> k.quadratic) || c1 != ',' || c2 != ',' ||
                 !(in >> std::ws).eof())
                 throw SettingsError("setting attenuation: '" + v + "' is not K_c,K_l,K_q");
             if (!(k.constant >= 0 && k.linear >= 0 && k.quadratic >= 0) ||
                 !(k.constant + k.linear + k.quadratic > 0) || !std::isfinite(k.constant + k.linear + k.quadratic))
                 throw SettingsError("setting attenuation: coefficients must be finite, non-negative, not all zero");
             s.lighting.attenuation = k;
         }},
        {"voxel-visibility", "how the voxel pass finds shadows: rays (against the triangles, from points on each voxel's surface) or stepping (the paper's walk through the voxels, eq. 17) (default rays)",
         [](S& s, const std::string& v) {
             if (v != "rays" && v != "stepping")
                 throw SettingsError("setting voxel-visibility = '" + v + "' is not one of rays, stepping");
             s.lighting.visibilityBy = v == "rays" ? VoxelVisibility::Rays : VoxelVisibility::Stepping;
         }},
        {"voxel-light-points", "with voxel-visibility rays: surface points per voxel face's area that the voxel pass lights (default 4)",
         [](S& s, const std::string& v) { s.lighting.surfacePoints = parseIntSetting("voxel-light-points", v, 1, 256); }},
        {"voxel-emitter-strata", "n × n visibility points per emissive quad or triangle and voxel in the voxel lighting pass (default 1)",
         [](S& s, const std::string& v) { s.lighting.emitterStrata = parseIntSetting("voxel-emitter-strata", v, 1, 32); }},
        {"hdda", "skip empty space with NanoVDB's HDDA when stepping toward lights (default true)",
         [](S& s, const std::string& v) {
             s.lighting.traversal = parseBoolSetting("hdda", v) ? VisibilityTraversal::Hdda : VisibilityTraversal::Dda;
         }},
        // Cone tracing
        {"cones", "cones per hemisphere of the receivers' final gather: 6, 16 or 32 (default 32)",
         [](S& s, const std::string& v) { s.gather.cone.coneCount = parseIntSetting("cones", v, 1, 64); }},
        {"aperture", "cone half-angle in degrees; 0 = the cone set's tiling angle (default 0)",
         [](S& s, const std::string& v) { s.gather.cone.apertureDegrees = static_cast<float>(parseRealSetting("aperture", v, 0, 89.9)); }},
        {"cone-offset", "cone start offset along the normal, in voxels (default 1.5)",
         [](S& s, const std::string& v) { s.gather.cone.startOffset = static_cast<float>(parseRealSetting("cone-offset", v, 0, 16)); }},
        {"step-factor", "cone step as a fraction of its diameter (default 0.5)",
         [](S& s, const std::string& v) { s.gather.cone.stepFactor = static_cast<float>(parseRealSetting("step-factor", v, 0.05, 4)); }},
        {"cone-max-distance", "metres a cone marches at most; 0 = until opaque or out of the grid (default 0)",
         [](S& s, const std::string& v) { s.gather.cone.maxDistance = static_cast<float>(parseRealSetting("cone-max-distance", v, 0, 1e9)); }},
        {"bounces", "voxel-to-voxel bounces before the final gather (default 24)",
         [](S& s, const std::string& v) { s.gather.bounces = parseIntSetting("bounces", v, 0, 1024); }},
        {"bounce-cones", "cones per hemisphere of the voxel-to-voxel bounces: 6, 16 or 32 (default 6)",
         [](S& s, const std::string& v) { s.gather.bounceCones = parseIntSetting("bounce-cones", v, 1, 64); }},
        {"bounce-tail", "add the rest of the bounce series as a geometric tail after the last bounce (default true)",
         [](S& s, const std::string& v) { s.gather.bounceTail = parseBoolSetting("bounce-tail", v); }},
        {"gather-level", "receivers interpolate irradiance gathered once per surface side of each block of 2^n voxels; -1: every sample gathers its own cones (default 2)",
         [](S& s, const std::string& v) { s.gather.gatherLevel = parseIntSetting("gather-level", v, -1, kMaxCacheLevel); }},
        {"gather-turns", "cone sets traced per gather point of the final gather, each turned by 1/n turn (default 2)",
         [](S& s, const std::string& v) { s.gather.gatherTurns = parseIntSetting("gather-turns", v, 1, kMaxGatherTurns); }},
        {"bright-patches", "faces brighter than this many times the mean face are gathered by shadow rays at the gather points, not by cones; 0: none; off in a scene with punctual lights under hit-light exact (default 8)",
         [](S& s, const std::string& v) { s.gather.brightPatches.factor = static_cast<float>(parseRealSetting("bright-patches", v, 0, 1e6)); }},
        {"bright-patch-cell", "voxels per axis of the cells whose bright faces merge into one patch (default 8)",
         [](S& s, const std::string& v) { s.gather.brightPatches.cellVoxels = parseIntSetting("bright-patch-cell", v, 1, 1024); }},
        {"bright-patch-samples", "shadow-ray samples of the bright patches per gather point (default 64)",
         [](S& s, const std::string& v) { s.gather.brightPatches.samples = parseIntSetting("bright-patch-samples", v, 1, 4096); }},
        {"bright-patch-max", "most bright patches, the most powerful first (default 256, at most 1024)",
         [](S& s, const std::string& v) { s.gather.brightPatches.maxPatches = parseIntSetting("bright-patch-max", v, 0, 1024); }},
        {"gather-visibility", "what a gather point sees by: rays (against the triangles, reading the mips where they hit), cones (the mips' opacity) or auto (rays unless the scene's rays see the backs of single-sided surfaces) (default auto)",
         [](S& s, const std::string& v) { s.gather.visibility = parseGatherVisibility(v); }},
        {"gather-rays", "rays per axis of each final-gather point's n x n fan when gathering by rays; as many as bounce-rays reuse the bounces' rays (default 14)",
         [](S& s, const std::string& v) { s.gather.gatherRays = parseIntSetting("gather-rays", v, 1, kMaxGatherRaysPerAxis); }},
        {"bounce-rays", "rays per axis of each bounce gather point's n x n fan when gathering by rays, traced once for all bounces (default 14)",
         [](S& s, const std::string& v) { s.gather.bounceRays = parseIntSetting("bounce-rays", v, 1, kMaxGatherRaysPerAxis); }},
        {"bounce-gather-level", "voxels interpolate bounce light gathered once per surface side of each block of 2^n voxels (default 2)",
         [](S& s, const std::string& v) { s.gather.bounceGatherLevel = parseIntSetting("bounce-gather-level", v, 0, kMaxCacheLevel); }},
        // Receivers
        {"materials", "authored (as the glTF gives them) or lambert (every material diffuse, metallic 0 and no transmission, its base colour kept) (default authored)",
         [](S& s, const std::string& v) {
             if (v != "authored" && v != "lambert")
                 throw SettingsError("setting materials = '" + v + "' is not one of authored, lambert");
             s.lambertMaterials = v == "lambert";
         }},
        {"light-bake", "what the lightmaps hold of each point, spot and directional light without a bake mode of its own: all (its direct and indirect light), indirect (its indirect light alone; the engine draws its direct light, and image_lightmapped draws it exactly per read) or shadowmask (as indirect, plus its visibility per texel in a channel of the atlas's shadowmask image, four lights at most; the engine draws its unshadowed direct light times the mask) (default all)",
         [](S& s, const std::string& v) {
             if (!parseLightBake(v, s.lightBake))
                 throw SettingsError("setting light-bake = '" + v + "' is not one of all, indirect, shadowmask");
         }},
        {"irradiance-volume", "metres between the probes of the irradiance volume scene.glb carries, which lights what moves through the scene (docs/irradiance-volume.md); off: none; auto: 0.5 m, finer where the scene's longest side would hold fewer than 8 probes, coarser where more than 32768 would cover it (default auto)",
         [](S& s, const std::string& v) {
             if (v == "auto") s.irradianceVolume.spacing = -1.0;
             else if (v == "off") s.irradianceVolume.spacing = 0.0;
             else s.irradianceVolume.spacing = parseRealSetting("irradiance-volume", v, 0.001, 1e6);
         }},
        {"lightmap-gather", "where lightmaps gather their indirect light: texels (records on the atlas's own texels) or points (the voxel gather points images use); texels needs gather-visibility rays (default texels)",
         [](S& s, const std::string& v) {
             if (v != "texels" && v != "points")
                 throw SettingsError("setting lightmap-gather = '" + v + "' is not one of texels, points");
             s.gather.lightmapGather = v == "texels" ? LightmapGather::Texels : LightmapGather::Points;
         }},
        {"texel-gather-spacing", "texels between a lightmap's gather records; 0: about 0.6 voxels (default 0)",
         [](S& s, const std::string& v) { s.gather.texelGatherSpacing = parseIntSetting("texel-gather-spacing", v, 0, 64); }},
        {"texel-gather-rays", "rays per axis of each lightmap gather record's n x n fan; 0: 8 (default 0)",
         [](S& s, const std::string& v) { s.gather.texelGatherRays = parseIntSetting("texel-gather-rays", v, 0, kMaxGatherRaysPerAxis); }},
        {"lightmap-seed", "turns the lightmap records' rays and draws: two bakes at two seeds differ by the lightmap's noise (default 0)",
         [](S& s, const std::string& v) { s.gather.lightmapSeed = parseIntSetting("lightmap-seed", v, 0, 1 << 30); }},
        {"lightmap-side", "which side of a double-sided surface its lightmap texels hold: inside (the side that sees less open sky, what a person in the room sees, never the inside of a closed solid, and a side facing the open space the scene's cameras stand in is never taken for one; a thin window frame whose front faces out is lit from the room) or front (the triangles' winding) (default inside)",
         [](S& s, const std::string& v) { s.lightmapSide = parseLightmapSide(v); }},
        {"lightmap-filter", "passes of the edge-stopping filter over a lightmap's gather records, each twice as wide (records one surface holds, whose difference their noise explains, are averaged); 0: off (default 3)",
         [](S& s, const std::string& v) { s.gather.lightmapFilterPasses = parseIntSetting("lightmap-filter", v, 0, 5); }},
        {"lightmap-res", "lightmap atlas width and height in texels, exactly (generated UVs get the texel size that fits them); auto: the bake sizes each atlas, the smallest power-of-two square that holds it at texels of half a voxel or finer, up to 4096 (default 256)",
         [](S& s, const std::string& v) {
             if (v == "auto") {
                 s.lightmap.autoResolution = true;
                 return;
             }
             char* end = nullptr;
             errno = 0;
             const long long n = std::strtoll(v.c_str(), &end, 10);
             if (v.empty() || *end != '\0' || errno == ERANGE)
                 throw SettingsError("setting lightmap-res: '" + v + "' is neither a number of texels nor auto");
             if (n < 1 || n > kMaxLightmapResolution)
                 throw SettingsError("setting lightmap-res = " + v + " is out of range [1, " +
                                     std::to_string(kMaxLightmapResolution) + "] (or auto)");
             s.lightmap.width = s.lightmap.height = static_cast<int>(n);
             s.lightmap.autoResolution = false;
         }},
        {"lightmap-texel", "metres per lightmap texel: each atlas the smallest square (a multiple of 4 texels a side, up to 8192) that holds its charts at it; overrides lightmap-res; 0: none (default 0)",
         [](S& s, const std::string& v) {
             char* end = nullptr;
             const double texel = std::strtod(v.c_str(), &end);
             if (v.empty() || *end != '\0' || !std::isfinite(texel))
                 throw SettingsError("setting lightmap-texel: '" + v + "' is not a number of metres");
             if (texel < 0.0 || (texel > 0.0 && texel < 1e-6) || texel > 1e6)
                 throw SettingsError("setting lightmap-texel = " + v +
                                     " must be a texel size in metres from 1e-6 to 1e6 (or 0: none)");
             s.lightmap.texelSize = texel;
         }},
        {"hit-light", "how a lightmap record's ray that hits a surface takes the punctual lights' light there: voxels (its voxel's face light, which a shaded point shares with a sunlit one beside it in the same voxel) or exact (a shadow ray from the hit point, with voxel-visibility rays; in a scene with punctual lights the bright patches are then off) (default exact)",
         [](S& s, const std::string& v) {
             if (v != "voxels" && v != "exact") throw SettingsError("setting hit-light = '" + v + "' is not one of voxels, exact");
             s.gather.hitLightExact = v == "exact";
         }},
        {"many-lights", "how a scene of more than 64 point lights or emissive triangles is lit: tree (each receiver and voxel takes a cut of a tree of the lights: the near and bright ones exact, the far ones sampled by importance, unbiased) or each (every receiver visits every light) (default tree)",
         [](S& s, const std::string& v) {
             if (v != "tree" && v != "each") throw SettingsError("setting many-lights = '" + v + "' is not one of tree, each");
             s.lightTrees = v == "tree";
         }},
        {"near-field", "a lightmap record's ray that hits a surface nearer than this many voxels traces the light there on, by a path of cosine rays, instead of reading the voxel, which a crease narrower than a voxel shares with the open surface beside it; 0: every hit reads its voxel (default 3)",
         [](S& s, const std::string& v) { s.gather.nearFieldVoxels = static_cast<float>(parseRealSetting("near-field", v, 0, 64)); }},
        {"lightmap-gradients", "a lightmap's texels take their gather records' light turned to their own normal by the records' rotation gradients, seen by the records' own rays (Ward and Heckbert's): a curved cushion's or a moulding's texels face a little away from their records (default true)",
         [](S& s, const std::string& v) { s.gather.lightmapGradients = parseBoolSetting("lightmap-gradients", v); }},
        {"lightmap-stitch", "stitch lightmap chart seams: where one surface is split between two charts, move the texels on both sides by a small least-squares solve so they read one value on the split itself (default true)",
         [](S& s, const std::string& v) { s.lightmapStitch = parseBoolSetting("lightmap-stitch", v); }},
        {"lightmap-subsamples", "n × n sub-texel probes per texel (default 4)",
         [](S& s, const std::string& v) { s.lightmap.subsamplesPerAxis = parseIntSetting("lightmap-subsamples", v, 1, 8); }},
        {"light-cut", "past 64 point lights or emissive triangles: how many nodes of each tree of lights a receiver sample takes, the near and bright ones alone and exact, the rest one light drawn by importance (default 64)",
         [](S& s, const std::string& v) { s.direct.lightCut = parseIntSetting("light-cut", v, 1, kMaxLightCut); }},
        {"emitter-strata", "n × n shadow points per emissive triangle for the exact direct term, ⌈n√2⌉² per parallelogram quad (default 4)",
         [](S& s, const std::string& v) { s.direct.emitterStrata = parseIntSetting("emitter-strata", v, 1, 64); }},
        {"sky", "a uniform sky's radiance R,G,B in W/(m²·sr), seen wherever the scene does not block it (default 0: none)",
         [](S& s, const std::string& v) {
             vec3 radiance(0.0f);
             std::istringstream in(v);
             bool read = static_cast<bool>(in >> radiance.x);
             if (v.find(',') == std::string::npos) {
                 radiance = vec3(radiance.x);
             } else {
                 char c1 = 0, c2 = 0;
                 read = read && (in >> c1 >> radiance.y >> c2 >> radiance.z) && c1 == ',' && c2 == ',';
             }
             if (!read || !(in >> std::ws).eof())
                 throw SettingsError("setting sky: '" + v + "' is not R,G,B (or one value for all three)");
             if (!isFinite(radiance) || glm::min(radiance.x, glm::min(radiance.y, radiance.z)) < 0.0f ||
                 glm::max(radiance.x, glm::max(radiance.y, radiance.z)) > 1e9f)
                 throw SettingsError("setting sky: '" + v + "' must be finite, non-negative and at most 1e9");
             s.sky = radiance;
         }},
        {"sky-image", "an equirectangular HDR image (.hdr, .exr) of the sky, mapped as Blender maps it, added to `sky` (default: none)",
         [](S& s, const std::string& v) { s.skyImage = v; }},
        {"sky-rotation", "degrees the sky image turns about +Y, counterclockwise seen from above (default 0)",
         [](S& s, const std::string& v) { s.skyRotation = static_cast<float>(parseRealSetting("sky-rotation", v, -360.0, 360.0)); }},
        {"sky-intensity", "scale of the sky image's radiance (default 1)",
         [](S& s, const std::string& v) { s.skyIntensity = static_cast<float>(parseRealSetting("sky-intensity", v, 0.0, 1e6)); }},
        {"sky-strata", "n × n directions per receiver sample that look for the sky, and as many drawn from its image (default 10)",
         [](S& s, const std::string& v) { s.direct.skyStrata = parseIntSetting("sky-strata", v, 1, 64); }},
        {"width", "image width in pixels (default 256)",
         [](S& s, const std::string& v) { s.imageWidth = parseIntSetting("width", v, 1, 16384); }},
        {"height", "image height in pixels (default 256)",
         [](S& s, const std::string& v) { s.imageHeight = parseIntSetting("height", v, 1, 16384); }},
        {"image-subsamples", "n × n primary rays per pixel (default 2)",
         [](S& s, const std::string& v) { s.imageSubsamples = parseIntSetting("image-subsamples", v, 1, 16); }},
        // Outputs
        {"lightmaps", "write lightmaps (default true)",
         [](S& s, const std::string& v) { s.outputs.lightmaps = parseBoolSetting("lightmaps", v); }},
        {"images", "write camera images (default true)",
         [](S& s, const std::string& v) { s.outputs.images = parseBoolSetting("images", v); }},
        {"lightmap-image", "write image_lightmapped.exr and .png: each camera lit by its lightmaps as scene.glb carries them, albedo x lightmap + emission, as the viewer shows it; needs lightmaps and images (default true)",
         [](S& s, const std::string& v) { s.outputs.lightmapImage = parseBoolSetting("lightmap-image", v); }},
        {"lightmap-image-subsamples", "n x n primary rays per pixel of image_lightmapped, each reading the lightmap at its own hit and averaged over the pixel, as the Cycles references filter theirs; 1: one read at the pixel's centre, as the viewer's page at the image's size (default 4)",
         [](S& s, const std::string& v) { s.lightmapImageSubsamples = parseIntSetting("lightmap-image-subsamples", v, 1, 16); }},
        {"grids", "write grids.vdb (default true)",
         [](S& s, const std::string& v) { s.outputs.grids = parseBoolSetting("grids", v); }},
        {"lightmap-uvs", "generate TEXCOORD_1 charts for a scene none of whose meshes has one (default true)",
         [](S& s, const std::string& v) { s.generateLightmapUvs = parseBoolSetting("lightmap-uvs", v); }},
        {"gltf", "write scene.glb, the scene with its lightmaps attached (MOZ_lightmap, RGBM PNG) (default true)",
         [](S& s, const std::string& v) { s.outputs.gltf = parseBoolSetting("gltf", v); }},
        // Input
        {"files-outside-scene",
         "read buffers and images whose glTF uri leaves the scene's folder (../, absolute paths, links out) (default false)",
         [](S& s, const std::string& v) { s.filesOutsideScene = parseBoolSetting("files-outside-scene", v); }},
        // Device
        {"device", "cpu, cuda or auto (the GPU when one is usable, else the CPU with a message) (default cpu)",
         [](S& s, const std::string& v) { s.device = cuda::parseDeviceChoice(v); }},
    };
    return table;
}

bool lightsVolume(const BakeSettings& s) {
    return s.outputs.gltf && s.gather.gatherLevel >= 0 && (s.outputs.lightmaps || s.outputs.images);
}

void validateBakeSettings(const BakeSettings& s) {
    s.lightmap.validate();
    if (s.voxel.resolution < 0)  // 0: chosen from the scene
        throw SettingsError("setting resolution = " + std::to_string(s.voxel.resolution) + " must be at least 1");
    if (s.voxel.voxelSize < 0.0 || !std::isfinite(s.voxel.voxelSize))
        throw SettingsError("setting voxel-size = " + numberText(s.voxel.voxelSize) + " must be positive and finite");
    validateGatherSettings(s.gather);
    if (s.irradianceVolume.spacing > 0.0 && !lightsVolume(s))
        throw SettingsError("setting irradiance-volume = " + numberText(s.irradianceVolume.spacing) +
                            " needs the final gather the lightmaps and images read (gather-level 0 or more, and "
                            "lightmaps or images on): give irradiance-volume off");
    if (s.direct.emitterStrata < 1 || s.direct.emitterStrata > 64)
        throw SettingsError("setting emitter-strata = " + std::to_string(s.direct.emitterStrata) + " is outside 1..64");
    if (s.direct.skyStrata < 1 || s.direct.skyStrata > 64)
        throw SettingsError("setting sky-strata = " + std::to_string(s.direct.skyStrata) + " is outside 1..64");
    if (s.direct.lightCut < 1 || s.direct.lightCut > kMaxLightCut)
        throw SettingsError("setting light-cut = " + std::to_string(s.direct.lightCut) + " is outside 1.." +
                            std::to_string(kMaxLightCut));
    if (s.lighting.visibilityBy == VoxelVisibility::Rays &&
        (s.lighting.attenuation || !s.lighting.lightAttenuation.empty()))
        throw SettingsError("setting attenuation: the paper's eq. 18 falloff is the stepping pass's; the receivers and "
                            "voxel-visibility rays light by inverse square: add voxel-visibility stepping to use it");
}

GatherInputs gatherInputs(const BakeSettings& settings) {
    GatherInputs inputs;
    inputs.receivers = settings.outputs.lightmaps || settings.outputs.images;
    inputs.voxelsLitByRays = settings.lighting.visibilityBy == VoxelVisibility::Rays;
    inputs.skyStrata = settings.direct.skyStrata;
    inputs.quiet = settings.quiet;
    return inputs;
}

std::string describeBakeSettings(const BakeSettings& s) {
    std::ostringstream out;
    out << "resolution=" << (s.voxel.resolution > 0 ? std::to_string(s.voxel.resolution) : "auto")
        << ", voxel-size=" << (s.voxel.voxelSize > 0.0 ? numberText(s.voxel.voxelSize) : "auto")
        << ", fill-interior=" << s.voxel.fillInterior
        << ", voxel-visibility=" << (s.lighting.visibilityBy == VoxelVisibility::Rays ? "rays" : "stepping")
        << ", normal-weights=" << toString(s.lighting.normalWeights)
        << ", hdda=" << (s.lighting.traversal == VisibilityTraversal::Hdda) << ", cones=" << s.gather.cone.coneCount
        << ", aperture=" << s.gather.cone.apertureDegrees << ", cone-offset=" << s.gather.cone.startOffset
        << ", step-factor=" << s.gather.cone.stepFactor << ", bounces=" << s.gather.bounces << ", bounce-cones=" << s.gather.bounceCones << ", bounce-tail=" << s.gather.bounceTail << ", gather-level=" << s.gather.gatherLevel << ", gather-turns=" << s.gather.gatherTurns << ", bright-patches=" << s.gather.brightPatches.factor << ", bright-patch-cell=" << s.gather.brightPatches.cellVoxels << ", bright-patch-max=" << s.gather.brightPatches.maxPatches << ", bright-patch-samples=" << s.gather.brightPatches.samples
        << ", gather-visibility=" << toString(s.gather.visibility) << ", gather-rays=" << s.gather.gatherRays
        << ", bounce-rays=" << s.gather.bounceRays << ", bounce-gather-level=" << s.gather.bounceGatherLevel
        << ", lightmap-gather=" << (s.gather.lightmapGather == LightmapGather::Texels ? "texels" : "points")
        << ", texel-gather-spacing=" << s.gather.texelGatherSpacing << ", texel-gather-rays=" << s.gather.texelGatherRays
        << ", lightmap-seed=" << s.gather.lightmapSeed << ", lightmap-filter=" << s.gather.lightmapFilterPasses
        << ", lightmap-res="
        << (s.lightmap.autoResolution ? std::string("auto") : std::to_string(s.lightmap.width))
        << ", lightmap-subsamples=" << s.lightmap.subsamplesPerAxis << ", emitter-strata=" << s.direct.emitterStrata
        << ", width=" << s.imageWidth << ", height=" << s.imageHeight;
    if (maxComponent(s.sky) > 0.0f) out << ", sky=" << s.sky.x << "," << s.sky.y << "," << s.sky.z;
    if (!s.skyImage.empty())
        out << ", sky-image=" << s.skyImage << ", sky-rotation=" << s.skyRotation << ", sky-intensity=" << s.skyIntensity;
    if (maxComponent(s.sky) > 0.0f || !s.skyImage.empty()) out << ", sky-strata=" << s.direct.skyStrata;
    if (s.lighting.attenuation)
        out << ", attenuation=" << s.lighting.attenuation->constant << "," << s.lighting.attenuation->linear << ","
            << s.lighting.attenuation->quadratic;
    if (s.device != cuda::DeviceChoice::Cpu) out << ", device=" << cuda::toString(s.device);
    if (s.lightmap.texelSize > 0.0) out << ", lightmap-texel=" << numberText(s.lightmap.texelSize);
    if (!s.generateLightmapUvs) out << ", lightmap-uvs=false";
    if (s.lambertMaterials) out << ", materials=lambert";
    if (s.lightBake != LightBake::All) out << ", light-bake=" << lightBakeName(s.lightBake);
    if (s.irradianceVolume.spacing == 0.0) out << ", irradiance-volume=off";
    else if (s.irradianceVolume.spacing > 0.0) out << ", irradiance-volume=" << numberText(s.irradianceVolume.spacing);
    if (s.lightmapSide != LightmapSide::Inside) out << ", lightmap-side=" << toString(s.lightmapSide);
    if (!s.lightmapStitch) out << ", lightmap-stitch=false";
    if (!s.gather.lightmapGradients) out << ", lightmap-gradients=false";
    if (!s.gather.hitLightExact) out << ", hit-light=voxels";
    if (!s.lightTrees) out << ", many-lights=each";
    if (s.direct.lightCut != DirectLightSettings{}.lightCut) out << ", light-cut=" << s.direct.lightCut;
    if (s.gather.nearFieldVoxels != GatherSettings{}.nearFieldVoxels) out << ", near-field=" << s.gather.nearFieldVoxels;
    if (s.lightmapImageSubsamples != BakeSettings{}.lightmapImageSubsamples)
        out << ", lightmap-image-subsamples=" << s.lightmapImageSubsamples;
    if (s.filesOutsideScene) out << ", files-outside-scene=true";
    if (!s.voxel.ownFrame) out << ", grid-frame=world";
    for (size_t g = 0; g < s.lightmap.atlases.size(); ++g) {
        const AtlasGroup& group = s.lightmap.atlases[g];
        out << (g == 0 ? ", atlases=" : "; ") << group.name << ":";
        for (size_t m = 0; m < group.meshes.size(); ++m) out << (m == 0 ? "" : "+") << group.meshes[m];
        if (group.width > 0) out << "@" << group.width << "x" << group.height;
    }
    return out.str();
}

void applySkySettings(const BakeSettings& settings, Scene& scene) {
    if (maxComponent(settings.sky) > 0.0f) scene.sky.radiance = settings.sky;
    if (settings.skyImage.empty()) return;
    if (!scene.sky.image || scene.sky.image->path != settings.skyImage) scene.sky.image = loadSkyImage(settings.skyImage);
    scene.sky.rotationDegrees = settings.skyRotation;
    scene.sky.intensity = settings.skyIntensity;
}

}  // namespace vl
