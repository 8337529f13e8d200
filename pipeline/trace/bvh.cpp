#include "trace/bvh.h"

#include "core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vl {

SceneTriangles gatherTriangles(const Scene& scene) {
    SceneTriangles out;
    const size_t total = scene.triangleCount();
    if (total >= 0xFFFFFFFFull)
        throw InputError(scene.sourcePath + ": " + std::to_string(total) + " triangles exceed the BVH's 32-bit ids");
    out.vertices.reserve(3 * total);
    out.meshIndex.reserve(total);
    out.localIndex.reserve(total);
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        const size_t count = mesh.triangleCount();
        for (size_t t = 0; t < count; ++t) {
            for (int k = 0; k < 3; ++k) {
                const uint32_t index = mesh.indices[3 * t + static_cast<size_t>(k)];
                if (index >= mesh.positions.size() || !isFinite(mesh.positions[index]))
                    throw InputError(scene.sourcePath + ": mesh '" + mesh.name + "' triangle " + std::to_string(t) +
                                     (index >= mesh.positions.size()
                                          ? ": vertex index " + std::to_string(index) + " out of range (" +
                                                std::to_string(mesh.positions.size()) + " positions)"
                                          : ": vertex " + std::to_string(index) + " is not finite"));
                out.vertices.push_back(mesh.positions[index]);
            }
            out.meshIndex.push_back(static_cast<uint32_t>(m));
            out.localIndex.push_back(static_cast<uint32_t>(t));
        }
    }
    return out;
}

namespace {

// Subtrees smaller than this are built on the calling thread: spawning costs more.
constexpr uint32_t kParallelThreshold = 4096;

constexpr int kMaxBins = 64;  // validate() keeps BvhSettings::bins within it

struct BinnedBounds {
    Aabb bounds;
    uint32_t count = 0;
};

// A node under construction. Slots are preassigned from the triangle range so parallel
// subtrees never contend and the result does not depend on scheduling: a leaf over
// [begin, end) lives at slot 2·begin, an inner node split at mid at slot 2·mid − 1, and the
// subtree over [begin, end) uses only slots [2·begin, 2·end − 1).
struct TempNode {
    Aabb bounds;
    uint32_t begin = 0, end = 0;
    uint32_t left = 0, right = 0;  // slots; inner nodes only
    bool leaf = true;
};

class Builder {
public:
    Builder(const SceneTriangles& tris, const BvhSettings& settings)
        : settings_(settings), triCount_(static_cast<uint32_t>(tris.vertices.size() / 3)) {
        triBounds_.resize(triCount_);
        centroids_.resize(triCount_);
        order_.resize(triCount_);
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, triCount_, 1024), [&](const tbb::blocked_range<uint32_t>& r) {
            for (uint32_t i = r.begin(); i != r.end(); ++i) {
                Aabb box;
                box.extend(tris.vertices[3 * size_t(i)]);
                box.extend(tris.vertices[3 * size_t(i) + 1]);
                box.extend(tris.vertices[3 * size_t(i) + 2]);
                triBounds_[i] = box;
                centroids_[i] = box.centre();
                order_[i] = i;
            }
        });
        temp_.resize(2 * size_t(triCount_) - 1);
    }

    uint32_t build() { return buildRange(0, triCount_, 0); }

    void flatten(Bvh& bvh, const SceneTriangles& tris, uint32_t rootSlot) {
        bvh.nodes.reserve(2 * size_t(triCount_));
        flattenNode(bvh, rootSlot);
        bvh.nodes.shrink_to_fit();
        bvh.triangleIds = order_;
        bvh.vertices.resize(3 * size_t(triCount_));
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, triCount_, 4096), [&](const tbb::blocked_range<uint32_t>& r) {
            for (uint32_t slot = r.begin(); slot != r.end(); ++slot)
                for (size_t k = 0; k < 3; ++k) bvh.vertices[3 * size_t(slot) + k] = tris.vertices[3 * size_t(order_[slot]) + k];
        });
    }

private:
    struct Split {
        int axis = -1;
        int bin = 0;         // triangles in bins [0, bin] go left
        float cost = 0.0f;   // SAH cost × node surface area
    };

    uint32_t makeLeaf(uint32_t begin, uint32_t end, const Aabb& bounds) {
        const uint32_t slot = 2 * begin;
        temp_[slot].bounds = bounds;
        temp_[slot].begin = begin;
        temp_[slot].end = end;
        temp_[slot].leaf = true;
        return slot;
    }

    static int ceilLog2(uint32_t n) {
        int bits = 0;
        while ((uint64_t(1) << bits) < n) ++bits;
        return bits;
    }

    uint32_t buildRange(uint32_t begin, uint32_t end, int depth) {
        const uint32_t n = end - begin;
        Aabb bounds, centroidBounds;
        auto boundRange = [&](uint32_t b, uint32_t e, Aabb* out) {
            for (uint32_t i = b; i < e; ++i) {
                out[0].extend(triBounds_[order_[i]]);
                out[1].extend(centroids_[order_[i]]);
            }
        };
        if (n < kChunkedThreshold) {
            Aabb out[2];
            boundRange(begin, end, out);
            bounds = out[0];
            centroidBounds = out[1];
        } else {
            forChunks<Aabb>(begin, end, boundRange, 2, [&](const Aabb* part) {
                bounds.extend(part[0]);
                centroidBounds.extend(part[1]);
            });
        }
        if (n == 1) return makeLeaf(begin, end, bounds);

        const uint32_t maxLeaf = static_cast<uint32_t>(settings_.maxLeafSize);
        // SAH may split very unevenly; once the depth budget gets tight, halve by object
        // median so the tree never outgrows the traversal stack.
        const bool depthTight = depth + ceilLog2(n) >= kBvhMaxDepth;
        uint32_t mid = begin;
        if (!depthTight) {
            const Split split = findSplit(begin, end, bounds, centroidBounds);
            const float leafCost = settings_.intersectionCost * float(n) * bounds.surfaceArea();
            if (split.axis >= 0 && (split.cost < leafCost || n > maxLeaf)) {
                const int axis = split.axis;
                const float lo = centroidBounds.lower[axis];
                const float scale = binScale(centroidBounds, axis);
                const int bins = settings_.bins;
                mid = static_cast<uint32_t>(
                    std::partition(order_.begin() + begin, order_.begin() + end,
                                   [&](uint32_t id) { return binOf(centroids_[id][axis], lo, scale, bins) <= split.bin; }) -
                    order_.begin());
            } else if (n <= maxLeaf) {
                return makeLeaf(begin, end, bounds);
            }
        } else if (n <= maxLeaf) {
            return makeLeaf(begin, end, bounds);
        }
        if (mid == begin || mid == end) {
            // No usable SAH split (coincident centroids) or the depth cap: object median on
            // the widest centroid axis, ties by id so the order is fully determined.
            const int axis = centroidBounds.longestAxis();
            mid = begin + n / 2;
            std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                             [&](uint32_t a, uint32_t b) {
                                 const float ca = centroids_[a][axis], cb = centroids_[b][axis];
                                 return ca < cb || (ca == cb && a < b);
                             });
        }

        uint32_t left = 0, right = 0;
        if (n >= kParallelThreshold) {
            tbb::parallel_invoke([&] { left = buildRange(begin, mid, depth + 1); },
                                 [&] { right = buildRange(mid, end, depth + 1); });
        } else {
            left = buildRange(begin, mid, depth + 1);
            right = buildRange(mid, end, depth + 1);
        }
        const uint32_t slot = 2 * mid - 1;
        TempNode& node = temp_[slot];
        node.bounds = bounds;
        node.begin = begin;
        node.end = end;
        node.left = left;
        node.right = right;
        node.leaf = false;
        return slot;
    }

    static float binScale(const Aabb& centroidBounds, int axis) {
        const float extent = centroidBounds.upper[axis] - centroidBounds.lower[axis];
        return extent > 0.0f ? 1.0f / extent : 0.0f;
    }

    static int binOf(float c, float lo, float scale, int bins) {
        const int b = static_cast<int>(float(bins) * ((c - lo) * scale));
        return std::min(std::max(b, 0), bins - 1);
    }

    // Ranges this large are bounded and binned in parallel chunks (the top of the tree,
    // where parallel_invoke has not yet spread the work).
    static constexpr uint32_t kChunkedThreshold = 65536;

    // Runs work(b, e, partial) over fixed chunks of [begin, end) in parallel, each into its
    // own `parts` default-initialised T values, then merge(partial) in chunk order. The
    // chunking depends on the range only, and every merge here is a min/max or an integer
    // sum, so the result is the same at any thread count (and equals the one-pass result).
    template <typename T, typename Work, typename Merge>
    static void forChunks(uint32_t begin, uint32_t end, Work&& work, size_t parts, Merge&& merge) {
        constexpr uint32_t kChunk = 16384;
        const uint32_t chunks = (end - begin + kChunk - 1) / kChunk;
        std::vector<T> partial(size_t(chunks) * parts);
        tbb::parallel_for(uint32_t(0), chunks, [&](uint32_t c) {
            work(begin + c * kChunk, std::min(end, begin + (c + 1) * kChunk), partial.data() + size_t(c) * parts);
        });
        for (uint32_t c = 0; c < chunks; ++c) merge(partial.data() + size_t(c) * parts);
    }

    Split findSplit(uint32_t begin, uint32_t end, const Aabb& bounds, const Aabb& centroidBounds) const {
        const int bins = settings_.bins;
        float scale[3], lo[3];
        for (int axis = 0; axis < 3; ++axis) {
            scale[axis] = binScale(centroidBounds, axis);
            lo[axis] = centroidBounds.lower[axis];
        }
        BinnedBounds bin[3][kMaxBins];
        if (end - begin < kChunkedThreshold) {
            for (int axis = 0; axis < 3; ++axis) {
                if (scale[axis] == 0.0f) continue;
                for (uint32_t i = begin; i < end; ++i) {
                    const uint32_t id = order_[i];
                    BinnedBounds& target = bin[axis][binOf(centroids_[id][axis], lo[axis], scale[axis], bins)];
                    target.bounds.extend(triBounds_[id]);
                    ++target.count;
                }
            }
        } else {
            forChunks<BinnedBounds>(begin, end, [&](uint32_t b, uint32_t e, BinnedBounds* out) {
                for (int axis = 0; axis < 3; ++axis) {
                    if (scale[axis] == 0.0f) continue;
                    for (uint32_t i = b; i < e; ++i) {
                        const uint32_t id = order_[i];
                        BinnedBounds& target = out[axis * bins + binOf(centroids_[id][axis], lo[axis], scale[axis], bins)];
                        target.bounds.extend(triBounds_[id]);
                        ++target.count;
                    }
                }
            }, size_t(3 * bins), [&](const BinnedBounds* part) {
                for (int axis = 0; axis < 3; ++axis)
                    for (int b = 0; b < bins; ++b) {
                        bin[axis][b].bounds.extend(part[axis * bins + b].bounds);
                        bin[axis][b].count += part[axis * bins + b].count;
                    }
            });
        }

        Split best;
        float rightArea[kMaxBins];
        uint32_t rightCount[kMaxBins];
        const float nodeArea = bounds.surfaceArea();
        for (int axis = 0; axis < 3; ++axis) {
            if (scale[axis] == 0.0f) continue;
            const BinnedBounds* axisBins = bin[axis];
            Aabb acc;
            uint32_t count = 0;
            for (int b = bins - 1; b > 0; --b) {
                acc.extend(axisBins[b].bounds);
                count += axisBins[b].count;
                rightArea[b] = acc.surfaceArea();
                rightCount[b] = count;
            }
            acc = Aabb{};
            count = 0;
            for (int b = 0; b < bins - 1; ++b) {
                acc.extend(axisBins[b].bounds);
                count += axisBins[b].count;
                if (count == 0 || rightCount[b + 1] == 0) continue;
                const float cost = settings_.traversalCost * nodeArea +
                                   settings_.intersectionCost *
                                       (acc.surfaceArea() * float(count) + rightArea[b + 1] * float(rightCount[b + 1]));
                if (best.axis < 0 || cost < best.cost) {
                    best.axis = axis;
                    best.bin = b;
                    best.cost = cost;
                }
            }
        }
        return best;
    }

    uint32_t flattenNode(Bvh& bvh, uint32_t slot) {
        const TempNode& t = temp_[slot];
        const uint32_t index = static_cast<uint32_t>(bvh.nodes.size());
        bvh.nodes.push_back(BvhNode{t.bounds, t.leaf ? t.begin : 0u, t.leaf ? t.end - t.begin : 0u});
        if (!t.leaf) {
            flattenNode(bvh, t.left);  // lands at index + 1
            const uint32_t right = flattenNode(bvh, t.right);
            bvh.nodes[index].firstOrChild = right;
        }
        return index;
    }

    const BvhSettings& settings_;
    uint32_t triCount_;
    std::vector<Aabb> triBounds_;
    std::vector<vec3> centroids_;
    std::vector<uint32_t> order_;
    std::vector<TempNode> temp_;
};

// Collapses the binary tree four-wide: starting from a node's two children, the inner
// child with the largest surface area is replaced by its two children until there are four
// (SAH's own measure of how likely a ray is to enter it). Returns the wide node's index.
uint32_t collapseWide(const std::vector<BvhNode>& nodes, uint32_t binary, std::vector<BvhWideNode>& wide) {
    uint32_t lanes[4];
    int laneCount = 0;
    if (nodes[binary].count > 0) {
        lanes[laneCount++] = binary;  // the whole tree is one leaf
    } else {
        lanes[laneCount++] = binary + 1;
        lanes[laneCount++] = nodes[binary].firstOrChild;
        while (laneCount < 4) {
            int widest = -1;
            float widestArea = -1.0f;
            for (int i = 0; i < laneCount; ++i) {
                const BvhNode& n = nodes[lanes[i]];
                if (n.count == 0 && n.bounds.surfaceArea() > widestArea) {
                    widest = i;
                    widestArea = n.bounds.surfaceArea();
                }
            }
            if (widest < 0) break;
            const uint32_t expanded = lanes[widest];
            lanes[widest] = expanded + 1;
            lanes[laneCount++] = nodes[expanded].firstOrChild;
        }
    }
    const uint32_t index = static_cast<uint32_t>(wide.size());
    wide.emplace_back();
    BvhWideNode node{};
    for (int i = 0; i < 4; ++i) {
        if (i >= laneCount) {
            node.lowerX[i] = node.lowerY[i] = node.lowerZ[i] = 0.0f;
            node.upperX[i] = node.upperY[i] = node.upperZ[i] = 0.0f;
            node.child[i] = 0;
            node.count[i] = kBvhEmptyLane;
            continue;
        }
        const BvhNode& n = nodes[lanes[i]];
        node.lowerX[i] = n.bounds.lower.x;
        node.lowerY[i] = n.bounds.lower.y;
        node.lowerZ[i] = n.bounds.lower.z;
        node.upperX[i] = n.bounds.upper.x;
        node.upperY[i] = n.bounds.upper.y;
        node.upperZ[i] = n.bounds.upper.z;
        node.count[i] = n.count;
        node.child[i] = n.count > 0 ? n.firstOrChild : collapseWide(nodes, lanes[i], wide);
    }
    wide[index] = node;
    return index;
}

void validate(const BvhSettings& s) {
    if (s.bins < 2 || s.bins > kMaxBins)
        throw SettingsError("BVH setting bins = " + std::to_string(s.bins) + " is outside [2, " + std::to_string(kMaxBins) + "]");
    if (s.maxLeafSize < 1 || s.maxLeafSize > 1024)
        throw SettingsError("BVH setting maxLeafSize = " + std::to_string(s.maxLeafSize) + " is outside [1, 1024]");
    if (!(s.traversalCost >= 0.0f && std::isfinite(s.traversalCost)))
        throw SettingsError("BVH setting traversalCost = " + std::to_string(s.traversalCost) + " must be finite and >= 0");
    if (!(s.intersectionCost > 0.0f && std::isfinite(s.intersectionCost)))
        throw SettingsError("BVH setting intersectionCost = " + std::to_string(s.intersectionCost) +
                            " must be finite and > 0");
}

}  // namespace

Bvh Bvh::build(const SceneTriangles& triangles, const BvhSettings& settings) {
    validate(settings);
    if (triangles.vertices.size() % 3 != 0)
        throw InputError("BVH input has " + std::to_string(triangles.vertices.size()) +
                         " vertices, not a multiple of 3");
    if (triangles.vertices.size() / 3 >= 0xFFFFFFFFull)
        throw InputError("BVH input has too many triangles for 32-bit ids");
    for (size_t i = 0; i < triangles.vertices.size(); ++i)
        if (!isFinite(triangles.vertices[i]))
            throw InputError("BVH input triangle " + std::to_string(i / 3) + " has a non-finite vertex");
    Bvh bvh;
    if (triangles.vertices.empty()) return bvh;
    Builder builder(triangles, settings);
    const uint32_t root = builder.build();
    builder.flatten(bvh, triangles, root);
    bvh.wideNodes.reserve(bvh.nodes.size() / 2 + 1);
    collapseWide(bvh.nodes, 0, bvh.wideNodes);
    bvh.wideNodes.shrink_to_fit();
    return bvh;
}

BvhView Bvh::view() const {
    BvhView v;
    v.nodes = nodes.data();
    v.vertices = vertices.data();
    v.triangleIds = triangleIds.data();
    v.nodeCount = static_cast<uint32_t>(nodes.size());
    v.wideNodes = wideNodes.empty() ? nullptr : wideNodes.data();
    v.wideNodeCount = static_cast<uint32_t>(wideNodes.size());
    if (!nodes.empty()) {
        const float largest = maxComponent(nodes[0].bounds.upper - nodes[0].bounds.lower);
        if (largest > 0.0f && isFinite(largest)) v.extent = largest;
    }
    return v;
}

size_t Bvh::memoryBytes() const {
    return nodes.capacity() * sizeof(BvhNode) + wideNodes.capacity() * sizeof(BvhWideNode) +
           vertices.capacity() * sizeof(vec3) + triangleIds.capacity() * sizeof(uint32_t);
}

const Aabb& Bvh::bounds() const {
    static const Aabb kEmpty{};
    return nodes.empty() ? kEmpty : nodes[0].bounds;
}

}  // namespace vl
