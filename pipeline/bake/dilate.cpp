#include "bake/dilate.h"

#include "core/error.h"

#include <vector>

namespace vl {

size_t dilatePadding(Image& image, const Image& mask, int passes) {
    if (mask.width != image.width || mask.height != image.height || mask.channels < 1)
        throw Error("dilatePadding: the mask is not the image's size");
    const int W = image.width, H = image.height, C = image.channels;
    std::vector<uint8_t> filled(static_cast<size_t>(W) * H);
    for (size_t i = 0; i < filled.size(); ++i) filled[i] = mask.pixels[i * mask.channels] > 0.5f ? 1 : 0;
    size_t total = 0;
    std::vector<size_t> ring;
    std::vector<float> values;
    for (int pass = 0; passes < 0 || pass < passes; ++pass) {
        ring.clear();
        values.clear();
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const size_t i = static_cast<size_t>(y) * W + x;
                if (filled[i]) continue;
                std::vector<double> sum(static_cast<size_t>(C), 0.0);
                int count = 0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int nx = x + dx, ny = y + dy;
                        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                        if (!filled[static_cast<size_t>(ny) * W + nx]) continue;
                        for (int c = 0; c < C; ++c) sum[static_cast<size_t>(c)] += image.at(nx, ny, c);
                        ++count;
                    }
                if (count == 0) continue;
                ring.push_back(i);
                for (int c = 0; c < C; ++c) values.push_back(static_cast<float>(sum[static_cast<size_t>(c)] / count));
            }
        if (ring.empty()) break;
        for (size_t k = 0; k < ring.size(); ++k) {
            filled[ring[k]] = 1;
            for (int c = 0; c < C; ++c) image.pixels[ring[k] * C + static_cast<size_t>(c)] = values[k * C + static_cast<size_t>(c)];
        }
        total += ring.size();
    }
    return total;
}

}  // namespace vl
