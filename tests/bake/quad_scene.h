// The rooms of support/room_scenes.h, and the quiet, lightmap-only settings most bake tests
// start from.
#pragma once

#include "bake/bake.h"
#include "bake/bake_settings.h"
#include "scene/scene.h"
#include "support/room_scenes.h"

#include <tbb/global_control.h>

#include <string>

namespace vl::test {

// No progress output, no camera images, no grids.vdb: the lightmaps alone.
inline BakeSettings quietSettings() {
    BakeSettings settings;
    settings.quiet = true;
    settings.outputs.images = false;
    settings.outputs.grids = false;
    return settings;
}

// The bake of `scene` on at most `threads` threads, its warnings kept quiet: for the tests
// that a bake is the same bytes at any thread count.
inline BakeResult bakeOnThreads(const Scene& scene, const BakeSettings& settings, int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Diagnostics diagnostics(false, false);
    return bake(scene, settings, diagnostics);
}

}  // namespace vl::test
