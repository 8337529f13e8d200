// A bounding hierarchy over many lights, so that a receiver's direct light costs what it sees
// and not how many lights the scene holds. Takes the lights' bounds (a box, a cone holding
// every emitting normal, a scalar power); gives a binary tree whose nodes bound their lights,
// and an unbiased estimator of a sum over the lights at one receiver:
//   * a cut: from the root, the node of largest importance (its power over the squared
//     distance, times bounds on both cosines) is replaced by its children until the cut holds
//     `budget` nodes or only single lights; children that provably send nothing are dropped;
//   * each single light of the cut is evaluated exactly; each node of several is sampled, one
//     light of it reached by descending to a child with probability ∝ its importance, its
//     contribution divided by that probability.
// Near and bright lights therefore end up alone in the cut, exact as the loop over every light
// gave them; only the far clusters carry noise, and a light is dropped only where its bounds
// show it cannot reach the receiver (the estimate is unbiased). The importance follows the
// many-lights bounds of Conty Estevez and Kulla (2018), written here in cosines only.
#pragma once

#include "core/hostdev.h"
#include "core/math.h"
#include "core/rng.h"

#include <cstdint>
#include <vector>

namespace vl {

struct LightTreeNode {
    // The box of every point that emits (a point light: its position), as its centre and half
    // extent, and the radius of the sphere about it that holds the box.
    vec3 centre{0.0f};
    vec3 half{0.0f};
    float radius = 0.0f;
    vec3 axis{0.0f, 0.0f, 1.0f};  // the emitting normals' cone: every one within its half-angle of axis
    float cosSpread = -1.0f;      // cos of that half-angle; −1: light leaves every way (points, two-sided)
    float sinSpread = 0.0f;
    float power = 0.0f;  // Σ of the lights' powers: what a light sends a receiver facing it, × d²
    uint32_t first = 0;  // a leaf: its light's item; else its children, first and first + 1
    uint32_t leaf = 0;
};

struct LightTreeView {
    const LightTreeNode* nodes = nullptr;  // the root first; null: no tree (few lights)
    uint32_t nodeCount = 0;
};

// The most nodes a cut holds.
constexpr int kMaxLightCut = 64;
// A scene with more than this many point and spot lights, or emissive triangles, has them in
// a tree (TraceSceneView); with fewer every receiver visits each, as exactly as before.
constexpr uint32_t kLightTreeFrom = 64;

// An upper bound, up to the power's scale, on what node sends a receiver at p whose shading
// normal is ns (zero: none of its lights can light p's side). ns zero: no receiver cosine.
VL_HOSTDEV inline float lightTreeImportance(const LightTreeNode& node, const vec3& p, const vec3& ns) {
    if (!(node.power > 0.0f)) return 0.0f;
    // The box decides first, exactly where the sphere below is coarse (p inside it): the box
    // wholly under p's horizon, or p behind every emitting normal the cone allows (the angle to
    // each point of the box at least 90° plus the cone's half-angle, under 90°). The largest of
    // a linear function over a box, and its farthest corner, in closed form.
    const bool normals = glm::dot(ns, ns) > 0.0f;
    const vec3 toNode = node.centre - p;
    if (normals && !(glm::dot(ns, toNode) + glm::dot(glm::abs(ns), node.half) > 0.0f)) return 0.0f;
    if (node.cosSpread > 0.0f) {
        const vec3 far = glm::abs(toNode) + node.half;
        const float inFront = -glm::dot(node.axis, toNode) + glm::dot(glm::abs(node.axis), node.half);
        if (!(inFront > -node.sinSpread * glm::length(far))) return 0.0f;
    }
    const float radius = node.radius;
    const float distance2 = glm::dot(toNode, toNode);
    const float distance = glm::sqrt(distance2);
    // The cone from p that holds the node's bounding sphere: cos and sin of its half-angle.
    const bool inside = !(distance > radius);
    const float sinBound = inside ? 1.0f : radius / distance;
    const float cosBound = inside ? -1.0f : glm::sqrt(glm::max(0.0f, 1.0f - sinBound * sinBound));
    const vec3 wi = distance > 0.0f ? toNode / distance : vec3(0.0f);
    // cos(max(0, θ − β)) from cos θ, sin θ and β's cos and sin (1 when θ ≤ β).
    const auto cosReduced = [](float cosTheta, float sinTheta, float cosBeta, float sinBeta) {
        if (cosTheta >= cosBeta) return 1.0f;
        return cosTheta * cosBeta + sinTheta * sinBeta;
    };
    float cosReceiver = 1.0f;
    if (!inside && normals) {
        const float c = glm::clamp(glm::dot(ns, wi), -1.0f, 1.0f);
        cosReceiver = cosReduced(c, glm::sqrt(glm::max(0.0f, 1.0f - c * c)), cosBound, sinBound);
        if (!(cosReceiver > 0.0f)) return 0.0f;
    }
    float cosEmitter = 1.0f;
    if (!inside && node.cosSpread > -1.0f) {
        // The angle between the cone's axis and the way to p, less the cone and the bound.
        const float c = glm::clamp(-glm::dot(node.axis, wi), -1.0f, 1.0f);
        const float s = glm::sqrt(glm::max(0.0f, 1.0f - c * c));
        if (c < node.cosSpread) {
            const float cosLess = c * node.cosSpread + s * node.sinSpread;
            const float sinLess = glm::max(0.0f, s * node.cosSpread - c * node.sinSpread);
            cosEmitter = cosReduced(cosLess, sinLess, cosBound, sinBound);
            if (!(cosEmitter > 0.0f)) return 0.0f;
        }
    }
    const float d2 = glm::max(distance2, radius * radius);
    if (!(d2 > 0.0f)) return node.power;
    return node.power * cosReceiver * cosEmitter / d2;
}

// Σ over the tree's lights at p, estimated as the header says. leaf(item, k, alone) returns
// light item's contribution: k (0 ≤ k < budget) numbers the evaluations so that each can draw
// points of its own, and alone says the light is a node of the cut by itself (false: it stands
// for its node's other lights too, and a cheaper estimate of it costs less noise than its
// draw adds). `seed` seeds the descents. Deterministic per seed.
template <typename Leaf>
VL_HOSTDEV inline vec3 estimateLightTree(const LightTreeView& tree, const vec3& p, const vec3& ns, int budget,
                                         uint64_t seed, Leaf&& leaf) {
    if (!tree.nodes || tree.nodeCount == 0) return vec3(0.0f);
    budget = glm::clamp(budget, 1, kMaxLightCut);
    uint32_t cut[kMaxLightCut];
    float importance[kMaxLightCut];
    int count = 0;
    const float rootImportance = lightTreeImportance(tree.nodes[0], p, ns);
    if (!(rootImportance > 0.0f)) return vec3(0.0f);
    cut[count] = 0;
    importance[count++] = rootImportance;
    for (;;) {
        int split = -1;
        for (int j = 0; j < count; ++j)
            if (!tree.nodes[cut[j]].leaf && (split < 0 || importance[j] > importance[split])) split = j;
        if (split < 0) break;
        const uint32_t children = tree.nodes[cut[split]].first;
        const float left = lightTreeImportance(tree.nodes[children], p, ns);
        const float right = lightTreeImportance(tree.nodes[children + 1], p, ns);
        const int added = (left > 0.0f ? 1 : 0) + (right > 0.0f ? 1 : 0);
        if (count - 1 + added > budget) break;
        // The split node's place goes to its first child that can light p, or to the last node.
        int at = split;
        if (left > 0.0f) {
            cut[at] = children;
            importance[at] = left;
            at = count;
        }
        if (right > 0.0f) {
            cut[at] = children + 1;
            importance[at] = right;
            at = count;
        }
        if (added == 0) {
            cut[split] = cut[count - 1];
            importance[split] = importance[count - 1];
        }
        count += added - 1;
        if (count == 0) return vec3(0.0f);
    }
    vec3 sum(0.0f);
    for (int k = 0; k < count; ++k) {
        uint32_t node = cut[k];
        const bool alone = tree.nodes[node].leaf != 0;
        float probability = 1.0f;
        Pcg32 draws = Pcg32::forItem(seed, uint64_t(k), 0x54524545ull);  // "TREE"
        bool reached = true;
        while (!tree.nodes[node].leaf) {
            const uint32_t children = tree.nodes[node].first;
            const float left = lightTreeImportance(tree.nodes[children], p, ns);
            const float right = lightTreeImportance(tree.nodes[children + 1], p, ns);
            if (!(left + right > 0.0f)) {
                reached = false;  // neither child can light p: this part sends nothing
                break;
            }
            const float pLeft = left / (left + right);
            const bool goLeft = draws.next1D() < pLeft;
            probability *= goLeft ? pLeft : 1.0f - pLeft;
            node = goLeft ? children : children + 1;
        }
        if (!reached || !(probability > 0.0f)) continue;
        sum += leaf(tree.nodes[node].first, k, alone) * (1.0f / probability);
    }
    return sum;
}

// One light's bounds, for building.
struct LightBounds {
    vec3 boundsMin{0.0f};
    vec3 boundsMax{0.0f};
    vec3 axis{0.0f, 0.0f, 1.0f};
    float cosSpread = -1.0f;  // −1: every direction
    float power = 0.0f;
    uint32_t item = 0;
};

// The tree over `lights` (any order; the same lights give the same tree). Empty for none.
std::vector<LightTreeNode> buildLightTree(std::vector<LightBounds> lights);

}  // namespace vl
