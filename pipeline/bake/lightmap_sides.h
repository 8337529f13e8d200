// Which side of a double-sided surface a lightmap holds. A texel has one value, a double-sided
// triangle two sides: the receivers face the triangle's front (its winding), and exporters set
// the winding of thin panels (window frames, jambs, shutters) as they please. Where the front
// faces the sun outdoors and the room sees the back, the viewer showed the sunlit front's light
// on the shaded inner face. Takes an atlas's samples and the traced scene; gives the samples
// with those on double-sided triangles turned to the side that sees less open sky (the side a
// person inside the room sees), where the difference is clear, and left facing front otherwise.
#pragma once

#include "trace/bvh.h"
#include "trace/surface_samples.h"
#include "trace/trace_scene.h"

#include <string>

namespace vl {

enum class LightmapSide {
    Front,   // the triangle's winding, whatever it is
    Inside,  // a double-sided triangle's side that sees less open sky
};

LightmapSide parseLightmapSide(const std::string& text);  // SettingsError naming lightmap-side
const char* toString(LightmapSide side);

// Per triangle of double-sided material holding samples: 16 cosine rays on each side, from four
// points of it. A side most of whose rays meet triangles from behind is inside a closed solid and
// never taken; otherwise the back is taken when the front is enclosed or its rays leave the
// scene at least 4 fewer times. The same bytes at any thread count. Returns the triangles turned.
size_t orientLightmapSamples(SurfaceSampleSet& samples, const BvhView& bvh, const TraceSceneView& scene);

}  // namespace vl
