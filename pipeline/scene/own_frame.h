// A scene's own frame: the axes of its two most common surface orientations (area-weighted; a
// normal and its opposite are one orientation) and their cross product, each taken as the
// signed local axis it lies nearest. A room modelled at an angle to the world axes has its
// walls along its own axes; the bake turns the scene into them before it sizes and voxelizes
// it (bake.h; VoxelSettings::ownFrame, the setting grid-frame), so the voxel grid runs along
// the walls whatever the turn.
//
// Why: walls at an angle to the grid cross its voxels in staircases, and the voxel bake's
// error against Cycles depends on that alignment; a grid along the scene's own axes bakes
// every turn as the unturned scene (docs/decisions.md, "The scene's own frame").
#pragma once

#include "scene/scene.h"

namespace vl {

// Own axes less than this far from the local axes are taken as them. Why: a wall 0.5° off an
// axis steps by one voxel across 115 voxels, no more than a modelled scene's own skew, and a
// turn that small changes only which voxel walls lying on voxel faces fall in
// (docs/decisions.md, "The scene's own frame").
constexpr double kOwnFrameMinTurn = 0.5 * 3.14159265358979323846 / 180.0;  // radians

// The own frame's axes in `scene`'s local frame (columns), a rotation: column k is the own
// axis nearest local axis k, signed to point along it. The identity, exactly, for a scene
// without triangles, one with a single orientation (a plane), and one whose own axes are
// within kOwnFrameMinTurn of the local axes (an axis-aligned scene, and any quarter turn of
// one).
glm::dmat3 ownFrameAxes(const Scene& scene);

// Turns `scene` into its own frame (Scene::turnFrame): afterwards its own axes are its local
// axes. Returns false, changing nothing, where they already are.
bool turnToOwnFrame(Scene& scene);

}  // namespace vl
