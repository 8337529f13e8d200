// What receivers trace against: the scene's triangles, their BVH, the traced scene (materials,
// lights, sky) and where people stand in it. Built once per scene; a lightmap atlas's rows, a
// camera's pixels and the gather's rays all read it.
#pragma once

#include "receivers/open_space.h"
#include "trace/bvh.h"
#include "trace/trace_scene.h"

#include <vector>

namespace vl {

struct Scene;

struct ReceiverScene {
    // Each triangle's mesh and index in it; its vertices are traceScene's (vertices empty).
    SceneTriangles triangles;
    Bvh bvh;
    TraceScene traceScene;
    std::vector<Viewpoint> viewpoints;  // the scene's own cameras: where people stand (receivers/open_space.h)
    // lightTrees: past 64 lights, receivers take a cut of a tree of them (trace/light_tree.h).
    explicit ReceiverScene(const Scene& scene, bool lightTrees = true);
};

}  // namespace vl
