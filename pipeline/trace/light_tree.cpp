#include "trace/light_tree.h"

#include <algorithm>
#include <cmath>

namespace vl {

namespace {

// Half-angles are widened by this (radians) so that rounding never leaves a normal outside.
constexpr double kConeMargin = 1e-4;

using dvec3 = glm::dvec3;

struct Cone {
    dvec3 axis{0.0, 0.0, 1.0};
    double angle = kPi;  // ≥ π: every direction
};

// The smallest cone (about) holding both.
Cone coneUnion(const Cone& a, const Cone& b) {
    if (a.angle >= kPi || b.angle >= kPi) return Cone{};
    const double between = std::acos(std::clamp(glm::dot(a.axis, b.axis), -1.0, 1.0));
    if (std::min(between + b.angle, double(kPi)) <= a.angle) return a;
    if (std::min(between + a.angle, double(kPi)) <= b.angle) return b;
    const double angle = 0.5 * (a.angle + between + b.angle);
    const dvec3 turn = glm::cross(a.axis, b.axis);
    if (angle >= kPi || glm::length(turn) < 1e-9) return Cone{};
    // Turn a's axis toward b's by angle − a.angle, in the plane of the two.
    const double by = angle - a.angle;
    const dvec3 k = glm::normalize(turn);
    const dvec3 axis = a.axis * std::cos(by) + glm::cross(k, a.axis) * std::sin(by);
    return Cone{glm::normalize(axis), angle};
}

struct Builder {
    std::vector<LightBounds>& lights;
    std::vector<LightTreeNode>& nodes;

    // Fills nodes[at] with the tree over lights [begin, end).
    Cone build(uint32_t at, size_t begin, size_t end) {
        LightTreeNode node;
        vec3 boundsMin = lights[begin].boundsMin, boundsMax = lights[begin].boundsMax;
        double power = 0.0;
        vec3 centresMin(kInfinity), centresMax(-kInfinity);
        for (size_t i = begin; i < end; ++i) {
            boundsMin = glm::min(boundsMin, lights[i].boundsMin);
            boundsMax = glm::max(boundsMax, lights[i].boundsMax);
            power += double(lights[i].power);
            const vec3 c = 0.5f * (lights[i].boundsMin + lights[i].boundsMax);
            centresMin = glm::min(centresMin, c);
            centresMax = glm::max(centresMax, c);
        }
        node.power = float(power);
        node.centre = 0.5f * (boundsMin + boundsMax);
        node.half = 0.5f * (boundsMax - boundsMin);
        // Rounded up a little, so that the sphere holds every corner.
        node.radius = glm::length(node.half) * (1.0f + 1e-6f);
        Cone cone;
        if (end - begin == 1) {
            const LightBounds& light = lights[begin];
            node.leaf = 1;
            node.first = light.item;
            if (light.cosSpread > -1.0f) cone = Cone{glm::normalize(dvec3(light.axis)), std::acos(double(light.cosSpread))};
        } else {
            // Split at the median of the centres along their widest axis (ties by item).
            const vec3 extent = centresMax - centresMin;
            const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
            const size_t middle = begin + (end - begin) / 2;
            std::nth_element(lights.begin() + long(begin), lights.begin() + long(middle), lights.begin() + long(end),
                             [axis](const LightBounds& a, const LightBounds& b) {
                                 const float ca = a.boundsMin[axis] + a.boundsMax[axis];
                                 const float cb = b.boundsMin[axis] + b.boundsMax[axis];
                                 return ca < cb || (ca == cb && a.item < b.item);
                             });
            node.first = uint32_t(nodes.size());
            nodes.resize(nodes.size() + 2);
            const Cone left = build(node.first, begin, middle);
            const Cone right = build(node.first + 1, middle, end);
            cone = coneUnion(left, right);
        }
        if (cone.angle < kPi) {
            const double widened = std::min(double(kPi), cone.angle + kConeMargin);
            node.axis = vec3(cone.axis);
            node.cosSpread = widened >= kPi ? -1.0f : float(std::cos(widened));
            node.sinSpread = widened >= kPi ? 0.0f : float(std::sin(widened));
        }
        nodes[at] = node;
        return cone;
    }
};

}  // namespace

std::vector<LightTreeNode> buildLightTree(std::vector<LightBounds> lights) {
    std::vector<LightTreeNode> nodes;
    if (lights.empty()) return nodes;
    nodes.reserve(2 * lights.size());
    nodes.resize(1);
    Builder builder{lights, nodes};
    builder.build(0, 0, lights.size());
    return nodes;
}

}  // namespace vl
