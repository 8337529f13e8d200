// Where a lightmap's chart seams jump, and what stitching leaves (lightmap/lightmap_seams.h).
// Bakes the scene (or a job file's first scene) in memory as `voxlight bake` does, finishes
// each atlas twice, unstitched and stitched, and reports the seams' mean relative jump (what
// bake.json's "lightmap_seams" reports) over all seams and by class: the fold between the two
// triangles, the seam's length in texels, and its light level. Also the time stitching took.
// With --truth SPP, whether the light itself is one value there: at every 16th pair read, the
// path tracer's irradiance at the two points the reads stand for (each side's texel point
// carried onto its triangle), against the bake's two reads. Stitching assumes it is; where the
// truth jumps too (a fold's shadow, a contact), a stitched seam is wrong on both sides. An
// accuracy measurement, not a test.
//
//   build/accuracy/accuracy_seams SCENE.gltf|JOB.json [--truth SPP] [name=value …]
//
// Bake settings as name=value (the bake's flags without --).
#include "accuracy_job.h"
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/job_file.h"
#include "lightmap/lightmap_image.h"
#include "lightmap/lightmap_seams.h"
#include "core/error.h"
#include "trace/path_tracer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <string>
#include <vector>

using namespace vl;
namespace fs = std::filesystem;

namespace {

// A class of seams: its share of the seams' counted weight and the two jumps' sums.
struct Class {
    const char* name;
    SeamJump before, after, edgeBefore, edgeAfter;
};

void add(SeamJump& sum, const SeamJump& one) {
    sum.edges += one.edges;
    sum.length += one.length;
    sum.weight += one.weight;
    sum.relativeSum += one.relativeSum;
}

double mean(const SeamJump& j) { return j.weight > 0.0 ? j.relativeSum / j.weight : 0.0; }

float grey(const vec3& v) { return (v.x + v.y + v.z) / 3.0f; }

double relativeJump(double a, double b) { return a + b > 0.0 ? std::abs(a - b) / (0.5 * (a + b)) : 0.0; }

// The point of a seam side's triangle that texel point `p` (texel coordinates) stands for: its
// barycentrics in uv1, clamped to the triangle, carried to the corners; the normal interpolated.
SurfaceSample pointOfTexel(const Scene& scene, const SeamSide& side, vec2 p, int width, int height) {
    const Mesh& mesh = scene.meshes[side.mesh];
    const uint32_t* index = &mesh.indices[3 * size_t(side.triangle)];
    const vec2 size{float(width), float(height)};
    const vec2 t0 = mesh.uv1[index[0]] * size, t1 = mesh.uv1[index[1]] * size, t2 = mesh.uv1[index[2]] * size;
    const float det = (t1.x - t0.x) * (t2.y - t0.y) - (t1.y - t0.y) * (t2.x - t0.x);
    float b1 = ((p.x - t0.x) * (t2.y - t0.y) - (p.y - t0.y) * (t2.x - t0.x)) / det;
    float b2 = ((t1.x - t0.x) * (p.y - t0.y) - (t1.y - t0.y) * (p.x - t0.x)) / det;
    b1 = std::max(0.0f, b1);
    b2 = std::max(0.0f, b2);
    if (b1 + b2 > 1.0f) {
        b1 /= b1 + b2;
        b2 = 1.0f - b1;
    }
    const float b0 = 1.0f - b1 - b2;
    const vec3 &q0 = mesh.positions[index[0]], &q1 = mesh.positions[index[1]], &q2 = mesh.positions[index[2]];
    SurfaceSample s;
    s.position = b0 * q0 + b1 * q1 + b2 * q2;
    s.normal = glm::normalize(mesh.normals.size() == mesh.positions.size()
                                  ? b0 * mesh.normals[index[0]] + b1 * mesh.normals[index[1]] + b2 * mesh.normals[index[2]]
                                  : glm::cross(q1 - q0, q2 - q0));
    s.albedo = vec3(1.0f);
    s.triangle = 0;  // gatherTriangles numbers the scene's triangles mesh by mesh
    for (uint32_t m = 0; m < side.mesh; ++m) s.triangle += uint32_t(scene.meshes[m].triangleCount());
    s.triangle += side.triangle;
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SCENE.gltf|JOB.json [name=value ...]\n", argv[0]);
        return 2;
    }
    try {
        const std::string input = argv[1];
        SettingAssignments assignments;
        int truthSpp = 0;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--truth" && i + 1 < argc) {
                truthSpp = std::max(1, std::stoi(argv[++i]));
                continue;
            }
            addAssignment(assignments, arg);
        }
        BakeJob job = accuracyJob(input, assignments);
        job.settings.quiet = true;
        job.settings.outputs.grids = false;

        Diagnostics diagnostics(false, false);
        Scene scene = loadJobScene(job);
        VoxelStages stages = bakeVoxelStages(scene, job.settings, diagnostics);
        const ReceiverGather gather = bakeReceiverGather(*stages.tracing, stages.indirect, job.settings, stages.onGpu);
        // Folds: < 1°, 1-15°, 15-45°, ≥ 45°; lengths: the longer side < 2, 2-16, ≥ 16 texels;
        // levels: the mean of the two sides unstitched, per channel, < 0.01, 0.01-0.1, ≥ 0.1.
        // Texels: whether the two sides' on-edge reads touch a texel in common (a covered texel
        // cut by both charts' edges, or a padding ring two charts share), and whether a texel
        // the seam's reads touch is read by three or more seam sides (corners, thin charts).
        std::vector<Class> classes = {{"all seams", {}, {}, {}, {}},         {"fold < 1 deg", {}, {}, {}, {}},
                                      {"fold 1-15 deg", {}, {}, {}, {}},     {"fold 15-45 deg", {}, {}, {}, {}},
                                      {"fold >= 45 deg", {}, {}, {}, {}},    {"length < 2 texels", {}, {}, {}, {}},
                                      {"length 2-16 texels", {}, {}, {}, {}}, {"length >= 16 texels", {}, {}, {}, {}},
                                      {"level < 0.01", {}, {}, {}, {}},      {"level 0.01-0.1", {}, {}, {}, {}},
                                      {"level >= 0.1", {}, {}, {}, {}},      {"sides share a texel", {}, {}, {}, {}},
                                      {"sides share none", {}, {}, {}, {}},  {"a texel of 3+ sides", {}, {}, {}, {}},
                                      {"texels of <= 2 sides", {}, {}, {}, {}}};
        SeamJump floatAfterAtEdge;
        double stitchSeconds = 0.0, finishSeconds = 0.0;
        // Every 16th pair read: the bake's two reads, and the two points they stand for.
        SurfaceSampleSet truthPoints;
        truthPoints.height = 1;
        truthPoints.begin.push_back(0);
        std::vector<vec2> bakeReads;
        size_t pairIndex = 0;
        for (const LightmapAtlas& atlas : buildLightmapReceivers(scene, stages.lightmap, diagnostics)) {
            const ReceiverLighting lit = gather.atlasRows(atlas, 0, atlas.receivers.height);
            BakeSettings plain = job.settings, stitched = job.settings;
            plain.lightmapStitch = false;
            stitched.lightmapStitch = true;
            const auto t0 = std::chrono::steady_clock::now();
            const BakedLightmap off = finishLightmap(atlas, lit.direct, lit.indirect, lit.open, scene, plain);
            const auto t1 = std::chrono::steady_clock::now();
            const BakedLightmap on = finishLightmap(atlas, lit.direct, lit.indirect, lit.open, scene, stitched);
            const auto t2 = std::chrono::steady_clock::now();
            finishSeconds += std::chrono::duration<double>(t1 - t0).count();
            stitchSeconds += std::chrono::duration<double>((t2 - t1) - (t1 - t0)).count();
            const Image before = shippedLightmapTexels(off.total), after = shippedLightmapTexels(on.total);
            const std::vector<LightmapSeam> seams = findLightmapSeams(scene, atlas.meshes, atlas.mask.width,
                                                                      atlas.mask.height);
            std::printf("atlas '%s': %d x %d, %zu seams, %.2f m; mean relative jump %.2f%% unstitched, %.2f%% "
                        "stitched, %zu texels moved\n",
                        atlas.name.c_str(), atlas.mask.width, atlas.mask.height, seams.size(), on.seams.after.length,
                        100.0 * on.seams.before.meanRelative, 100.0 * on.seams.after.meanRelative,
                        on.seams.texelsMoved);
            floatAfterAtEdge = measureSeamJump(seams, on.total, 0.0f);
            // The texels each seam side's on-edge reads touch (bilinear, as the stitch sees them).
            const auto sideTexels = [&](const LightmapSeam& seam, int side) {
                std::vector<size_t> texels;
                const float length = std::max(glm::length(seam.sides[0].b - seam.sides[0].a),
                                              glm::length(seam.sides[1].b - seam.sides[1].a));
                const int n = std::clamp(int(std::ceil(2.0f * length)), 2, 4096);
                for (int k = 0; k < n; ++k) {
                    const float t = (float(k) + 0.5f) / float(n);
                    const vec2 p = seam.sides[side].a + t * (seam.sides[side].b - seam.sides[side].a) - vec2(0.5f);
                    const int x0 = int(std::floor(p.x)), y0 = int(std::floor(p.y));
                    for (int dy = 0; dy <= 1; ++dy)
                        for (int dx = 0; dx <= 1; ++dx) {
                            const int x = std::clamp(x0 + dx, 0, before.width - 1), y = std::clamp(y0 + dy, 0, before.height - 1);
                            texels.push_back(size_t(y) * size_t(before.width) + size_t(x));
                        }
                }
                std::sort(texels.begin(), texels.end());
                texels.erase(std::unique(texels.begin(), texels.end()), texels.end());
                return texels;
            };
            std::vector<uint8_t> sidesAt(size_t(before.width) * size_t(before.height), 0);
            std::vector<std::array<std::vector<size_t>, 2>> touched(seams.size());
            for (size_t s = 0; s < seams.size(); ++s)
                for (int side = 0; side < 2; ++side) {
                    touched[s][size_t(side)] = sideTexels(seams[s], side);
                    for (size_t texel : touched[s][size_t(side)]) sidesAt[texel] = uint8_t(std::min(255, sidesAt[texel] + 1));
                }
            for (size_t s = 0; s < seams.size(); ++s) {
                const LightmapSeam& seam = seams[s];
                const SeamJump b = measureSeamJump({seam}, before), a = measureSeamJump({seam}, after);
                const SeamJump eb = measureSeamJump({seam}, before, 0.0f), ea = measureSeamJump({seam}, after, 0.0f);
                std::vector<size_t> common;
                std::set_intersection(touched[s][0].begin(), touched[s][0].end(), touched[s][1].begin(),
                                      touched[s][1].end(), std::back_inserter(common));
                bool crowded = false;
                for (int side = 0; side < 2; ++side)
                    for (size_t texel : touched[s][size_t(side)]) crowded = crowded || sidesAt[texel] >= 3;
                const float texels = std::max(glm::length(seam.sides[0].b - seam.sides[0].a),
                                              glm::length(seam.sides[1].b - seam.sides[1].a));
                const double level = b.weight > 0.0 ? b.levelSum / b.weight / 3.0 : 0.0;
                const float fold = seam.foldDegrees;
                if (truthSpp > 0) {
                    const int n = std::clamp(int(std::ceil(2.0f * texels)), 2, 4096);
                    const float texelMetres = float(seam.length) / std::max(texels, 1e-6f);
                    for (int k = 0; k < n; ++k, ++pairIndex) {
                        if (pairIndex % 16 != 0) continue;
                        const float t = (float(k) + 0.5f) / float(n);
                        const vec2 size{float(before.width), float(before.height)};
                        vec2 at[2];
                        for (int side = 0; side < 2; ++side)
                            at[side] = seam.sides[side].a + t * (seam.sides[side].b - seam.sides[side].a) +
                                       kSeamInsetTexels * seam.sides[side].inward;
                        const SurfaceSample a = pointOfTexel(scene, seam.sides[0], at[0], before.width, before.height);
                        const SurfaceSample b = pointOfTexel(scene, seam.sides[1], at[1], before.width, before.height);
                        // A sliver's clamp can carry a point far along its edge: such pairs say nothing.
                        if (glm::distance(a.position, b.position) > 3.0f * texelMetres) continue;
                        for (const SurfaceSample& point : {a, b}) {
                            truthPoints.samples.push_back(point);
                            truthPoints.begin.push_back(uint32_t(truthPoints.samples.size()));
                        }
                        bakeReads.push_back({grey(sampleLightmap(before, at[0] / size)), grey(sampleLightmap(before, at[1] / size))});
                    }
                }
                for (size_t c : {size_t(0), size_t(fold < 1.0f ? 1 : fold < 15.0f ? 2 : fold < 45.0f ? 3 : 4),
                                 size_t(texels < 2.0f ? 5 : texels < 16.0f ? 6 : 7),
                                 size_t(level < 0.01 ? 8 : level < 0.1 ? 9 : 10), size_t(common.empty() ? 12 : 11),
                                 size_t(crowded ? 13 : 14)}) {
                    add(classes[c].before, b);
                    add(classes[c].after, a);
                    add(classes[c].edgeBefore, eb);
                    add(classes[c].edgeAfter, ea);
                }
            }
        }
        if (truthSpp > 0 && !bakeReads.empty()) {
            truthPoints.width = int(truthPoints.samples.size());
            PathTracerSettings settings;
            settings.samplesPerPixel = truthSpp;
            settings.quiet = true;
            const TraceResult truth = traceIrradiance(stages.tracing->traceScene, stages.tracing->bvh, truthPoints, settings);
            double counts[2][2] = {{0.0, 0.0}, {0.0, 0.0}};  // [bake jumps][truth jumps], by over 50%
            double bakeSum = 0.0, truthSum = 0.0;
            for (size_t k = 0; k < bakeReads.size(); ++k) {
                const double bake = relativeJump(bakeReads[k].x, bakeReads[k].y);
                const double real = relativeJump(grey(truth.beauty.rgb(int(2 * k), 0)), grey(truth.beauty.rgb(int(2 * k + 1), 0)));
                counts[bake > 0.5][real > 0.5] += 1.0;
                bakeSum += bake;
                truthSum += real;
            }
            const double n = double(bakeReads.size());
            std::printf("the truth at %d spp at %zu pair reads (every 16th, unstitched): mean relative jump %.2f%% in the bake, %.2f%% in "
                        "the truth; over 50%% in both %.1f%%, the bake alone %.1f%%, the truth alone %.1f%%, neither %.1f%%\n",
                        truthSpp, bakeReads.size(), 100.0 * bakeSum / n, 100.0 * truthSum / n, 100.0 * counts[1][1] / n,
                        100.0 * counts[1][0] / n, 100.0 * counts[0][1] / n, 100.0 * counts[0][0] / n);
        }
        std::printf("%s: finishing the lightmaps took %.2f s unstitched; stitching added %.2f s\n",
                    job.scenePath.c_str(), finishSeconds, stitchSeconds);
        std::printf("on the edge, stitched, before 8-bit RGBM: %.2f%%\n", 100.0 * floatAfterAtEdge.meanRelative);
        std::printf("%-22s %7s %9s %14s %14s %14s %14s\n", "seams", "count", "share", "jump before", "jump after",
                    "edge before", "edge after");
        const double total = classes[0].before.weight;
        for (const Class& c : classes)
            std::printf("%-22s %7zu %8.1f%% %13.2f%% %13.2f%% %13.2f%% %13.2f%%\n", c.name, c.before.edges,
                        total > 0.0 ? 100.0 * c.before.weight / total : 0.0, 100.0 * mean(c.before),
                        100.0 * mean(c.after), 100.0 * mean(c.edgeBefore), 100.0 * mean(c.edgeAfter));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
