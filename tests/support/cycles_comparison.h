// Comparing a noisy estimate (our path tracer) with a Cycles reference: the channel means must
// agree within 1% of the reference plus 4σ of our mean's own Monte Carlo error.
#pragma once

#include "metrics/metrics.h"

#include <catch2/catch.hpp>

#include <cmath>

namespace vl::test {

inline void requireMeansAgree(const ErrorMetrics& metrics, const double (&sigmaMean)[3]) {
    for (int ch = 0; ch < 3; ++ch) {
        const double tolerance = 0.01 * metrics.meanReference[ch] + 4.0 * sigmaMean[ch];
        INFO("channel " << ch << ": ours " << metrics.meanTest[ch] << ", Cycles " << metrics.meanReference[ch]
                        << ", tolerance " << tolerance);
        REQUIRE(std::abs(metrics.meanTest[ch] - metrics.meanReference[ch]) <= tolerance);
    }
}

}  // namespace vl::test
