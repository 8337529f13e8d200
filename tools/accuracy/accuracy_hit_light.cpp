// What a camera pixel's surface gathers at the first bounce, ray by ray: the light the bake's
// rays read from the voxels where they hit (the fans' read: the face of the hit voxel that looks
// back at the ray) against the exact light those hit points send back (the lights' direct
// irradiance there, shadowed, × albedo / π). Voxel bounces 0 and no bright patches, so the
// voxels hold the first reflection alone. Punctual lights only: a scene with a sky or
// emissive surfaces is refused. Sums by the hit's material show which surfaces the
// voxels make too bright or too dark for that pixel. An accuracy measurement, not a test.
//
//   build/accuracy/accuracy_hit_light JOB.json|SCENE.gltf --pixel X,Y [--pixel X,Y …] [--rays N] [name=value …]
#include "accuracy_job.h"
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "gather/fan_rays.h"
#include "bake/job_file.h"
#include "core/error.h"
#include "core/sampling.h"
#include "trace/bvh_traverse.h"
#include "trace/camera.h"
#include "trace/path_kernels.h"
#include "trace/ray_offset.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

using namespace vl;

namespace {

struct Sums {
    vec3 voxels{0.0f}, exact{0.0f};
    int rays = 0;
};

float grey(const vec3& v) { return (v.x + v.y + v.z) / 3.0f; }

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2)
            throw SettingsError("usage: accuracy_hit_light JOB.json|SCENE.gltf --pixel X,Y [--pixel X,Y …] [--rays N] [name=value …]");
        int raysPerAxis = 64;
        std::vector<std::pair<int, int>> pixels;
        SettingAssignments assignments;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--pixel" && i + 1 < argc) {
                pixels.push_back(parsePoint(arg, argv[++i]));
            } else if (arg == "--rays" && i + 1 < argc) {
                raysPerAxis = std::max(1, int(std::lround(std::sqrt(std::stod(argv[++i])))));
            } else {
                addAssignment(assignments, arg);
            }
        }
        if (pixels.empty()) throw SettingsError("--pixel: name at least one pixel");
        BakeJob job = accuracyJob(argv[1], assignments);
        job.settings.quiet = true;
        job.settings.outputs.lightmaps = job.settings.outputs.grids = false;
        job.settings.gather.bounces = 0;
        job.settings.gather.bounceTail = false;
        job.settings.gather.brightPatches.factor = 0.0f;

        Scene scene = loadJobScene(job);
        Diagnostics diagnostics(false, false);
        const VoxelStages stages = bakeVoxelStages(scene, job.settings, diagnostics);
        const TraceSceneView view = stages.tracing->traceScene.view();
        const BvhView bvh = stages.tracing->bvh.view();
        // The exact side computes the lights' (punctual) direct light alone.
        if (view.emitterCount > 0 || view.sky.present())
            throw InputError(job.scenePath + ": it has a sky or emissive surfaces, whose light the exact side does not "
                                             "compute: give its lights alone (a job without \"sky\", emission off)");
        const MipView mips = stages.indirect.mips.view();
        const Level0Texels level0(mips.levels[0]);
        const std::vector<FaceRadiance>& faces = stages.indirect.bright.restFaces;
        const CameraModel camera =
            makeCameraModel(bakeCameras(scene, job.settings).front(), job.settings.imageWidth, job.settings.imageHeight);

        for (const auto& [px, py] : pixels) {
            Hit first;
            const Ray primary = pinholeRay(camera, vec2(float(px) + 0.5f, float(py) + 0.5f));
            if (!intersectClosest(bvh, primary, first)) {
                std::printf("pixel %d,%d: sees nothing\n", px, py);
                continue;
            }
            const SurfaceHit seen = surfaceAt(view, first.triangle, first.b1, first.b2);
            const vec3 n = glm::dot(seen.geometricNormal, primary.direction) < 0.0f ? seen.geometricNormal : -seen.geometricNormal;
            vec3 t, b;
            orthonormalBasis(n, t, b);
            IndexLeafCache leaves;
            std::map<std::string, Sums> byMaterial;
            Sums all;
            for (int i = 0; i < raysPerAxis; ++i)
                for (int j = 0; j < raysPerAxis; ++j) {
                    const vec3 d = sampleCosineHemisphere(vec2((float(i) + 0.5f) / float(raysPerAxis), (float(j) + 0.5f) / float(raysPerAxis)));
                    Ray ray;
                    ray.origin = offsetRayOrigin(seen.position, n, bvh.extent);
                    ray.direction = glm::normalize(d.x * t + d.y * b + d.z * n);
                    Hit hit;
                    if (!intersectClosest(bvh, ray, hit)) continue;
                    vec3 read(0.0f);
                    readHitTexels(level0, leaves, ray.at(hit.t), ray.direction, windingCross(view, hit.triangle),
                                  [&](int32_t voxel, int travel, float weight) { read += weight * faces[size_t(voxel)][size_t(travel ^ 1)]; });
                    const SurfaceHit h = surfaceAt(view, hit.triangle, hit.b1, hit.b2);
                    const vec3 side = glm::dot(h.geometricNormal, ray.direction) < 0.0f ? h.geometricNormal : -h.geometricNormal;
                    vec3 irradiance(0.0f);
                    constexpr int kDisk = 4;  // a sun's disk, 4 × 4 points
                    for (int u = 0; u < kDisk; ++u)
                        for (int v = 0; v < kDisk; ++v)
                            irradiance += punctualIrradiance(view, bvh, h.position, side, side,
                                                             vec2((float(u) + 0.5f) / kDisk, (float(v) + 0.5f) / kDisk));
                    const vec3 exact = baseColorAt(view, h) * irradiance / (kPi * float(kDisk * kDisk));
                    Sums& m = byMaterial[scene.materials[h.material].name];
                    for (Sums* s : {&m, &all}) {
                        s->voxels += read;
                        s->exact += exact;
                        ++s->rays;
                    }
                }
            const float perRay = kPi / float(raysPerAxis * raysPerAxis);
            std::printf("pixel %d,%d (%s): first-bounce irradiance / pi from the voxels %.4f, exact %.4f (%+.0f%%)\n", px, py,
                        scene.materials[seen.material].name.c_str(), grey(all.voxels) * perRay / kPi,
                        grey(all.exact) * perRay / kPi, 100.0 * (grey(all.voxels) / std::max(grey(all.exact), 1e-12f) - 1.0));
            std::vector<std::pair<std::string, Sums>> rows(byMaterial.begin(), byMaterial.end());
            std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& c) {
                return std::abs(grey(a.second.voxels - a.second.exact)) > std::abs(grey(c.second.voxels - c.second.exact));
            });
            for (size_t k = 0; k < rows.size() && k < 6; ++k)
                std::printf("  %-22s %5d rays: voxels %.4f, exact %.4f\n", rows[k].first.c_str(), rows[k].second.rays,
                            grey(rows[k].second.voxels) * perRay / kPi, grey(rows[k].second.exact) * perRay / kPi);
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accuracy_hit_light: %s\n", e.what());
        return 1;
    }
}
