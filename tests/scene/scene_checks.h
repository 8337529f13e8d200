// Comparisons the scene tests share.
#pragma once

#include "core/error.h"
#include "scene/gltf_loader.h"
#include "support/paths.h"

#include <catch2/catch.hpp>

#include <sstream>

namespace vl::test {

inline bool near(const vec3& a, const vec3& b, float eps = 1e-6f) { return glm::all(glm::lessThanEqual(glm::abs(a - b), vec3(eps))); }
inline bool near(const vec4& a, const vec4& b, float eps = 1e-6f) { return glm::all(glm::lessThanEqual(glm::abs(a - b), vec4(eps))); }
inline bool near(const vec2& a, const vec2& b, float eps = 1e-6f) { return glm::all(glm::lessThanEqual(glm::abs(a - b), vec2(eps))); }

template <int N>
std::string str(const glm::vec<N, float>& v) {
    std::ostringstream out;
    out.precision(9);
    out << "(";
    for (int i = 0; i < N; ++i) out << (i ? ", " : "") << v[i];
    return out.str() + ")";
}

#define CHECK_NEAR(a, b, ...)                                                         \
    do {                                                                              \
        INFO(#a " = " << vl::test::str(a) << ", expected " << vl::test::str(b));   \
        CHECK(vl::test::near(a, b, ##__VA_ARGS__));                                   \
    } while (0)

// A local position of `scene` in world space (scene.h: world = origin + local).
inline vec3 world(const Scene& scene, const vec3& local) { return vec3(scene.origin + glm::dvec3(local)); }

// Unit geometric normal of triangle t from its index order (CCW = front).
inline vec3 faceNormal(const Mesh& mesh, size_t t) {
    const vec3& a = mesh.positions[mesh.indices[3 * t]];
    const vec3& b = mesh.positions[mesh.indices[3 * t + 1]];
    const vec3& c = mesh.positions[mesh.indices[3 * t + 2]];
    return glm::normalize(glm::cross(b - a, c - a));
}

inline Scene loadQuiet(const std::string& path, bool strict = false) {
    LoadOptions options;
    options.strict = strict;
    options.echoWarnings = false;
    return loadGltf(path, options);
}

inline bool anyWarningContains(const Scene& scene, const std::string& text) {
    for (const std::string& w : scene.warnings)
        if (w.find(text) != std::string::npos) return true;
    return false;
}

}  // namespace vl::test
