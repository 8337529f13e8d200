#include "receivers/receiver_scene.h"

#include "scene/scene.h"

namespace vl {

ReceiverScene::ReceiverScene(const Scene& scene, bool lightTrees)
    : triangles(gatherTriangles(scene)), bvh(Bvh::build(triangles)), traceScene(TraceScene::build(scene, triangles, lightTrees)),
      viewpoints(cameraViewpoints(scene)) {
    // The vertices live on in traceScene (the same, triangle by triangle): a third copy of
    // them would be most of a large scene's memory after its BVH's.
    std::vector<vec3>().swap(triangles.vertices);
}

}  // namespace vl
