// Wall time per named stage of a bake ("voxelize", "bounces", "lightmaps" …): bake.json's
// stages, the bench's columns.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace vl {

struct StageTime {
    std::string stage;
    double seconds = 0.0;
};

// The seconds of the stages named `stage` (0 when there is none) and of all of them.
double stageSeconds(const std::vector<StageTime>& stages, const std::string& stage);
double totalSeconds(const std::vector<StageTime>& stages);

// Runs `work` as the stage `name`, appending its wall time to `stages` (also when it throws),
// and returns what `work` returns.
template <typename F>
auto timed(std::vector<StageTime>& stages, const std::string& name, F&& work) {
    struct Record {
        std::vector<StageTime>& stages;
        const std::string& name;
        std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
        ~Record() {
            stages.push_back({name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
        }
    } record{stages, name};
    return work();
}

}  // namespace vl
