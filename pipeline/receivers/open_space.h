// The open space people stand in: cells of a grid over a scene's triangles that no triangle
// crosses, connected face to face to a viewpoint's cell (a camera the scene's author placed).
// A side of a surface that faces into it can be seen; one that faces into a sealed cavity (a
// closed solid's inside, the gap under a floor slab) cannot, whichever way it is wound.
#pragma once

#include "core/math.h"
#include "scene/scene.h"
#include "trace/trace_scene.h"

#include <cstdint>
#include <vector>

namespace vl {

struct Viewpoint {
    vec3 position{0.0f};
    vec3 forward{0.0f, 0.0f, -1.0f};  // unit: where it looks
};

class OpenSpace {
public:
    // Cells about 1/cellsAlongLongest of the triangles' longest extent, plus one cell of margin
    // all round; a triangle marks every cell a lattice of points on it at a third of a cell
    // apart meets, so no face-to-face path slips through a surface. A viewpoint outside the grid
    // starts from its margin; one in a marked cell, from the first free cell ahead of it within
    // eight cells, else nowhere. With no viewpoints, nothing is open.
    OpenSpace(const TraceSceneView& scene, const std::vector<Viewpoint>& viewpoints, int cellsAlongLongest = 160);

    bool open(const vec3& point) const;  // outside the grid: false
    bool empty() const { return state_.empty(); }
    float cellSize() const { return cell_; }

private:
    int64_t index(const vec3& point) const;  // -1 outside

    vec3 origin_{0.0f};
    float cell_ = 0.0f;
    int dims_[3] = {0, 0, 0};
    std::vector<uint8_t> state_;  // 0 free, 1 crossed by a triangle, 2 open
};

// Where the scene's own cameras stand (none: an empty list; the bake's default camera, framed
// from outside the scene's bounds, is not a place anyone stands).
std::vector<Viewpoint> cameraViewpoints(const Scene& scene);

}  // namespace vl
