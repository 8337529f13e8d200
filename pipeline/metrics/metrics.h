// Error metrics between a test image (a bake, a render) and a reference, over the first
// three channels (one for single-channel images), RGB pooled: every included pixel adds
// its channels as separate terms. A mask restricts the pixels (lightmap covered texels);
// excludeReferenceAbove drops pixels whose reference exceeds a value in any channel (the
// emitter in a render, as ../shared/reference/README.md does with 5). Input containing NaN
// or Inf, or images of different sizes, is an InputError naming the image and the pixel.
#pragma once

#include "core/image.h"

#include <cstddef>
#include <string>

namespace vl {

struct MetricOptions {
    const Image* mask = nullptr;        // pixel included where channel 0 > 0.5; null = all
    // And where this one's channel 0 > 0.5, when given: the test's own coverage (a bake's
    // lightmap mask, which leaves out the texels inside closed geometry it fills from their
    // neighbours, where a reference bake holds black).
    const Image* testMask = nullptr;
    float excludeReferenceAbove = 0.0f;  // > 0: drop pixels with any reference channel above it
    double relMseEpsilon = 1e-2;        // relMSE = mean((t − r)² / (r² + ε))
    double smapeEpsilon = 1e-2;         // SMAPE = mean(|t − r| / (|t| + |r| + ε))
    std::string testName = "test";      // how messages name the two images
    std::string referenceName = "reference";
};

struct ErrorMetrics {
    size_t pixels = 0;          // included pixels
    double rmse = 0.0;          // √ mean (t − r)², RGB pooled
    double relativeRmse = 0.0;  // rmse / |mean(r)|, RGB pooled (InputError when only the mean is 0)
    double relMse = 0.0;
    double smape = 0.0;
    double meanTest[3] = {0.0, 0.0, 0.0};       // per channel over the included pixels
    double meanReference[3] = {0.0, 0.0, 0.0};
};

ErrorMetrics compareImages(const Image& test, const Image& reference, const MetricOptions& options = {});

// The single numbers, for callers that want one.
double relativeRmse(const Image& test, const Image& reference, const MetricOptions& options = {});
double relMse(const Image& test, const Image& reference, const MetricOptions& options = {});
double smape(const Image& test, const Image& reference, const MetricOptions& options = {});

}  // namespace vl
