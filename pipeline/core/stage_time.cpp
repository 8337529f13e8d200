#include "core/stage_time.h"

namespace vl {

double stageSeconds(const std::vector<StageTime>& stages, const std::string& stage) {
    double seconds = 0.0;
    for (const StageTime& t : stages)
        if (t.stage == stage) seconds += t.seconds;
    return seconds;
}

double totalSeconds(const std::vector<StageTime>& stages) {
    double seconds = 0.0;
    for (const StageTime& t : stages) seconds += t.seconds;
    return seconds;
}

}  // namespace vl
