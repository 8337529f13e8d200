// Which side of a double-sided surface a lightmap holds. A texel has one value, a double-sided
// triangle two sides: the receivers face the triangle's front (its winding), and exporters set
// the winding of thin panels (window frames, jambs, shutters) as they please. Where the front
// faces the sun outdoors and the room sees the back, the viewer showed the sunlit front's light
// on the shaded inner face. Takes an atlas's samples and the traced scene; gives the samples
// with those on double-sided triangles turned to the side that sees less open sky (the side a
// person inside the room sees), where the difference is clear, and left facing front otherwise.
#pragma once

#include "receivers/open_space.h"
#include "trace/bvh.h"
#include "trace/surface_samples.h"
#include "trace/trace_scene.h"

#include <string>
#include <vector>

namespace vl {

enum class LightmapSide {
    Front,   // the triangle's winding, whatever it is
    Inside,  // a double-sided triangle's side that sees less open sky
};

// Changes when the rule below does: caches of what it decides (the bench's references) key on it.
constexpr int kLightmapSideRule = 4;

LightmapSide parseLightmapSide(const std::string& text);  // SettingsError naming lightmap-side
const char* toString(LightmapSide side);

// Per triangle of double-sided material holding samples: 16 cosine rays on each side, from four
// points of it. A side inside a closed solid is never taken: most of its rays meet its own
// material from behind, or all of them meet something from behind and it faces no open space
// the viewpoints (receivers/open_space.h) reach. Otherwise the back is taken when the front is
// enclosed or its rays leave the scene at least 4 fewer times, or, where the sky does not tell
// them apart, when the front's rays meet something four times nearer (a frame's face against
// its wall). Where one side is sealed at those points and the other sees outdoors, each sample
// that faces open space on the sealed side holds that side (a wall's strip above a panel hung
// on it). The same bytes at any thread count. Returns the triangles turned (wholly or in part).
size_t orientLightmapSamples(SurfaceSampleSet& samples, const BvhView& bvh, const TraceSceneView& scene,
                             const std::vector<Viewpoint>& viewpoints);

}  // namespace vl
