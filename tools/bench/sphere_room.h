// A scene made for the bench's triangle axis: a closed room lit by a lamp under its ceiling,
// holding a grid of spheres whose tessellation sets the scene's triangle count. Every mesh
// carries TEXCOORD_1 in a cell of its own of one atlas, the same cells at any triangle count:
// the lightmap's covered texels stay the same while the triangles grow, so a lightmap that
// costs more per texel costs it for the triangles alone.
#pragma once

#include "scene/scene.h"

#include <cstddef>

namespace vl {

// About `triangles` triangles (within 0.1% from 30,000; at least the room's and 8 per sphere).
Scene sphereRoom(size_t triangles);

}  // namespace vl
