// What the lightmap shows at a camera pixel, against the truth there. Bakes the scene (or a job
// file's first scene) in memory as `voxlight bake` does; for each pixel named, its main surface
// (the camera sample with the largest share): mesh, material, whether the camera sees the
// triangle's front or back and whether the lightmap holds that side; the texel it reads and the
// 2 × 2 texels of its bilinear read, with what each holds; the lightmap's value there (E/π)
// against the path tracer's irradiance at the pixel's point on the side the camera sees, and
// at the texel's own samples on the side the lightmap holds. So a pixel's error splits into the
// light the texel holds (texel against its truth) and how the lightmap represents the surface
// (its truth against the pixel's). --texel X,Y does the same for a texel of the (first) atlas:
// its samples, each with its truth, and whether each is buried (shade_element.h isBuried) and by
// what surface. --classes OUT.exr writes, per pixel, the share of its samples
// whose bilinear read reaches a texel that holds the other side of the surface (R), another face
// of it (normals over 45° apart, G), or padding or another mesh (B), and OUT_materials.exr the
// material of each pixel's main sample: an error heat map split by cause (docs/accuracy.md).
// --truth-lightmap OUT.exr writes the lightmap-lit view from lightmaps whose every texel the path
// tracer lit (--spp paths a sample, --seed; none from samples inside closed geometry, whose
// texels are filled from their neighbours; less the direct light of lights the engine draws,
// light-bake indirect), dilated and stitched as the bake's: what the
// atlas, its texels and the bilinear read alone cost against the truth (two seeds give their
// noise), and beside it OUT_texels_<atlas>.exr, the truth's texels as shipped. With
// --truth-texels T.exr[,T2.exr …] (one file an atlas, in the bake's order) those texels are
// read instead of traced: the same truth rendered again at other view settings
// (lightmap-image-subsamples). An accuracy measurement, not a test.
//
//   build/accuracy/accuracy_pixel JOB.json|SCENE.gltf [--pixel X,Y …] [--texel X,Y …] [--classes OUT.exr]
//                                 [--truth-lightmap OUT.exr [--truth-texels T.exr,…]] [--spp N] [--seed S]
//                                 [name=value …]
#include "accuracy_job.h"
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "lightmap/lightmap_image.h"
#include "gather/shade_element.h"
#include "receivers/lightmap_sides.h"
#include "core/error.h"
#include "core/image_io.h"
#include "trace/path_tracer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace vl;

namespace {

float grey(const vec3& v) { return (v.x + v.y + v.z) / 3.0f; }

// E/π on each sample's side by the path tracer, `spp` paths each.
std::vector<vec3> truthAt(const std::vector<SurfaceSample>& samples, const TraceScene& scene, const Bvh& bvh, int spp,
                          std::vector<vec3>* direct = nullptr) {
    SurfaceSampleSet set;
    set.width = int(samples.size());
    set.height = 1;
    for (size_t k = 0; k <= samples.size(); ++k) set.begin.push_back(uint32_t(k));
    set.samples = samples;
    for (SurfaceSample& s : set.samples) s.weight = 1.0f;
    PathTracerSettings settings;
    settings.samplesPerPixel = spp;
    settings.quiet = true;
    const TraceResult traced = traceIrradiance(scene, bvh, set, settings);
    std::vector<vec3> out;
    for (size_t k = 0; k < samples.size(); ++k) out.push_back(traced.beauty.rgb(int(k), 0));
    if (direct)
        for (size_t k = 0; k < samples.size(); ++k) direct->push_back(traced.direct.rgb(int(k), 0));
    return out;
}

std::string meshOf(const Scene& scene, const SceneTriangles& triangles, uint32_t triangle) {
    if (triangle >= triangles.meshIndex.size()) return "-";
    const Mesh& mesh = scene.meshes[triangles.meshIndex[triangle]];
    const std::string material = mesh.material >= 0 ? scene.materials[size_t(mesh.material)].name : "default";
    const bool doubleSided = mesh.material >= 0 && scene.materials[size_t(mesh.material)].doubleSided;
    return mesh.name + " [" + material + (doubleSided ? ", double-sided" : "") + "] triangle " +
           std::to_string(triangles.localIndex[triangle]) + " (" + std::to_string(triangle) + ")";
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2)
            throw SettingsError("usage: accuracy_pixel JOB.json|SCENE.gltf --pixel X,Y [--pixel X,Y …] [--spp N] [name=value …]");
        int spp = 1024;
        std::string classesPath, truthLightmapPath, truthTexelsList;
        uint64_t seed = 0;
        std::vector<std::pair<int, int>> pixels, texels;
        SettingAssignments assignments;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--pixel" && i + 1 < argc) {
                pixels.push_back(parsePoint(arg, argv[++i]));
            } else if (arg == "--texel" && i + 1 < argc) {
                texels.push_back(parsePoint(arg, argv[++i]));
            } else if (arg == "--classes" && i + 1 < argc) {
                classesPath = argv[++i];
            } else if (arg == "--truth-lightmap" && i + 1 < argc) {
                truthLightmapPath = argv[++i];
            } else if (arg == "--truth-texels" && i + 1 < argc) {
                truthTexelsList = argv[++i];
            } else if (arg == "--seed" && i + 1 < argc) {
                seed = std::stoull(argv[++i]);
            } else if (arg == "--spp" && i + 1 < argc) {
                spp = std::max(1, std::stoi(argv[++i]));
            } else {
                addAssignment(assignments, arg);
            }
        }
        if (pixels.empty() && texels.empty() && classesPath.empty() && truthLightmapPath.empty())
            throw SettingsError("--pixel: name at least one pixel, or --classes OUT.exr, or --truth-lightmap OUT.exr");
        BakeJob job = accuracyJob(argv[1], assignments);
        job.settings.quiet = true;
        job.settings.outputs.grids = false;

        Diagnostics diagnostics(false, false);
        Scene scene = loadJobScene(job);
        VoxelStages stages = bakeVoxelStages(scene, job.settings, diagnostics);
        const ReceiverScene& tracing = *stages.tracing;
        const ReceiverGather gather = bakeReceiverGather(tracing, stages.indirect, job.settings, stages.onGpu);
        struct Baked {
            LightmapAtlas atlas;  // its samples on the sides the lightmap holds
            Image shipped;
            Image shaded;  // direct + indirect as shaded, before dilation and seam stitching
            Image shadedDirect;
            std::vector<uint32_t> meshes;
            Image shippedMask;  // its shadowmask as it ships (shadowmask lights); empty: none
        };
        std::vector<Baked> baked;
        std::vector<int> atlasOf(scene.meshes.size(), -1);
        for (LightmapAtlas& atlas : buildLightmapReceivers(scene, stages.lightmap, diagnostics)) {
            const ReceiverLighting lit = gather.atlasRows(atlas, 0, atlas.receivers.height);
            const BakedLightmap lightmap =
                finishLightmap(atlas, lit.direct, lit.indirect, lit.open, scene, job.settings, lit.shadowmask);
            if (job.settings.lightmapSide == LightmapSide::Inside)
                orientLightmapSamples(atlas.receivers, tracing.bvh.view(), tracing.traceScene.view(), tracing.viewpoints);
            for (uint32_t m : lightmap.meshes)
                if (!scene.meshes[m].uv1.empty()) atlasOf[m] = int(baked.size());
            Image shaded = lit.direct;
            for (size_t k = 0; k < shaded.pixels.size(); ++k) shaded.pixels[k] += lit.indirect.pixels[k];
            baked.push_back({std::move(atlas), shippedLightmapTexels(lightmap.total), std::move(shaded), lit.direct,
                             lightmap.meshes, shippedShadowmask(lightmap.shadowmask)});
        }
        const Camera camera = bakeCameras(scene, job.settings).front();
        const CameraReceivers receivers = bakeCameraReceivers(
            tracing.traceScene, tracing.bvh, makeCameraModel(camera, job.settings.imageWidth, job.settings.imageHeight),
            job.settings);
        const SurfaceSampleSet& pixelSet = receivers.receivers;

        // One of a pixel's samples: what the lightmap shows there against the truth.
        const auto probe = [&](const SurfaceSample& sample) {
            const uint32_t t = sample.triangle;
            const vec3* corner = &tracing.triangles.vertices[3 * size_t(t)];
            const vec3 ng = glm::normalize(glm::cross(corner[1] - corner[0], corner[2] - corner[0]));
            const bool seesFront = glm::dot(ng, sample.normal) > 0.0f;
            const uint32_t m = tracing.triangles.meshIndex[t];
            const vec3 truthPixel = truthAt({sample}, tracing.traceScene, tracing.bvh, spp).front();
            std::printf(" %s, share %.2f, camera sees its %s, albedo %.3f\n", meshOf(scene, tracing.triangles, t).c_str(),
                        sample.weight, seesFront ? "front" : "back", grey(sample.albedo));
            if (atlasOf[m] < 0) {
                std::printf("  in no lightmap: shown at %.3f; truth E/pi %.4f %.4f %.4f\n", kUnlitLight, truthPixel.x,
                            truthPixel.y, truthPixel.z);
                return;
            }
            const Baked& b = baked[size_t(atlasOf[m])];
            const vec2 uv = lightmapUvAt(scene.meshes[m], tracing.triangles.localIndex[t], corner, sample.position);
            const vec3 shown = sampleLightmap(b.shipped, uv);
            std::printf("  lightmap '%s' at uv (%.5f, %.5f): shows E/pi %.4f %.4f %.4f; truth at the pixel %.4f %.4f %.4f (%.2fx)\n",
                        b.atlas.name.c_str(), uv.x, uv.y, shown.x, shown.y, shown.z, truthPixel.x, truthPixel.y, truthPixel.z,
                        grey(shown) / std::max(grey(truthPixel), 1e-6f));
            const SurfaceSampleSet& set = b.atlas.receivers;
            const float px = uv.x * float(set.width) - 0.5f, py = uv.y * float(set.height) - 0.5f;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const int tx = std::clamp(int(std::floor(px)) + dx, 0, set.width - 1);
                    const int ty = std::clamp(int(std::floor(py)) + dy, 0, set.height - 1);
                    const size_t texel = size_t(ty) * size_t(set.width) + size_t(tx);
                    const vec3 value = b.shipped.rgb(tx, ty);
                    const vec3 shaded = b.shaded.rgb(tx, ty);
                    std::printf("  texel (%d, %d) holds %.4f %.4f %.4f (shaded %.4f %.4f %.4f):", tx, ty, value.x, value.y, value.z,
                                shaded.x, shaded.y, shaded.z);
                    if (!set.covered(texel)) {
                        std::printf(" padding\n");
                        continue;
                    }
                    std::vector<SurfaceSample> own(set.samples.begin() + set.begin[texel], set.samples.begin() + set.begin[texel + 1]);
                    std::vector<vec3> directs;
                    const std::vector<vec3> truths = truthAt(own, tracing.traceScene, tracing.bvh, spp, &directs);
                    vec3 truth(0.0f), truthDirect(0.0f);
                    bool sameSide = false, sameMesh = false;
                    float apart = 0.0f;
                    for (size_t k = 0; k < own.size(); ++k) {
                        apart += own[k].weight * glm::distance(own[k].position, sample.position);
                        truth += own[k].weight * truths[k];
                        truthDirect += own[k].weight * directs[k];
                        sameSide = sameSide || glm::dot(own[k].normal, sample.normal) > 0.0f;
                        sameMesh = sameMesh || tracing.triangles.meshIndex[own[k].triangle] == m;
                    }
                    std::printf(" %zu samples %.1f cm away, %s, %s the pixel's side; their truth %.4f %.4f %.4f (%.2fx)\n", own.size(), 100.0f * apart,
                                sameMesh ? "the pixel's mesh" : ("another mesh: " + meshOf(scene, tracing.triangles, own.front().triangle)).c_str(),
                                sameSide ? "on" : "NOT on", truth.x, truth.y, truth.z, grey(value) / std::max(grey(truth), 1e-6f));
                    std::printf("    direct: shaded %.4f, truth %.4f; indirect: shaded %.4f, truth %.4f\n", grey(b.shadedDirect.rgb(tx, ty)),
                                grey(truthDirect), grey(shaded - b.shadedDirect.rgb(tx, ty)), grey(truth - truthDirect));
                }
        };
        for (const auto& [x, y] : pixels) {
            if (x < 0 || y < 0 || x >= pixelSet.width || y >= pixelSet.height)
                throw SettingsError("--pixel " + std::to_string(x) + "," + std::to_string(y) + ": outside the image");
            const size_t element = size_t(y) * size_t(pixelSet.width) + size_t(x);
            std::printf("pixel (%d, %d):%s\n", x, y, pixelSet.covered(element) ? "" : " the sky");
            for (uint32_t k = pixelSet.begin[element]; k < pixelSet.begin[element + 1]; ++k)
                probe(pixelSet.samples[k]);
        }
        for (const auto& [x, y] : texels) {
            const Baked& b = baked.front();
            const SurfaceSampleSet& set = b.atlas.receivers;
            const size_t texel = size_t(y) * size_t(set.width) + size_t(x);
            std::printf("texel (%d, %d) of '%s': holds %.4f, shaded %.4f (direct %.4f)\n", x, y, b.atlas.name.c_str(), grey(b.shipped.rgb(x, y)),
                        grey(b.shaded.rgb(x, y)), grey(b.shadedDirect.rgb(x, y)));
            if (!set.covered(texel)) continue;
            std::vector<SurfaceSample> own(set.samples.begin() + set.begin[texel], set.samples.begin() + set.begin[texel + 1]);
            std::vector<vec3> directs;
            const std::vector<vec3> truths = truthAt(own, tracing.traceScene, tracing.bvh, spp, &directs);
            for (size_t k = 0; k < own.size(); ++k)
                std::printf("  sample at (%.3f, %.3f, %.3f) n (%.2f, %.2f, %.2f) weight %.3f on %s: truth %.4f (direct %.4f)\n", own[k].position.x,
                            own[k].position.y, own[k].position.z, own[k].normal.x, own[k].normal.y, own[k].normal.z, own[k].weight,
                            meshOf(scene, tracing.triangles, own[k].triangle).c_str(), grey(truths[k]), grey(directs[k]));
            // Whether each sample is buried (shade_element.h isBuried), and by what: the probes
            // that meet a surface from behind, and the nearest such surface.
            for (size_t k = 0; k < own.size(); ++k) {
                const SurfaceSample& r = own[k];
                vec3 tangent, bitangent;
                orthonormalBasis(r.normal, tangent, bitangent);
                Ray ray;
                ray.origin = offsetRayOrigin(r.position, r.normal, tracing.bvh.view().extent);
                int behind = 0;
                Hit nearest;
                nearest.t = INFINITY;
                for (int a = 0; a < kBuriedProbesPerAxis; ++a)
                    for (int c = 0; c < kBuriedProbesPerAxis; ++c) {
                        const vec3 d = sampleCosineHemisphere(
                            vec2((float(a) + 0.5f) / kBuriedProbesPerAxis, (float(c) + 0.5f) / kBuriedProbesPerAxis));
                        ray.direction = d.x * tangent + d.y * bitangent + d.z * r.normal;
                        Hit hit;
                        if (!intersectClosest(tracing.bvh.view(), ray, hit)) continue;
                        const vec3* n = tracing.traceScene.view().normals + 3 * size_t(hit.triangle);
                        const vec3 normal = (1.0f - hit.b1 - hit.b2) * n[0] + hit.b1 * n[1] + hit.b2 * n[2];
                        if (!(glm::dot(normal, ray.direction) > 0.0f)) continue;
                        ++behind;
                        if (hit.t < nearest.t) nearest = hit;
                    }
                std::printf("  sample %zu: %d of %d probes meet a surface from behind%s%s%s: %s\n", k, behind, kBuriedProbeRays,
                            behind ? " (the nearest " : "", behind ? meshOf(scene, tracing.triangles, nearest.triangle).c_str() : "",
                            behind ? (" at " + std::to_string(nearest.t) + ")").c_str() : "",
                            isBuried(tracing.traceScene.view(), tracing.bvh.view(), r) ? "buried" : "open");
            }
        }
        if (!truthLightmapPath.empty()) {
            std::vector<std::string> givenTexels;
            std::istringstream list(truthTexelsList);
            for (std::string item; std::getline(list, item, ',');) givenTexels.push_back(item);
            if (!givenTexels.empty() && givenTexels.size() != baked.size())
                throw SettingsError("--truth-texels: " + std::to_string(givenTexels.size()) + " files for " +
                                    std::to_string(baked.size()) + " atlases");
            const std::string stem = truthLightmapPath.substr(0, truthLightmapPath.size() - 4);
            std::vector<ShippedLightmap> truths;
            for (size_t a = 0; a < baked.size(); ++a) {
                const Baked& b = baked[a];
                if (!givenTexels.empty()) {
                    Image texels = readImage(givenTexels[a]);
                    if (texels.width != b.shipped.width || texels.height != b.shipped.height)
                        throw SettingsError(givenTexels[a] + ": not the size of atlas '" + b.atlas.name + "'");
                    truths.push_back({b.meshes, std::move(texels), b.shippedMask});
                    continue;
                }
                PathTracerSettings traceSettings;
                traceSettings.samplesPerPixel = spp;
                traceSettings.seed = seed;
                traceSettings.quiet = true;
                // Samples inside closed geometry are nobody's truth (a path from there finds only
                // what leaks through the cracks): they take no paths, and the lightmap is finished
                // from the open ones as the bake's is (bake.h finishLightmap). The bake's rule: most
                // probe rays meet backs, and neither a light nor the sky reaches it.
                SurfaceSampleSet open = b.atlas.receivers;
                tbb::parallel_for(size_t(0), open.samples.size(), [&](size_t k) {
                    const TraceSceneView view = tracing.traceScene.view();
                    if (isBuried(view, tracing.bvh.view(), open.samples[k]) &&
                        !(maxComponent(directIrradiance(view, tracing.bvh.view(), open.samples[k], job.settings.direct, k)) > 0.0f))
                        open.samples[k].weight = 0.0f;
                });
                Image openWeight(open.width, open.height, 1);
                for (size_t texel = 0; texel < open.elementCount(); ++texel)
                    for (uint32_t k = open.begin[texel]; k < open.begin[texel + 1]; ++k)
                        if (open.samples[k].weight > 0.0f) openWeight.pixels[texel] += open.samples[k].weight;
                TraceResult traced = traceIrradiance(tracing.traceScene, tracing.bvh, open, traceSettings);
                // Lights the engine draws (light-bake indirect): the truth a lightmap can hold is
                // the rest, so their direct light, exact at each sample as the bake's, is taken
                // off the traced direct light (what is left of their paths' noise is zero-mean).
                const TraceSceneView view = tracing.traceScene.view();
                if (std::any_of(view.lights, view.lights + view.lightCount,
                                [](const TraceLight& l) { return l.engineDrawn != 0; })) {
                    DirectLightSettings every = job.settings.direct, kept = job.settings.direct;
                    every.skyAtSamples = kept.skyAtSamples = false;
                    kept.engineDrawnLights = false;
                    tbb::parallel_for(size_t(0), open.elementCount(), [&](size_t texel) {
                        for (uint32_t k = open.begin[texel]; k < open.begin[texel + 1]; ++k) {
                            const SurfaceSample& sample = open.samples[k];
                            if (!(sample.weight > 0.0f)) continue;
                            const vec3 drawn = directIrradiance(view, tracing.bvh.view(), sample, every, k) -
                                               directIrradiance(view, tracing.bvh.view(), sample, kept, k);
                            for (int c = 0; c < 3; ++c) traced.direct.pixels[3 * texel + size_t(c)] -= sample.weight * drawn[c] * kInvPi;
                        }
                    });
                }
                const BakedLightmap truth =
                    finishLightmap(b.atlas, traced.direct, traced.indirect, openWeight, scene, job.settings);
                // Shadowmask lights: the bake's own mask, each texel's exact visibility.
                truths.push_back({b.meshes, shippedLightmapTexels(truth.total), b.shippedMask});
                writeExr(truths.back().texels, stem + "_texels_" + b.atlas.name + ".exr");
            }
            writeExr(bakeLightmapImage(tracing.traceScene, tracing.bvh,
                                       makeCameraModel(camera, job.settings.imageWidth, job.settings.imageHeight), scene,
                                       tracing.triangles, job.settings, truths),
                     truthLightmapPath);
        }
        if (!classesPath.empty()) {
            // Per pixel, the share of its samples whose bilinear read reaches a texel that holds the
            // other side (R), another face (normal apart by over 45°, G), or padding or another
            // mesh (B).
            Image classes(pixelSet.width, pixelSet.height, 3), materials(pixelSet.width, pixelSet.height, 1, -1.0f);
            for (int y = 0; y < pixelSet.height; ++y)
                for (int x = 0; x < pixelSet.width; ++x) {
                    const size_t element = size_t(y) * size_t(pixelSet.width) + size_t(x);
                    vec3 share(0.0f);
                    float mainWeight = 0.0f;
                    for (uint32_t k = pixelSet.begin[element]; k < pixelSet.begin[element + 1]; ++k) {
                        const SurfaceSample& sample = pixelSet.samples[k];
                        if (sample.weight > mainWeight) {
                            mainWeight = sample.weight;
                            materials.at(x, y) = float(scene.meshes[tracing.triangles.meshIndex[sample.triangle]].material);
                        }
                        const uint32_t t = sample.triangle, m = tracing.triangles.meshIndex[t];
                        if (atlasOf[m] < 0) continue;
                        const Baked& b = baked[size_t(atlasOf[m])];
                        const vec2 uv = lightmapUvAt(scene.meshes[m], tracing.triangles.localIndex[t],
                                                     &tracing.triangles.vertices[3 * size_t(t)], sample.position);
                        if (!std::isfinite(uv.x)) continue;
                        const SurfaceSampleSet& set = b.atlas.receivers;
                        const float px = uv.x * float(set.width) - 0.5f, py = uv.y * float(set.height) - 0.5f;
                        bool otherSide = false, otherFace = false, outside = false;
                        for (int dy = 0; dy < 2; ++dy)
                            for (int dx = 0; dx < 2; ++dx) {
                                const int tx = std::clamp(int(std::floor(px)) + dx, 0, set.width - 1);
                                const int ty = std::clamp(int(std::floor(py)) + dy, 0, set.height - 1);
                                const size_t texel = size_t(ty) * size_t(set.width) + size_t(tx);
                                if (!set.covered(texel)) {
                                    outside = true;
                                    continue;
                                }
                                for (uint32_t q = set.begin[texel]; q < set.begin[texel + 1]; ++q) {
                                    const SurfaceSample& o = set.samples[q];
                                    const float facing = glm::dot(o.normal, sample.normal);
                                    if (tracing.triangles.meshIndex[o.triangle] != m) outside = true;
                                    else if (facing < 0.0f) otherSide = true;
                                    else if (facing < 0.7071f) otherFace = true;
                                }
                            }
                        share += sample.weight * vec3(otherSide, otherFace && !otherSide, outside && !otherSide && !otherFace);
                    }
                    classes.setRgb(x, y, share);
                }
            writeExr(classes, classesPath);
            writeExr(materials, classesPath.substr(0, classesPath.size() - 4) + "_materials.exr");
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
