#include "lightmap/dilate.h"

#include "core/error.h"

#include <vector>

namespace vl {

size_t dilatePadding(Image& image, const Image& mask, int passes) {
    if (mask.width != image.width || mask.height != image.height || mask.channels < 1)
        throw Error("dilatePadding: the mask is not the image's size");
    const int W = image.width, H = image.height, C = image.channels;
    const size_t texels = static_cast<size_t>(W) * H;
    std::vector<uint8_t> filled(texels);
    for (size_t i = 0; i < texels; ++i) filled[i] = mask.pixels[i * mask.channels] > 0.5f ? 1 : 0;

    // A pass fills exactly the unfilled texels next to a filled one, and those lie next to
    // what the pass before filled (else an earlier pass would have taken them): each pass
    // looks only there, so the whole dilation costs one visit per texel and its neighbours,
    // not one sweep of the image per pass (which at 1024² was a large share of a bake:
    // docs/lightmap-speed.md).
    const auto visitNeighbours = [&](size_t i, auto&& visit) {
        const int x = static_cast<int>(i % static_cast<size_t>(W)), y = static_cast<int>(i / static_cast<size_t>(W));
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int nx = x + dx, ny = y + dy;
                if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                visit(static_cast<size_t>(ny) * W + nx, nx, ny);
            }
    };
    std::vector<uint8_t> queued(texels, 0);
    std::vector<size_t> ring;
    for (size_t i = 0; i < texels; ++i) {
        if (filled[i]) continue;
        bool nextToFilled = false;
        visitNeighbours(i, [&](size_t j, int, int) { nextToFilled = nextToFilled || filled[j]; });
        if (nextToFilled) {
            ring.push_back(i);
            queued[i] = 1;
        }
    }

    size_t total = 0;
    std::vector<float> values;
    std::vector<double> sum(static_cast<size_t>(C));
    std::vector<size_t> next;
    for (int pass = 0; (passes < 0 || pass < passes) && !ring.empty(); ++pass) {
        values.clear();
        for (size_t i : ring) {
            std::fill(sum.begin(), sum.end(), 0.0);
            int count = 0;
            visitNeighbours(i, [&](size_t j, int nx, int ny) {
                if (!filled[j]) return;
                for (int c = 0; c < C; ++c) sum[static_cast<size_t>(c)] += image.at(nx, ny, c);
                ++count;
            });
            for (int c = 0; c < C; ++c) values.push_back(static_cast<float>(sum[static_cast<size_t>(c)] / count));
        }
        for (size_t k = 0; k < ring.size(); ++k) {
            filled[ring[k]] = 1;
            for (int c = 0; c < C; ++c) image.pixels[ring[k] * C + static_cast<size_t>(c)] = values[k * C + static_cast<size_t>(c)];
        }
        total += ring.size();
        next.clear();
        for (size_t i : ring)
            visitNeighbours(i, [&](size_t j, int, int) {
                if (filled[j] || queued[j]) return;
                queued[j] = 1;
                next.push_back(j);
            });
        ring.swap(next);
    }
    return total;
}

void fillUnseenShadowmask(Image& shadowmask, const Image& mask) {
    const size_t texels = size_t(shadowmask.width) * size_t(shadowmask.height);
    const size_t channels = size_t(shadowmask.channels);
    for (size_t c = 0; c < channels; ++c) {
        Image channel(shadowmask.width, shadowmask.height, 1), known(shadowmask.width, shadowmask.height, 1);
        bool any = false;
        for (size_t t = 0; t < texels; ++t) {
            const float v = shadowmask.pixels[t * channels + c];
            channel.pixels[t] = v;
            known.pixels[t] = mask.pixels[t * size_t(mask.channels)] > 0.5f && v >= 0.0f ? 1.0f : 0.0f;
            any = any || known.pixels[t] > 0.5f;
        }
        if (any) dilatePadding(channel, known);
        for (size_t t = 0; t < texels; ++t)
            shadowmask.pixels[t * channels + c] = any && channel.pixels[t] >= 0.0f ? channel.pixels[t] : 1.0f;
    }
}

}  // namespace vl
