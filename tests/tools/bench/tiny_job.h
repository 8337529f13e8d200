// The bench tests' job: the project's Cornell box at sizes that bake in a fraction of a second
// (16 voxels along its longest axis, a 32² lightmap, a 24² image).
#pragma once

#include "bake/bake_job.h"
#include "support/paths.h"

#include <string>
#include <utility>
#include <vector>

namespace vl::test {

inline BakeJob tinyJob(const std::string& output) {
    BakeJob job;
    job.scenePath = sourceDir() + "/scenes/cornell_box.gltf";
    job.outputDir = output;
    for (const auto& [name, value] : std::vector<std::pair<std::string, std::string>>{
             {"resolution", "16"}, {"lightmap-res", "32"}, {"lightmap-subsamples", "2"}, {"width", "24"},
             {"height", "24"}, {"image-subsamples", "1"}, {"emitter-strata", "2"}, {"voxel-emitter-strata", "1"}})
        applySetting(bakeSettingsTable(), job.settings, name, value);
    job.settings.quiet = true;
    return job;
}

}  // namespace vl::test
