#include "receivers/open_space.h"

#include "core/aabb.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace vl {

OpenSpace::OpenSpace(const TraceSceneView& scene, const std::vector<Viewpoint>& viewpoints, int cellsAlongLongest) {
    Aabb box;
    for (size_t i = 0; i < 3 * size_t(scene.triangleCount); ++i) box.extend(scene.vertices[i]);
    if (box.empty() || viewpoints.empty() || cellsAlongLongest < 1) return;
    const vec3 extent = box.extent();
    const float longest = std::max(extent.x, std::max(extent.y, extent.z));
    if (!(longest > 0.0f)) return;
    cell_ = longest / float(cellsAlongLongest);
    origin_ = box.lower - vec3(cell_);
    for (int a = 0; a < 3; ++a) dims_[a] = int(std::ceil(extent[a] / cell_)) + 2;
    state_.assign(size_t(dims_[0]) * size_t(dims_[1]) * size_t(dims_[2]), 0);

    // Points on each triangle no more than a third of a cell apart along its edges; triangles in
    // parallel, each cell's mark a relaxed atomic store (any order leaves the same marks).
    const float spacing = cell_ / 3.0f;
    std::vector<std::atomic<uint8_t>> crossed(state_.size());
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, scene.triangleCount), [&](const tbb::blocked_range<uint32_t>& range) {
        for (uint32_t t = range.begin(); t < range.end(); ++t) {
            const vec3* v = scene.vertices + 3 * size_t(t);
            const float edge = std::max(glm::length(v[1] - v[0]), std::max(glm::length(v[2] - v[1]), glm::length(v[0] - v[2])));
            const int steps = std::max(1, int(std::ceil(edge / spacing)));
            for (int i = 0; i <= steps; ++i)
                for (int j = 0; i + j <= steps; ++j) {
                    const float a = float(i) / float(steps), b = float(j) / float(steps);
                    const int64_t k = index(v[0] + a * (v[1] - v[0]) + b * (v[2] - v[0]));
                    if (k >= 0) crossed[size_t(k)].store(1, std::memory_order_relaxed);
                }
        }
    });
    for (size_t k = 0; k < state_.size(); ++k) state_[k] = crossed[k].load(std::memory_order_relaxed);

    // Face-to-face from every viewpoint's free cell.
    std::vector<int64_t> frontier;
    for (const Viewpoint& view : viewpoints) {
        // A viewpoint outside the grid stands in the open air round it: the margin. One in a
        // crossed cell (a camera set against a wall, or in a window's frame) starts at the
        // first free cell it looks into, up to eight cells out.
        int64_t k = index(view.position) >= 0 ? index(view.position) : 0;
        for (int step = 1; step <= 16 && k >= 0 && state_[size_t(k)] == 1; ++step)
            k = index(view.position + (0.5f * cell_ * float(step)) * view.forward);
        if (k >= 0 && state_[size_t(k)] == 0) {
            state_[size_t(k)] = 2;
            frontier.push_back(k);
        }
    }
    const int64_t stride[3] = {1, dims_[0], int64_t(dims_[0]) * dims_[1]};
    while (!frontier.empty()) {
        const int64_t k = frontier.back();
        frontier.pop_back();
        const int64_t c[3] = {k % dims_[0], (k / dims_[0]) % dims_[1], k / stride[2]};
        for (int a = 0; a < 3; ++a)
            for (int step : {-1, 1}) {
                if (c[a] + step < 0 || c[a] + step >= dims_[a]) continue;
                const int64_t n = k + step * stride[a];
                if (state_[size_t(n)] != 0) continue;
                state_[size_t(n)] = 2;
                frontier.push_back(n);
            }
    }
}

std::vector<Viewpoint> cameraViewpoints(const Scene& scene) {
    std::vector<Viewpoint> points;
    for (const Camera& camera : scene.cameras) points.push_back({camera.position, camera.forward});
    return points;
}

int64_t OpenSpace::index(const vec3& point) const {
    if (state_.empty()) return -1;
    int64_t c[3];
    for (int a = 0; a < 3; ++a) {
        const float f = std::floor((point[a] - origin_[a]) / cell_);
        if (!(f >= 0.0f) || f >= float(dims_[a])) return -1;
        c[a] = int64_t(f);
    }
    return c[0] + dims_[0] * (c[1] + int64_t(dims_[1]) * c[2]);
}

bool OpenSpace::open(const vec3& point) const {
    const int64_t k = index(point);
    return k >= 0 && state_[size_t(k)] == 2;
}

}  // namespace vl
