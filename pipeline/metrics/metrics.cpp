#include "metrics/metrics.h"

#include "core/error.h"

#include <algorithm>
#include <cmath>

namespace vl {
namespace {

std::string pixelName(int x, int y, int c) {
    return "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") channel " + std::to_string(c);
}

void checkFinite(const Image& image, const std::string& name) {
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < image.channels; ++c)
                if (!std::isfinite(image.at(x, y, c)))
                    throw InputError(name + ": " + pixelName(x, y, c) + " is not finite (" +
                                     std::to_string(image.at(x, y, c)) + ")");
}

}  // namespace

ErrorMetrics compareImages(const Image& test, const Image& reference, const MetricOptions& options) {
    const std::string names = options.testName + " vs " + options.referenceName;
    if (test.width != reference.width || test.height != reference.height)
        throw InputError(names + ": sizes differ (" + std::to_string(test.width) + " x " + std::to_string(test.height) +
                         " and " + std::to_string(reference.width) + " x " + std::to_string(reference.height) + ")");
    if (test.empty() || reference.empty()) throw InputError(names + ": an image is empty");
    const int channels = std::min({test.channels, reference.channels, 3});
    if (channels != std::min(test.channels, 3) || channels != std::min(reference.channels, 3))
        throw InputError(names + ": channel counts differ (" + std::to_string(test.channels) + " and " +
                         std::to_string(reference.channels) + ")");
    for (const Image* mask : {options.mask, options.testMask})
        if (mask && (mask->width != test.width || mask->height != test.height || mask->channels < 1))
            throw InputError(names + ": the " + (mask == options.mask ? "mask" : options.testName + "'s mask") + " is " +
                             std::to_string(mask->width) + " x " + std::to_string(mask->height) +
                             ", not the images' size");
    checkFinite(test, options.testName);
    checkFinite(reference, options.referenceName);
    if (options.mask) checkFinite(*options.mask, "mask");
    if (options.testMask) checkFinite(*options.testMask, options.testName + "'s mask");

    ErrorMetrics m;
    double sumSq = 0.0, sumRel = 0.0, sumSmape = 0.0, sumRef = 0.0;
    double sumT[3] = {0, 0, 0}, sumR[3] = {0, 0, 0};
    for (int y = 0; y < test.height; ++y)
        for (int x = 0; x < test.width; ++x) {
            if (options.mask && !(options.mask->at(x, y, 0) > 0.5f)) continue;
            if (options.testMask && !(options.testMask->at(x, y, 0) > 0.5f)) continue;
            if (options.excludeReferenceAbove > 0.0f) {
                bool bright = false;
                for (int c = 0; c < channels; ++c) bright = bright || reference.at(x, y, c) > options.excludeReferenceAbove;
                if (bright) continue;
            }
            ++m.pixels;
            for (int c = 0; c < channels; ++c) {
                const double t = test.at(x, y, c), r = reference.at(x, y, c);
                const double d = t - r;
                sumSq += d * d;
                sumRel += d * d / (r * r + options.relMseEpsilon);
                sumSmape += std::abs(d) / (std::abs(t) + std::abs(r) + options.smapeEpsilon);
                sumRef += r;
                sumT[c] += t;
                sumR[c] += r;
            }
        }
    if (m.pixels == 0) throw InputError(names + ": the mask leaves no pixel to compare");
    const double terms = static_cast<double>(m.pixels) * channels;
    m.rmse = std::sqrt(sumSq / terms);
    const double meanRef = sumRef / terms;
    if (m.rmse > 0.0 && meanRef == 0.0)
        throw InputError(names + ": the reference's mean is 0, so a relative error is undefined");
    m.relativeRmse = m.rmse == 0.0 ? 0.0 : m.rmse / std::abs(meanRef);
    m.relMse = sumRel / terms;
    m.smape = sumSmape / terms;
    for (int c = 0; c < channels; ++c) {
        m.meanTest[c] = sumT[c] / m.pixels;
        m.meanReference[c] = sumR[c] / m.pixels;
    }
    return m;
}

double relativeRmse(const Image& test, const Image& reference, const MetricOptions& options) {
    return compareImages(test, reference, options).relativeRmse;
}

double relMse(const Image& test, const Image& reference, const MetricOptions& options) {
    return compareImages(test, reference, options).relMse;
}

double smape(const Image& test, const Image& reference, const MetricOptions& options) {
    return compareImages(test, reference, options).smape;
}

}  // namespace vl
