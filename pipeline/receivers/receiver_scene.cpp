#include "receivers/receiver_scene.h"

#include "scene/scene.h"

namespace vl {

ReceiverScene::ReceiverScene(const Scene& scene, bool lightTrees)
    : triangles(gatherTriangles(scene)), bvh(Bvh::build(triangles)), traceScene(TraceScene::build(scene, triangles, lightTrees)),
      viewpoints(cameraViewpoints(scene)) {}

}  // namespace vl
