// How well the voxel direct-lighting pass holds the direct light of the surfaces inside each
// voxel: the light each voxel side reflects (faceRadiance · π / albedo, its irradiance) against
// the exact direct irradiance (lighting/direct_light.h: shadow rays against the triangles) averaged
// over points spread over the surface inside that voxel side, area-weighted. Reported as
// reflected power (albedo × E × area) by material and overall, the ratio voxels / exact: what
// the first bounce can at best carry. The job's sky is left out (the voxel pass does not hold
// it: the bounces gather it). An accuracy measurement, not a test and not a speed figure.
//
//   build/accuracy/accuracy_voxel_light JOB.json [--points-per-voxel N] [--write FILE.csv] [name=value …]
#include "bake/bake.h"
#include "bake/bake_job.h"
#include "bake/bake_settings.h"
#include "gather/bright_patches.h"
#include "lighting/direct_light.h"
#include "bake/job_file.h"
#include "gather/ray_gather.h"
#include "gather/irradiance_cache.h"
#include "cone/radiance_mips.h"
#include "bake/voxel_size.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "lighting/lighting.h"
#include "lighting/surface_light.h"
#include "scene/own_frame.h"
#include "voxel/voxelize.h"
#include "voxel_side_points.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

using namespace vl;

namespace {

struct SideSum {
    double area = 0.0;
    glm::dvec3 exact{0.0};   // Σ E·a
    glm::dvec3 albedo{0.0};  // Σ ρ·a
    std::map<int, double> materialArea;
};

double mean3(const glm::dvec3& v) { return (v.x + v.y + v.z) / 3.0; }

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2)
            throw SettingsError("usage: accuracy_voxel_light JOB.json [--points-per-voxel N] [--write FILE.csv] [name=value …]");
        int pointsPerVoxel = 16;
        std::string csv;
        BakeSettings defaults;
        defaults.quiet = true;
        std::vector<BakeJob> jobs = readJobFile(argv[1], defaults, "output");
        if (jobs.empty()) throw InputError(std::string(argv[1]) + ": no scenes");
        BakeJob job = jobs.front();
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--points-per-voxel" && i + 1 < argc)
                pointsPerVoxel = std::stoi(argv[++i]);
            else if (arg == "--write" && i + 1 < argc)
                csv = argv[++i];
            else
                applySetting(bakeSettingsTable(), job.settings, arg);
        }
        const BakeSettings& settings = job.settings;
        Scene scene = loadJobScene(job);
        scene.sky = Sky{};  // the voxel pass holds lights and emitters, not the sky
        if (settings.voxel.ownFrame) turnToOwnFrame(scene);
        const VoxelSizeChoice choice = chooseVoxelSize(scene, settings);
        VoxelSettings voxelSettings = settings.voxel;
        voxelSettings.voxelSize = choice.voxelSize;
        const double h = voxelSizeFor(scene, voxelSettings);
        anchorToVoxelGrid(scene, h);
        VoxelScene voxels = voxelize(scene, voxelSettings);
        std::fprintf(stderr, "%zu voxels of %.2f cm\n", voxels.size(), 100.0 * h);
        const ReceiverScene tracing(scene);
        const TraceSceneView view = tracing.traceScene.view();
        const BvhView bvh = tracing.bvh.view();
        const VoxelSurfacePoints surfacePoints = voxelSurfacePoints(voxels, view, settings.lighting.surfacePoints);
        if (settings.lighting.visibilityBy == VoxelVisibility::Rays)
            lightVoxelsByRays(voxels, surfacePoints, view, bvh, 0);
        else
            lightVoxels(scene, voxels, settings.lighting);

        // Points per triangle ∝ its area: pointsPerVoxel per h² of surface, at least one.
        std::vector<SideSum> sums(voxels.size() * 6);
        uint64_t samples = 0;
        forEachVoxelSidePoint(voxels, view, pointsPerVoxel, 0xACCu, [&](const VoxelSidePoint& p) {
            const vec3 E = directIrradiance(view, bvh, p.sample, settings.direct, p.draw);
            SideSum& sum = sums[size_t(p.voxel) * 6 + size_t(p.side)];
            sum.area += p.area;
            sum.exact += p.area * glm::dvec3(E);
            sum.albedo += p.area * glm::dvec3(p.sample.albedo);
            sum.materialArea[int(view.materialIds[p.sample.triangle])] += p.area;
            ++samples;
        });
        std::fprintf(stderr, "%llu surface points\n", static_cast<unsigned long long>(samples));

        // Per material: reflected power by the voxels (ρ_voxel/π·E_voxel·π = ρ E over the side's
        // area) and by the exact points.
        struct Totals {
            glm::dvec3 voxel{0.0}, exact{0.0};
            double area = 0.0;
        };
        std::map<int, Totals> byMaterial;
        Totals all;
        std::FILE* out = csv.empty() ? nullptr : std::fopen(csv.c_str(), "w");
        if (out) std::fprintf(out, "x,y,z,side,nx,ny,nz,area,material,voxel_E,exact_E\n");
        for (size_t v = 0; v < voxels.size(); ++v) {
            const VoxelSides sides = voxelSides(voxels.normal[v], voxels.axisWeights[v].data());
            for (int s = 0; s < sides.count; ++s) {
                const SideSum& sum = sums[v * 6 + size_t(s)];
                if (!(sum.area > 0.0)) continue;
                int face = -1;
                for (int f = 0; f < 6; ++f)
                    if (sides.sideOfFace[f] == s) face = f;
                const glm::dvec3 albedo = glm::dvec3(voxels.albedo[v]);
                const glm::dvec3 L = glm::dvec3(voxels.faceRadiance[v][size_t(face)]);
                // Reflected power: the voxel's L·π over the side's area; the exact ρ·E.
                glm::dvec3 reflectedExact(0.0);
                const glm::dvec3 meanAlbedo = sum.albedo / sum.area;
                reflectedExact = meanAlbedo * (sum.exact);  // ρ̄ Σ E a (albedo varies little within a voxel side)
                const glm::dvec3 reflectedVoxel = L * double(kPi) * sum.area;
                int material = -1;
                double most = 0.0;
                for (const auto& [m, a] : sum.materialArea)
                    if (a > most) material = m, most = a;
                Totals& t = byMaterial[material];
                t.voxel += reflectedVoxel;
                t.exact += reflectedExact;
                t.area += sum.area;
                all.voxel += reflectedVoxel;
                all.exact += reflectedExact;
                all.area += sum.area;
                if (out) {
                    const double voxelE = mean3(albedo) > 0.0 ? mean3(L) * kPi / mean3(albedo) : 0.0;
                    std::fprintf(out, "%d,%d,%d,%d,%.3f,%.3f,%.3f,%.6g,%d,%.6g,%.6g\n", voxels.coords[v].x,
                                 voxels.coords[v].y, voxels.coords[v].z, s, sides.normal[s].x, sides.normal[s].y,
                                 sides.normal[s].z, sum.area, material, voxelE, mean3(sum.exact) / sum.area);
                }
                (void)albedo;
            }
        }
        if (out) std::fclose(out);
        std::printf("%-28s %10s %12s %12s %8s\n", "material", "area m²", "voxels W", "exact W", "ratio");
        for (const auto& [m, t] : byMaterial) {
            const std::string name = m >= 0 && size_t(m) < scene.materials.size() ? scene.materials[size_t(m)].name : "default";
            std::printf("%-28s %10.3f %12.4f %12.4f %8.3f\n", name.c_str(), t.area, mean3(t.voxel), mean3(t.exact),
                        mean3(t.exact) > 0.0 ? mean3(t.voxel) / mean3(t.exact) : 0.0);
        }
        // The bright patches a final gather of this direct light would split off.
        const BrightPatchSplit split = splitBrightPatches(voxels, surfacePoints, settings.gather.brightPatches);
        double patchPower = 0.0;
        for (const BrightPatch& p : split.patches) patchPower += kPi * double(p.area) * mean3(glm::dvec3(p.radiance));
        std::printf("bright patches: %zu from %zu faces, power %.4f W (of %.4f W the voxels reflect)\n",
                    split.patches.size(), split.faces, patchPower, mean3(all.voxel));
        std::vector<BrightPatch> top = split.patches;
        std::sort(top.begin(), top.end(), [](const BrightPatch& a, const BrightPatch& b) {
            return a.area * (a.radiance.x + a.radiance.y + a.radiance.z) > b.area * (b.radiance.x + b.radiance.y + b.radiance.z);
        });
        const vec3 lo = [&] { vec3 m(1e30f); for (const Mesh& mesh : scene.meshes) for (const vec3& q : mesh.positions) m = glm::min(m, q); return m; }();
        const vec3 hi = [&] { vec3 m(-1e30f); for (const Mesh& mesh : scene.meshes) for (const vec3& q : mesh.positions) m = glm::max(m, q); return m; }();
        std::printf("scene box (local) %.2f %.2f %.2f .. %.2f %.2f %.2f\n", lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
        for (size_t k = 0; k < std::min<size_t>(top.size(), 25); ++k)
            std::printf("  patch at %6.2f %6.2f %6.2f n %5.2f %5.2f %5.2f area %.4f m² L %.3f power %.4f W\n", top[k].position.x,
                        top[k].position.y, top[k].position.z, top[k].normal.x, top[k].normal.y, top[k].normal.z, top[k].area,
                        mean3(glm::dvec3(top[k].radiance)), kPi * top[k].area * mean3(glm::dvec3(top[k].radiance)));
        // The patches' estimate at the final gather's points against rays that read the same
        // bright faces (64 × 64 per point): the estimator's bias alone.
        {
            std::vector<FaceRadiance> bright(voxels.size());
            for (size_t v = 0; v < voxels.size(); ++v)
                for (int f = 0; f < 6; ++f) bright[v][size_t(f)] = voxels.faceRadiance[v][size_t(f)] - split.restFaces[v][size_t(f)];
            const GatherScene enclosed{bvh, view};
            IrradianceCache cache(voxels, settings.gather.gatherLevel, &enclosed);
            const RadianceMips mips = buildRadianceMipsFor(voxels, MipReaders::RaysOnly);
            const std::vector<vec3> byRays = gatherByRays(cache.points(), mips.view(), bright, bvh, view, 64);
            std::vector<vec3> byPatches(cache.points().size(), vec3(0.0f));
            addBrightPatchIrradiance(cache.points(), fanOrigins(cache.points(), float(h), bvh, view), split, bvh,
                                     settings.gather.brightPatches.samples, byPatches);
            double sumRays = 0.0, sumPatches = 0.0;
            for (size_t k = 0; k < byRays.size(); ++k) {
                sumRays += mean3(glm::dvec3(byRays[k]));
                sumPatches += mean3(glm::dvec3(byPatches[k]));
            }
            std::printf("bright patches at %zu gather points: patches %.4f, rays %.4f (mean E), ratio %.3f\n",
                        byRays.size(), sumPatches / byRays.size(), sumRays / byRays.size(), sumPatches / sumRays);
            if (!csv.empty()) {
                std::FILE* pts = std::fopen((csv + ".points.csv").c_str(), "w");
                std::fprintf(pts, "x,y,z,nx,ny,nz,patches,rays\n");
                for (size_t k = 0; k < byRays.size(); ++k) {
                    const GatherPoint& q = cache.points()[k];
                    std::fprintf(pts, "%.3f,%.3f,%.3f,%.2f,%.2f,%.2f,%.5g,%.5g\n", q.position.x, q.position.y, q.position.z,
                                 q.normal.x, q.normal.y, q.normal.z, mean3(glm::dvec3(byPatches[k])), mean3(glm::dvec3(byRays[k])));
                }
                std::fclose(pts);
            }
        }
        std::printf("%-28s %10.3f %12.4f %12.4f %8.3f\n", "all", all.area, mean3(all.voxel), mean3(all.exact),
                    mean3(all.voxel) / mean3(all.exact));
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
