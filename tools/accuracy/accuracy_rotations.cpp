// The default bake's lightmap error against Cycles on the Cycles Cornell boxes turned to N
// uniform random orientations (fixed seed): how far the voxel bake depends on how a scene is
// turned against the voxel grid (issue "Where a scene sits and how big it is…"). The
// lightmap's UV layout does not turn with the scene, so Cycles' unturned bake is the truth
// for every turn. An accuracy measurement, not a test and not a speed figure.
//
//   build/accuracy/accuracy_rotations [--turns N] [--only K] [--write DIR] [name=value …]
//   (bake settings; --only: turn K alone, 0 unturned; --write: each lightmap's total,
//   direct and indirect as DIR/<box>_turnK{,_direct,_indirect}.exr, to map where the error is)
//
// The bake turns each box into its own frame before it sizes it (scene/own_frame.h), so a
// `resolution` counts voxels along the box's own side at every turn; `grid-frame=world` keeps
// the grid on the world's axes, where a resolution counts along the turned box's axis-aligned
// bounds (up to √3 times its side: give `voxel-size`, 0.559 m / N, to compare counts there).
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "core/image_io.h"
#include "metrics/metrics.h"
#include "scene/gltf_loader.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace vl;

namespace {

// Turns the scene about its local origin (the centre of its bounds, Scene::origin).
void turn(Scene& scene, const glm::quat& q) {
    for (Mesh& mesh : scene.meshes) {
        for (vec3& p : mesh.positions) p = q * p;
        for (vec3& n : mesh.normals) n = q * n;
    }
    for (Light& light : scene.lights) {
        light.position = q * light.position;
        light.direction = q * light.direction;
    }
    for (Camera& camera : scene.cameras) {
        camera.position = q * camera.position;
        camera.forward = q * camera.forward;
        camera.up = q * camera.up;
    }
}

struct Errors {
    double total = 0.0, indirect = 0.0, indirectMean = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
    try {
        int turns = 16, only = -1;
        std::string writeDir;
        BakeSettings settings;
        settings.quiet = true;
        settings.outputs.grids = settings.outputs.images = false;
        for (int i = 1; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--turns" && i + 1 < argc) {
                turns = std::stoi(argv[++i]);
                continue;
            }
            if (arg == "--only" && i + 1 < argc) {
                only = std::stoi(argv[++i]);
                continue;
            }
            if (arg == "--write" && i + 1 < argc) {
                writeDir = argv[++i];
                continue;
            }
            applySetting(bakeSettingsTable(), settings, arg);
        }
        // Uniform random rotations: normalised 4-D Gaussian quaternions, fixed seed.
        std::mt19937_64 rng(20261124);
        std::normal_distribution<double> gaussian;
        std::vector<glm::quat> rotations = {glm::quat(1.0f, 0.0f, 0.0f, 0.0f)};
        for (int k = 0; k < turns; ++k) {
            double q[4], length = 0.0;
            for (double& c : q) {
                c = gaussian(rng);
                length += c * c;
            }
            length = std::sqrt(length);
            rotations.push_back(glm::quat(float(q[3] / length), float(q[0] / length), float(q[1] / length), float(q[2] / length)));
        }
        const std::string reference = std::string(VOXLIGHT_SOURCE_DIR) + "/../shared/reference/";
        for (const std::string name : {"quad", "point"}) {
            const std::string cycles = reference + "cycles/cornell_" + name;
            const Image total = readImage(cycles + "_lightmap_4096spp.exr");
            const Image direct = readImage(cycles + "_lightmap_direct_4096spp.exr");
            const Image mask = readImage(cycles + "_lightmap_mask.exr");
            Image indirect = total;
            for (size_t p = 0; p < indirect.pixels.size(); ++p) indirect.pixels[p] -= direct.pixels[p];
            MetricOptions options;
            options.mask = &mask;
            LoadOptions load;
            load.echoWarnings = false;
            const Scene original = loadGltf(reference + "cornell_" + name + ".gltf", load);
            std::vector<Errors> errors;
            for (size_t k = 0; k < rotations.size(); ++k) {
                if (only >= 0 && k != size_t(only)) continue;
                Scene scene = original;
                turn(scene, rotations[k]);
                Diagnostics diagnostics(false, false);
                const BakeResult result = bake(scene, settings, diagnostics);
                const BakedLightmap& lightmap = result.lightmaps.at(0);
                MetricOptions own = options;  // over the texels the bake holds its own light in
                own.testMask = &lightmap.mask;
                const ErrorMetrics t = compareImages(lightmap.total, total, own);
                const ErrorMetrics i = compareImages(lightmap.indirect, indirect, own);
                if (!writeDir.empty()) {
                    const std::string stem = writeDir + "/" + name + "_turn" + std::to_string(k);
                    writeExr(lightmap.total, stem + ".exr");
                    writeExr(lightmap.direct, stem + "_direct.exr");
                    writeExr(lightmap.indirect, stem + "_indirect.exr");
                }
                errors.push_back({t.relativeRmse, i.relativeRmse, i.meanTest[0] / i.meanReference[0] - 1.0});
                const glm::quat& q = rotations[k];
                std::printf("%-5s %s (%+.3f %+.3f %+.3f %+.3f): lightmap %.2f%%, indirect %.2f%% (mean %+.1f%%)\n",
                            name.c_str(), k == 0 ? "unturned" : ("turn " + std::to_string(k)).c_str(), q.w, q.x,
                            q.y, q.z, 100 * errors.back().total, 100 * errors.back().indirect,
                            100 * errors.back().indirectMean);
            }
            double lo = 1e9, hi = 0.0, sum = 0.0;
            for (size_t k = 1; k < errors.size(); ++k) {
                lo = std::min(lo, errors[k].total);
                hi = std::max(hi, errors[k].total);
                sum += errors[k].total;
            }
            if (errors.size() > 1)
                std::printf("%-5s unturned %.2f%%; %zu turns %.2f%% .. %.2f%%, mean %.2f%%\n", name.c_str(),
                            100 * errors[0].total, errors.size() - 1, 100 * lo, 100 * hi,
                            100 * sum / double(errors.size() - 1));
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accuracy_rotations: %s\n", e.what());
        return 1;
    }
}
