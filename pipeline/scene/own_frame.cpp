#include "scene/own_frame.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vl {
namespace {

struct Face {
    glm::dvec3 normal;  // unit, its largest component positive (one per orientation)
    double area;
};

std::vector<Face> faceOrientations(const Scene& scene) {
    std::vector<Face> faces;
    for (const Mesh& mesh : scene.meshes)
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const glm::dvec3 a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
                c(mesh.positions[mesh.indices[3 * t + 2]]);
            glm::dvec3 n = glm::cross(b - a, c - a);
            const double twiceArea = glm::length(n);
            if (!(twiceArea > 0.0)) continue;
            n /= twiceArea;
            int axis = 0;
            for (int k = 1; k < 3; ++k)
                if (std::abs(n[k]) > std::abs(n[axis])) axis = k;
            if (n[axis] < 0.0) n = -n;
            faces.push_back({n, 0.5 * twiceArea});
        }
    return faces;
}

// The area-weighted mean orientation of the fullest bin (of an octahedral map of orientations)
// among the faces `take` accepts; false when it accepts none.
template <typename Take>
bool dominantOrientation(const std::vector<Face>& faces, Take&& take, glm::dvec3& axis) {
    constexpr int kBins = 32;  // per side of the octahedral map
    std::vector<double> area(kBins * kBins, 0.0);
    std::vector<glm::dvec3> sum(kBins * kBins, glm::dvec3(0.0));
    for (const Face& f : faces) {
        if (!take(f.normal)) continue;
        glm::dvec3 p = f.normal / (std::abs(f.normal.x) + std::abs(f.normal.y) + std::abs(f.normal.z));
        if (p.z < 0.0) {
            const double x = (1.0 - std::abs(p.y)) * (p.x < 0.0 ? -1.0 : 1.0);
            p.y = (1.0 - std::abs(p.x)) * (p.y < 0.0 ? -1.0 : 1.0);
            p.x = x;
        }
        const int i = std::min(kBins - 1, int((p.x + 1.0) * 0.5 * kBins));
        const int j = std::min(kBins - 1, int((p.y + 1.0) * 0.5 * kBins));
        area[j * kBins + i] += f.area;
        sum[j * kBins + i] += f.area * f.normal;
    }
    const size_t best = size_t(std::max_element(area.begin(), area.end()) - area.begin());
    if (!(area[best] > 0.0)) return false;
    axis = glm::normalize(sum[best]);
    return true;
}

}  // namespace

glm::dmat3 ownFrameAxes(const Scene& scene) {
    const std::vector<Face> faces = faceOrientations(scene);
    glm::dvec3 first, second;
    if (!dominantOrientation(faces, [](const glm::dvec3&) { return true; }, first)) return glm::dmat3(1.0);
    if (!dominantOrientation(faces, [&](const glm::dvec3& n) { return std::abs(glm::dot(n, first)) < 0.1; }, second))
        return glm::dmat3(1.0);
    second = glm::normalize(second - glm::dot(second, first) * first);
    const glm::dvec3 own[3] = {first, second, glm::cross(first, second)};
    // Each own axis to the free local axis it lies nearest, the most decided first, signed
    // toward it: the turn into the own frame is then the smallest one.
    glm::dmat3 axes(0.0);
    bool taken[3] = {false, false, false}, placed[3] = {false, false, false};
    int lastAxis = 0;
    for (int round = 0; round < 3; ++round) {
        int bestOwn = -1, bestAxis = -1;
        double bestCosine = -1.0;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a)
                if (!placed[k] && !taken[a] && std::abs(own[k][a]) > bestCosine) {
                    bestCosine = std::abs(own[k][a]);
                    bestOwn = k;
                    bestAxis = a;
                }
        placed[bestOwn] = taken[bestAxis] = true;
        lastAxis = bestAxis;
        axes[bestAxis] = own[bestOwn][bestAxis] < 0.0 ? -own[bestOwn] : own[bestOwn];
    }
    // An odd permutation of the axes leaves the three signed axes left-handed: the least
    // decided one turns.
    if (glm::determinant(axes) < 0.0) axes[lastAxis] = -axes[lastAxis];
    // The turn's angle: cos θ = (trace − 1) / 2.
    const double cosTurn = 0.5 * (axes[0][0] + axes[1][1] + axes[2][2] - 1.0);
    return cosTurn >= std::cos(kOwnFrameMinTurn) ? glm::dmat3(1.0) : axes;
}

bool turnToOwnFrame(Scene& scene) {
    const glm::dmat3 axes = ownFrameAxes(scene);
    if (axes == glm::dmat3(1.0)) return false;
    scene.turnFrame(scene.frame * axes);
    return true;
}

}  // namespace vl
