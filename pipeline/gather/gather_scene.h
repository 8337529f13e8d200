// What a gather's rays meet: the scene's BVH and its triangles, materials, lights and sky, as
// the views the kernels read (trace/).
#pragma once

#include "trace/bvh.h"
#include "trace/trace_scene.h"

namespace vl {

struct GatherScene {
    BvhView bvh;
    TraceSceneView scene;
};

}  // namespace vl
