// The tree of many lights (trace/light_tree.h) against the sums it stands for: unbiased over
// seeds, exact when the cut holds every light, and never dropping a light that can reach.
#include "trace/light_tree.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace vl;

namespace {

struct PointLight {
    vec3 position;
    float intensity;
};

// What a point light sends a receiver at p with normal n, unshadowed: I·max(n·ω, 0)/d².
float pointContribution(const PointLight& light, const vec3& p, const vec3& n) {
    const vec3 d = light.position - p;
    const float d2 = glm::dot(d, d);
    return light.intensity * glm::max(0.0f, glm::dot(n, d) / std::sqrt(d2)) / d2;
}

std::vector<PointLight> scatteredLights(int count, uint64_t seed) {
    Pcg32 rng(seed, 1);
    std::vector<PointLight> lights;
    for (int i = 0; i < count; ++i) {
        float x, y, z, w;
        rng.next2D(x, y);
        rng.next2D(z, w);
        // Powers over two decades, one light a hundred times the others' mean.
        const float intensity = i == 7 ? 300.0f : 0.1f + 9.9f * w * w;
        lights.push_back({vec3(10.0f * x - 5.0f, 1.0f + 4.0f * y, 10.0f * z - 5.0f), intensity});
    }
    return lights;
}

LightTreeView viewOf(const std::vector<LightTreeNode>& nodes) { return {nodes.data(), uint32_t(nodes.size())}; }

std::vector<LightTreeNode> treeOf(const std::vector<PointLight>& lights) {
    std::vector<LightBounds> bounds;
    for (size_t i = 0; i < lights.size(); ++i) {
        LightBounds b;
        b.boundsMin = b.boundsMax = lights[i].position;
        b.power = lights[i].intensity;
        b.item = uint32_t(i);
        bounds.push_back(b);
    }
    return buildLightTree(bounds);
}

}  // namespace

TEST_CASE("A light tree's estimate is unbiased: over seeds its mean is the sum over every light", "[trace]") {
    const std::vector<PointLight> lights = scatteredLights(300, 11);
    const std::vector<LightTreeNode> nodes = treeOf(lights);
    REQUIRE(nodes.size() == 2 * lights.size() - 1);
    Pcg32 rng(5, 2);
    for (int r = 0; r < 12; ++r) {
        float x, z, a, b;
        rng.next2D(x, z);
        rng.next2D(a, b);
        const vec3 p(8.0f * x - 4.0f, 0.0f, 8.0f * z - 4.0f);
        // Floors, and receivers tilted up to 60° off the vertical.
        const vec3 n = glm::normalize(vec3(std::cos(6.283f * a) * b, 0.6f, std::sin(6.283f * a) * b));
        double exact = 0.0;
        for (const PointLight& light : lights) exact += pointContribution(light, p, n);
        const int seeds = 4000;
        double sum = 0.0, squares = 0.0;
        for (int s = 0; s < seeds; ++s) {
            const float e = estimateLightTree(viewOf(nodes), p, n, 8, uint64_t(s) * 7919u + uint64_t(r),
                                              [&](uint32_t item, int, bool) { return vec3(pointContribution(lights[item], p, n)); })
                                .x;
            sum += e;
            squares += double(e) * e;
        }
        const double mean = sum / seeds;
        const double spread = std::sqrt(std::max(0.0, squares / seeds - mean * mean));
        const double standardError = spread / std::sqrt(double(seeds));
        INFO("receiver " << r << ": exact " << exact << ", mean of " << seeds << " estimates " << mean
                         << ", one estimate's relative deviation " << spread / exact);
        // Within four standard errors of the mean (a false alarm about once in 16,000), and
        // the mean within 1% of the sum.
        CHECK(std::abs(mean - exact) < 4.0 * standardError + 1e-6 * exact);
        CHECK(std::abs(mean - exact) < 0.01 * exact);
    }
}

TEST_CASE("A light tree's cut that holds every light is the exact sum, whatever the seed", "[trace]") {
    const std::vector<PointLight> lights = scatteredLights(24, 3);
    const std::vector<LightTreeNode> nodes = treeOf(lights);
    const vec3 p(0.3f, 0.0f, -0.2f), n(0.0f, 1.0f, 0.0f);
    double exact = 0.0;
    for (const PointLight& light : lights) exact += pointContribution(light, p, n);
    for (uint64_t seed = 0; seed < 20; ++seed) {
        int evaluations = 0;
        const float e = estimateLightTree(viewOf(nodes), p, n, 32, seed, [&](uint32_t item, int, bool) {
                            ++evaluations;
                            return vec3(pointContribution(lights[item], p, n));
                        }).x;
        CHECK(evaluations == 24);
        CHECK(std::abs(e - exact) < 1e-5 * exact);
    }
    // A cut of 4 evaluates 4 lights, not 24.
    int evaluations = 0;
    estimateLightTree(viewOf(nodes), p, n, 4, 1, [&](uint32_t, int, bool) {
        ++evaluations;
        return vec3(1.0f);
    });
    CHECK(evaluations == 4);
}

TEST_CASE("A light tree never drops a panel that can light the receiver, and drops those behind it", "[trace]") {
    // 200 one-sided square panels, 0.2 m, facing random ways. A panel can light p (normal n)
    // exactly when p lies in front of its plane and some corner lies above p's horizon (a
    // half-space meets a convex polygon only at a vertex, if at all). For every such pair every
    // node from the root down to the panel's leaf must have importance > 0, or the estimate
    // would lose that panel's light.
    Pcg32 rng(17, 3);
    struct Panel {
        vec3 corners[4];
        vec3 normal;
    };
    std::vector<Panel> panels;
    std::vector<LightBounds> bounds;
    for (uint32_t i = 0; i < 200; ++i) {
        float x, y, z, a, b, c;
        rng.next2D(x, y);
        rng.next2D(z, a);
        rng.next2D(b, c);
        const vec3 centre(6.0f * x - 3.0f, 3.0f * y, 6.0f * z - 3.0f);
        const float cosTheta = 1.0f - 2.0f * a, phi = 6.283f * b;
        const float sinTheta = std::sqrt(1.0f - cosTheta * cosTheta);
        Panel panel;
        panel.normal = vec3(sinTheta * std::cos(phi), cosTheta, sinTheta * std::sin(phi));
        vec3 t, s;
        orthonormalBasis(panel.normal, t, s);
        panel.corners[0] = centre - 0.1f * t - 0.1f * s;
        panel.corners[1] = centre + 0.1f * t - 0.1f * s;
        panel.corners[2] = centre + 0.1f * t + 0.1f * s;
        panel.corners[3] = centre - 0.1f * t + 0.1f * s;
        LightBounds light;
        light.boundsMin = light.boundsMax = panel.corners[0];
        for (const vec3& q : panel.corners) {
            light.boundsMin = glm::min(light.boundsMin, q);
            light.boundsMax = glm::max(light.boundsMax, q);
        }
        light.axis = panel.normal;
        light.cosSpread = 1.0f;
        light.power = 0.04f * (1.0f + c);
        light.item = i;
        panels.push_back(panel);
        bounds.push_back(light);
    }
    const std::vector<LightTreeNode> nodes = buildLightTree(bounds);
    std::vector<uint32_t> parent(nodes.size(), 0), leafOf(panels.size(), 0);
    for (uint32_t k = 0; k < nodes.size(); ++k) {
        if (nodes[k].leaf)
            leafOf[nodes[k].first] = k;
        else
            parent[nodes[k].first] = parent[nodes[k].first + 1] = k;
    }
    int reachable = 0, unreachable = 0, droppedLeaves = 0;
    for (int r = 0; r < 200; ++r) {
        float x, y, z, a, b, c;
        rng.next2D(x, y);
        rng.next2D(z, a);
        rng.next2D(b, c);
        const vec3 p(8.0f * x - 4.0f, 4.0f * y - 0.5f, 8.0f * z - 4.0f);
        const float cosTheta = 1.0f - 2.0f * a, phi = 6.283f * b;
        const float sinTheta = std::sqrt(1.0f - cosTheta * cosTheta);
        const vec3 n(sinTheta * std::cos(phi), cosTheta, sinTheta * std::sin(phi));
        for (size_t i = 0; i < panels.size(); ++i) {
            const Panel& panel = panels[i];
            bool above = false;
            for (const vec3& q : panel.corners) above = above || glm::dot(n, q - p) > 0.0f;
            const bool inFront = glm::dot(panel.normal, p - panel.corners[0]) > 0.0f;
            if (!(above && inFront)) {
                ++unreachable;
                droppedLeaves += lightTreeImportance(nodes[leafOf[i]], p, n) > 0.0f ? 0 : 1;
                continue;
            }
            ++reachable;
            for (uint32_t k = leafOf[i];; k = parent[k]) {
                INFO("receiver " << r << ", panel " << i << ", node " << k);
                REQUIRE(lightTreeImportance(nodes[k], p, n) > 0.0f);
                if (k == 0) break;
            }
        }
    }
    INFO(reachable << " receiver-panel pairs can light, " << unreachable << " cannot, of which the leaf's bound drops "
                   << droppedLeaves);
    CHECK(reachable > 5000);
    // The bounds are tight enough to drop most of what cannot reach: behind a panel's plane at
    // any distance, or with the whole panel under the receiver's horizon.
    CHECK(droppedLeaves > 0.8 * unreachable);

    // Every panel faces down from y ≥ 5 and the receiver looks up from above them all: nothing.
    std::vector<LightBounds> ceiling;
    for (uint32_t i = 0; i < 50; ++i) {
        LightBounds light;
        light.boundsMin = vec3(float(i % 10), 5.0f, float(i / 10));
        light.boundsMax = light.boundsMin + vec3(0.2f, 0.0f, 0.2f);
        light.axis = vec3(0.0f, -1.0f, 0.0f);
        light.cosSpread = 1.0f;
        light.power = 1.0f;
        light.item = i;
        ceiling.push_back(light);
    }
    const std::vector<LightTreeNode> down = buildLightTree(ceiling);
    CHECK(lightTreeImportance(down[0], vec3(4.0f, 6.0f, 2.0f), vec3(0.0f, 1.0f, 0.0f)) == 0.0f);
    CHECK(lightTreeImportance(down[0], vec3(4.0f, 1.0f, 2.0f), vec3(0.0f, 1.0f, 0.0f)) > 0.0f);
}
