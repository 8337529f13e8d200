// The reference path tracer's host entry points: camera images and irradiance at surface
// samples (lightmap texels), each split into direct and indirect light. Work runs on TBB over
// rows / element blocks; every pixel or element draws sample j's path from
// Pcg32::forItem(index, j, seed) (camera pixel and lens positions from a stratified pattern
// rotated per pixel, trace/sample_patterns.h), so the output bytes do not depend on the
// thread count or on how the work is split.
// The per-path kernels are in trace/path_kernels.h.
#pragma once

#include "core/image.h"
#include "trace/camera.h"
#include "trace/path_kernels.h"

#include <cstdint>

namespace vl {

class Bvh;
class TraceScene;

struct PathTracerSettings {
    int samplesPerPixel = 64;  // per pixel, or per texel for irradiance
    PathSettings path;         // max bounces (64, as Cycles' references), Russian roulette from bounce 5
    PixelFilter filter = PixelFilter::Tent;
    uint64_t seed = 0;
    bool quiet = false;        // no progress on stderr

    // Throws SettingsError naming the setting.
    void validate() const;
};

struct TraceResult {
    Image beauty;    // RGB: direct + indirect (camera: radiance; irradiance: E/π)
    Image direct;
    Image indirect;
    Image albedo;    // camera: base colour at the first hit; irradiance: mean sample albedo
    Image variance;  // RGB: variance of each pixel's mean as if its samples were independent
                     // (sample variance / spp); an overestimate where the stratified pixel
                     // pattern resolves an edge
    uint64_t nonFiniteSamples = 0;  // samples dropped for a NaN/Inf value (counted, never written)
    uint64_t paths = 0;
    double seconds = 0.0;
};

TraceResult renderCamera(const TraceScene& scene, const Bvh& bvh, const CameraModel& camera,
                         const PathTracerSettings& settings);

// E/π per element of `receivers` (zero where an element has no sample). The spp of an
// element are shared among its receiver samples in proportion to their weights, in order
// (sample j goes where the cumulative weight passes (j + ½)/spp): with n equal-weight
// samples and spp a multiple of n, every sub-texel position gets spp/n paths.
TraceResult traceIrradiance(const TraceScene& scene, const Bvh& bvh, const SurfaceSampleSet& receivers,
                            const PathTracerSettings& settings);

}  // namespace vl
