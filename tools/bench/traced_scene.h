// What the bench's path-tracer points and path-traced reference share: the job's scene
// (with its added lights) loaded and made traceable, the first lightmap atlas's receivers
// (the shared atlas unless atlas groups take every mesh) and the first camera (or the
// bake's default view) at the bake's image size.
#pragma once

#include "bake/bake_job.h"
#include "receivers/receivers.h"
#include "trace/bvh.h"
#include "trace/camera.h"
#include "trace/path_tracer.h"
#include "trace/trace_scene.h"

#include <optional>

namespace vl {

struct BenchTraceScene {
    Scene scene;
    SceneTriangles triangles;
    Bvh bvh;
    TraceScene trace;
    std::optional<LightmapAtlas> atlas;  // absent when no mesh has TEXCOORD_1 or lightmaps are off
    std::optional<CameraModel> camera;   // absent when images are off
};

BenchTraceScene loadBenchTraceScene(const BakeJob& job);

// Path-tracer settings of the bench: a box pixel filter, as the bake's n × n primary rays and
// Cycles' 1-pixel box filter, so the three compare pixel by pixel.
PathTracerSettings benchPathSettings(int spp, uint64_t seed);

// Estimated relative noise of a path-traced result: √(mean variance of the element means) /
// |mean value| over the included elements (mask channel 0 > 0.5; null = all), RGB pooled.
double relativeNoise(const TraceResult& result, const Image* mask);

}  // namespace vl
