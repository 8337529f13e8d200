// How well the voxels hold a scene's whole light, bounces and sky included: the light each
// voxel side reflects after the bake's voxel stages (faceRadiance · π, over the side's
// surface area) against the path tracer's (albedo × its irradiance, direct and indirect, at
// points spread over the surface inside that side, area-weighted), by material. Where a
// material's ratio is far from 1 after bounces and near 1 in accuracy_voxel_light (direct
// light alone), the voxels' bounces are what carries too little or too much; every ray a
// record or a near-field path reads from the voxels reads it. An accuracy measurement, not a
// test and not a speed figure.
//
//   build/accuracy/accuracy_voxel_bounces JOB.json|SCENE.gltf [--points-per-voxel N] [--spp N] [name=value …]
#include "accuracy_job.h"
#include "bake/bake.h"
#include "core/diagnostics.h"
#include "core/error.h"
#include "trace/path_tracer.h"
#include "voxel_side_points.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

using namespace vl;

namespace {

double mean3(const glm::dvec3& v) { return (v.x + v.y + v.z) / 3.0; }

// A point on a voxel side: which voxel, which of its faces, the area it stands for.
struct SidePoint {
    uint32_t voxel = 0;
    int face = 0;
    double area = 0.0;
    int material = -1;
};

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2)
            throw SettingsError("usage: accuracy_voxel_bounces JOB.json|SCENE.gltf [--points-per-voxel N] [--spp N] [name=value …]");
        int pointsPerVoxel = 4, spp = 32;
        SettingAssignments assignments;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--points-per-voxel" && i + 1 < argc) {
                pointsPerVoxel = std::max(1, std::stoi(argv[++i]));
                continue;
            }
            if (arg == "--spp" && i + 1 < argc) {
                spp = std::max(1, std::stoi(argv[++i]));
                continue;
            }
            addAssignment(assignments, arg);
        }
        BakeJob job = accuracyJob(argv[1], assignments);
        job.settings.quiet = true;
        Scene scene = loadJobScene(job);
        Diagnostics diagnostics(false, false);
        const VoxelStages stages = bakeVoxelStages(scene, job.settings, diagnostics);
        const VoxelScene& voxels = stages.result.voxels;
        const double h = voxels.voxelSize;
        const TraceSceneView view = stages.tracing->traceScene.view();
        std::fprintf(stderr, "%zu voxels of %.2f cm\n", voxels.size(), 100.0 * h);

        // Points per triangle ∝ its area, each to the side of its voxel that faces its way.
        SurfaceSampleSet set;
        std::vector<SidePoint> points;
        forEachVoxelSidePoint(voxels, view, pointsPerVoxel, 0xB0CEu, [&](const VoxelSidePoint& p) {
            const VoxelSides sides = voxelSides(voxels.normal[p.voxel], voxels.axisWeights[p.voxel].data());
            int face = -1;
            for (int f = 0; f < 6; ++f)
                if (sides.sideOfFace[f] == p.side) face = f;
            if (face < 0) return;
            set.samples.push_back(p.sample);
            points.push_back({p.voxel, face, p.area, int(view.materialIds[p.sample.triangle])});
        });
        set.width = int(set.samples.size());
        set.height = 1;
        for (size_t k = 0; k <= set.samples.size(); ++k) set.begin.push_back(uint32_t(k));
        std::fprintf(stderr, "%zu surface points, %d paths each\n", set.samples.size(), spp);
        PathTracerSettings trace;
        trace.samplesPerPixel = spp;
        trace.quiet = true;
        const TraceResult traced = traceIrradiance(stages.tracing->traceScene, stages.tracing->bvh, set, trace);

        // Per voxel face: its area, ρ Σ E a by the path tracer; then per material (the face's
        // largest), the voxels' reflected power L·π·area against the path tracer's.
        struct FaceSum {
            double area = 0.0;
            glm::dvec3 exact{0.0}, direct{0.0};
            std::map<int, double> materialArea;
        };
        std::unordered_map<uint64_t, FaceSum> faces;
        for (size_t k = 0; k < points.size(); ++k) {
            const SidePoint& p = points[k];
            FaceSum& sum = faces[uint64_t(p.voxel) * 6 + uint64_t(p.face)];
            const glm::dvec3 albedo(set.samples[k].albedo);
            sum.area += p.area;
            sum.exact += p.area * albedo * glm::dvec3(traced.beauty.rgb(int(k), 0)) * double(kPi);
            sum.direct += p.area * albedo * glm::dvec3(traced.direct.rgb(int(k), 0)) * double(kPi);
            sum.materialArea[p.material] += p.area;
        }
        struct Totals {
            glm::dvec3 voxel{0.0}, exact{0.0}, direct{0.0};
            double area = 0.0;
        };
        std::map<int, Totals> byMaterial;
        Totals all;
        std::vector<uint64_t> keys;
        for (const auto& [key, sum] : faces) keys.push_back(key);
        std::sort(keys.begin(), keys.end());  // the same sums in the same order every run
        for (uint64_t key : keys) {
            const FaceSum& sum = faces[key];
            const glm::dvec3 L(voxels.faceRadiance[size_t(key / 6)][size_t(key % 6)]);
            int material = -1;
            double most = 0.0;
            for (const auto& [m, a] : sum.materialArea)
                if (a > most) material = m, most = a;
            for (Totals* t : {&byMaterial[material], &all}) {
                t->voxel += L * double(kPi) * sum.area;
                t->exact += sum.exact;
                t->direct += sum.direct;
                t->area += sum.area;
            }
        }
        std::printf("%-28s %10s %12s %12s %12s %8s\n", "material", "area m²", "voxels W", "traced W", "of it direct",
                    "ratio");
        const auto row = [](const std::string& name, const Totals& t) {
            std::printf("%-28s %10.3f %12.4f %12.4f %12.4f %8.3f\n", name.c_str(), t.area, mean3(t.voxel), mean3(t.exact),
                        mean3(t.direct), mean3(t.exact) > 0.0 ? mean3(t.voxel) / mean3(t.exact) : 0.0);
        };
        for (const auto& [m, t] : byMaterial)
            row(m >= 0 && size_t(m) < scene.materials.size() ? scene.materials[size_t(m)].name : "default", t);
        row("all", all);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
