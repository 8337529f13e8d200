// Cycles as the bench's peer: a headless Blender (tools/bench/cycles_bake.py) bakes the same
// lightmap atlas and renders the same camera at several spp in this run, on this machine; and
// Cycles results computed elsewhere (the lower-spp files of ../shared/reference/cycles with
// their timings.json) as a second, labelled, curve.
#pragma once

#include "bench/run.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace vl {

struct CyclesPeer {
    bool available = false;
    std::string blender;  // executable
    std::string script;
    std::string why;      // when unavailable: a sentence for the report
};

// Blender from options.blender or the PATH, and the script; unavailable (with why) otherwise.
CyclesPeer findCyclesPeer(const BenchOptions& options);

using CompareOutputs = std::function<void(BenchPointResult&, const std::filesystem::path& dir)>;

// Runs Blender once for p.spec.spp: lightmap (total and direct: 3.4's indirect-only bake is
// zero) and image; times are the script's own around each bake/render (Blender's start-up and
// the glTF import are not counted: generous to Cycles). Throws Error with the log's tail.
void runCyclesPoint(const BenchOptions& options, const CyclesPeer& peer, BenchPointResult& p, const CompareOutputs& compare);

using CompareStems = std::function<void(BenchPointResult&, const std::filesystem::path& dir, const std::string& lightmapStem,
                                        const std::string& imageStem)>;

// Points for <scene stem>_lightmap_<N>spp.exr / _render_<N>spp.exr in `dir` (not the named
// reference files), timed by timings.json's "lightmap_<variant>_<N>spp" / "render_<variant>_<N>spp"
// (variant: the stem's last word, "quad" of cornell_quad); empty when none match.
std::vector<BenchPointResult> cyclesFilePoints(const std::string& dir, const std::string& scenePath,
                                               const BenchReferenceFiles& reference, const CompareStems& compare);

}  // namespace vl
