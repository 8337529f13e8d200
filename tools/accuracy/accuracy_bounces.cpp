// The bake's bounce series against the path tracer's, bounce by bounce: the path tracer
// limited to N bounces (no Russian roulette) against the bake with N − 1 voxel bounces and no
// tail, as the mean indirect radiance of the job's first camera image. Where the two part,
// the bake's per-bounce transfer is wrong; where they agree and the full bakes do not, the
// tail is. An accuracy measurement, not a test and not a speed figure. --region takes the mean
// over a window of pixels instead of the whole image, to follow a bias a heat map shows.
//
//   build/accuracy/accuracy_bounces JOB.json [--spp N] [--bounces 1,2,3,5,9,17] [--region x0,y0,x1,y1] [name=value …]
#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "bake/job_file.h"
#include "bench/traced_scene.h"
#include "core/error.h"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

using namespace vl;

namespace {

struct Region {
    int x0 = 0, y0 = 0, x1 = 1 << 30, y1 = 1 << 30;  // pixels [x0, x1) × [y0, y1)
};

double meanOf(const Image& image, const Region& region) {
    double sum = 0.0;
    size_t count = 0;
    for (int y = std::max(0, region.y0); y < std::min(image.height, region.y1); ++y)
        for (int x = std::max(0, region.x0); x < std::min(image.width, region.x1); ++x)
            for (int c = 0; c < image.channels; ++c) {
                sum += image.at(x, y, c);
                ++count;
            }
    if (count == 0) throw SettingsError("--region holds no pixel of the image");
    return sum / double(count);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) throw SettingsError("usage: accuracy_bounces JOB.json [--spp N] [--bounces 1,2,…] [name=value …]");
        int spp = 8;
        std::vector<int> counts = {1, 2, 3, 5, 9, 17};
        Region region;
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
            } else if (arg == "--region" && i + 1 < argc) {
                if (std::sscanf(argv[++i], "%d,%d,%d,%d", &region.x0, &region.y0, &region.x1, &region.y1) != 4 ||
                    region.x1 <= region.x0 || region.y1 <= region.y0)
                    throw SettingsError(std::string("--region: '") + argv[i] + "' is not x0,y0,x1,y1 with x0 < x1, y0 < y1");
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
            const double pathMean = meanOf(renderCamera(traced.trace, traced.bvh, *traced.camera, path).indirect, region);
            BakeSettings settings = job.settings;
            settings.gather.bounces = count - 1;
            settings.gather.bounceTail = false;
            Diagnostics diagnostics(false, false);
            const double bakeMean = meanOf(bake(scene, settings, diagnostics).images.at(0).indirect, region);
            std::printf("%2d bounce%s: path tracer %.4f, bake %.4f (%+.1f%%)\n", count, count == 1 ? " " : "s", pathMean,
                        bakeMean, 100.0 * (bakeMean / pathMean - 1.0));
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accuracy_bounces: %s\n", e.what());
        return 1;
    }
}
