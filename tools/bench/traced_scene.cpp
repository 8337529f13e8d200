#include "bench/traced_scene.h"

#include "receivers/lightmap_sides.h"
#include "receivers/open_space.h"
#include "core/diagnostics.h"

#include <cmath>

namespace vl {

BenchTraceScene loadBenchTraceScene(const BakeJob& job) {
    BenchTraceScene s;
    s.scene = loadJobScene(job);
    s.triangles = gatherTriangles(s.scene);
    s.bvh = Bvh::build(s.triangles);
    s.trace = TraceScene::build(s.scene, s.triangles);
    if (job.settings.outputs.lightmaps) {
        Diagnostics diagnostics(job.settings.strict, false);
        std::vector<LightmapAtlas> atlases = buildLightmapReceivers(s.scene, job.settings.lightmap, diagnostics);
        if (!atlases.empty()) {
            s.atlas = std::move(atlases.front());
            // The side the bake's lightmap holds, so the reference traces the same surface.
            if (job.settings.lightmapSide == LightmapSide::Inside)
                orientLightmapSamples(s.atlas->receivers, s.bvh.view(), s.trace.view(), cameraViewpoints(s.scene));
        }
    }
    if (job.settings.outputs.images) {
        const BakeSettings& b = job.settings;
        const float aspect = static_cast<float>(b.imageWidth) / static_cast<float>(b.imageHeight);
        const Camera camera = s.scene.cameras.empty() ? defaultCamera(s.scene.bounds(), aspect) : s.scene.cameras.front();
        s.camera = makeCameraModel(camera, b.imageWidth, b.imageHeight);
    }
    return s;
}

PathTracerSettings benchPathSettings(int spp, uint64_t seed) {
    PathTracerSettings settings;
    settings.samplesPerPixel = spp;
    settings.filter = PixelFilter::Box;
    settings.seed = seed;
    settings.quiet = true;
    settings.validate();
    return settings;
}

double relativeNoise(const TraceResult& result, const Image* mask) {
    double variance = 0.0, mean = 0.0;
    size_t terms = 0;
    const Image& v = result.variance;
    const Image& b = result.beauty;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) {
            if (mask && !(mask->at(x, y) > 0.5f)) continue;
            for (int c = 0; c < 3; ++c) {
                variance += v.at(x, y, c);
                mean += b.at(x, y, c);
                ++terms;
            }
        }
    if (terms == 0 || mean == 0.0) return 0.0;
    return std::sqrt(variance / terms) / std::abs(mean / terms);
}

}  // namespace vl
