// The bake's bounce series against the path tracer's, bounce by bounce: the path tracer
// limited to N bounces (no Russian roulette) against the bake with N − 1 voxel bounces and no
// tail, as the mean indirect radiance of the job's first camera image. Where the two part,
// the bake's per-bounce transfer is wrong; where they agree and the full bakes do not, the
// tail is. An accuracy measurement, not a test and not a speed figure.
//
//   build/accuracy/accuracy_bounces JOB.json [--spp N] [--bounces 1,2,3,5,9,17] [name=value …]
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "bake/job_file.h"
#include "bench/traced_scene.h"
#include "core/error.h"

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

using namespace vl;

namespace {

double meanOf(const Image& image) {
    double sum = 0.0;
    for (float v : image.pixels) sum += v;
    return image.pixels.empty() ? 0.0 : sum / double(image.pixels.size());
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) throw SettingsError("usage: accuracy_bounces JOB.json [--spp N] [--bounces 1,2,…] [name=value …]");
        int spp = 8;
        std::vector<int> counts = {1, 2, 3, 5, 9, 17};
        BakeSettings defaults;
        defaults.quiet = true;
        std::vector<BakeJob> jobs = readJobFile(argv[1], defaults, "output");
        if (jobs.empty()) throw InputError(std::string(argv[1]) + ": no scenes");
        BakeJob job = jobs.front();
        job.settings.quiet = true;
        job.settings.outputs.grids = job.settings.outputs.lightmaps = false;
        for (int i = 2; i < argc; ++i) {
            const std::string arg = argv[i];
            if (arg == "--spp" && i + 1 < argc) {
                spp = std::stoi(argv[++i]);
            } else if (arg == "--bounces" && i + 1 < argc) {
                counts.clear();
                std::stringstream list(argv[++i]);
                for (std::string item; std::getline(list, item, ',');) counts.push_back(std::stoi(item));
            } else {
                applySetting(bakeSettingsTable(), job.settings, arg);
            }
        }
        const BenchTraceScene traced = loadBenchTraceScene(job);
        if (!traced.camera) throw InputError(job.scenePath + ": no camera image to compare");
        const Scene scene = loadJobScene(job);
        for (int count : counts) {
            if (count < 1) throw SettingsError("--bounces: counts start at 1");
            PathTracerSettings path = benchPathSettings(spp, 1);
            path.path.maxBounces = count;
            path.path.russianRoulette = false;
            path.quiet = true;
            const double pathMean = meanOf(renderCamera(traced.trace, traced.bvh, *traced.camera, path).indirect);
            BakeSettings settings = job.settings;
            settings.bounces = count - 1;
            settings.bounceTail = false;
            Diagnostics diagnostics(false, false);
            const double bakeMean = meanOf(bake(scene, settings, diagnostics).images.at(0).indirect);
            std::printf("%2d bounce%s: path tracer %.4f, bake %.4f (%+.1f%%)\n", count, count == 1 ? " " : "s", pathMean,
                        bakeMean, 100.0 * (bakeMean / pathMean - 1.0));
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accuracy_bounces: %s\n", e.what());
        return 1;
    }
}
