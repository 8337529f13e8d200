// Fills lightmap padding from the covered texels around it, so bilinear filtering and mip
// maps at chart edges do not pull in black. Pass by pass, every unfilled texel with at least
// one filled 8-neighbour takes the mean of those neighbours and counts as filled for the
// next pass. Covered texels never change. Deterministic (each pass reads the previous one).
#pragma once

#include "core/image.h"

namespace vl {

// mask: 1 channel, > 0.5 = covered. passes < 0: until no padding texel next to a filled one
// is left. Returns the number of texels filled.
size_t dilatePadding(Image& image, const Image& mask, int passes = -1);

// A shadowmask (gather/shadowmask.h, RGBA) finished as a lightmap's padding is, channel by
// channel: every texel that is padding (mask ≤ 0.5) or holds a negative value (scene.h
// kShadowmaskUnseen) takes its neighbours' values by dilatePadding, from the covered texels
// that hold a value. A channel with no such texel anywhere is 1 (no texel faces its light:
// nothing for it to shadow).
void fillUnseenShadowmask(Image& shadowmask, const Image& mask);

}  // namespace vl
