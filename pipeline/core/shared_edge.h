// Two triangles that share an edge, as a quad split along its diagonal is exported: the
// emitters' patches (lighting/lighting.cpp) and the receivers' parallelogram quads
// (trace/trace_scene.cpp, lighting/direct_light.h) are found and laid out from this.
#pragma once

#include "core/hostdev.h"
#include "core/math.h"

namespace vl {

struct SharedEdge {
    int shared = 0;  // corners of b that are corners of a (2: they share an edge)
    int ownA = -1;   // the corner of a that b lacks (−1: none)
    int ownB = -1;   // the corner of b that a lacks
};

// Corners compare exactly: the halves of an exported quad reuse its vertices.
VL_HOSTDEV inline SharedEdge sharedEdge(const vec3* a, const vec3* b) {
    SharedEdge e;
    for (int i = 0; i < 3; ++i) {
        if (!(a[i] == b[0] || a[i] == b[1] || a[i] == b[2])) e.ownA = i;
        if (b[i] == a[0] || b[i] == a[1] || b[i] == a[2])
            ++e.shared;
        else
            e.ownB = i;
    }
    return e;
}

}  // namespace vl
