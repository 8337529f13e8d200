#include "cone/cone_set.h"

#include "core/error.h"

#include <cmath>
#include <cstdint>
#include <string>

namespace vl {

namespace {

// The weights of each ring's cones (all equal: the cones of a ring are rotations of one
// another), from cosineCellWeights at 1024² points averaged over each ring: accurate to
// ~1e-4 (cell boundaries cut through ~1000 of the 10⁶ points). Tabulated because the
// quadrature is a noticeable cost at every start of the tool (docs/decisions.md, "Cone
// sets"); tests/cone/cone_set_test.cpp recomputes them.
constexpr float kRingWeights6[] = {0.321405411f, 0.135718912f};
constexpr float kRingWeights16[] = {0.135944366f, 0.0936838761f, 0.0335502625f};
constexpr float kRingWeights32[] = {0.0750255585f, 0.0537967682f, 0.035118971f, 0.012468338f};

std::vector<int> ringCounts(int count) {
    switch (count) {
        case 6: return {1, 5};
        case 16: return {1, 6, 9};
        case 32: return {1, 7, 11, 13};
        default:
            throw SettingsError("cone count " + std::to_string(count) + " is not supported (use 6, 16 or 32)");
    }
}

ConeSet makeConeSet(int count) {
    ConeSet set;
    const std::vector<vec3> directions = coneDirections(count);
    const float* ringWeights = count == 6 ? kRingWeights6 : count == 16 ? kRingWeights16 : kRingWeights32;
    std::vector<float> weights;
    const std::vector<int> rings = ringCounts(count);
    for (size_t r = 0; r < rings.size(); ++r) weights.insert(weights.end(), size_t(rings[r]), ringWeights[r]);
    set.count = count;
    set.defaultHalfAngle = static_cast<float>(std::acos(1.0 - 1.0 / count));
    for (int k = 0; k < count; ++k) {
        set.directions[k] = directions[static_cast<size_t>(k)];
        set.weights[k] = weights[static_cast<size_t>(k)];
    }
    return set;
}

}  // namespace

std::vector<vec3> coneDirections(int count) {
    const std::vector<int> rings = ringCounts(count);
    std::vector<vec3> directions;
    int conesAbove = 0;  // cones in the rings above, i.e. solid angle above in units of 2π/N
    for (size_t r = 0; r < rings.size(); ++r) {
        const int n = rings[r];
        // Equal-area band: z falls linearly with solid angle, dω = dz dφ.
        const double zTop = 1.0 - double(conesAbove) / count;
        const double zBottom = 1.0 - double(conesAbove + n) / count;
        const double z = r == 0 ? 1.0 : 0.5 * (zTop + zBottom);
        const double sinTheta = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double stagger = (r % 2 == 0) ? 0.0 : 0.5;
        for (int j = 0; j < n; ++j) {
            const double phi = 2.0 * M_PI * (j + stagger) / n;
            directions.emplace_back(static_cast<float>(sinTheta * std::cos(phi)),
                                    static_cast<float>(sinTheta * std::sin(phi)), static_cast<float>(z));
        }
        conesAbove += n;
    }
    return directions;
}

std::vector<float> cosineCellWeights(const std::vector<vec3>& directions, int resolution) {
    std::vector<int64_t> counts(directions.size(), 0);
    for (int iu = 0; iu < resolution; ++iu) {
        const double u = (iu + 0.5) / resolution;  // u = z²
        const double z = std::sqrt(u);
        const double sinTheta = std::sqrt(1.0 - u);
        for (int ip = 0; ip < resolution; ++ip) {
            const double phi = 2.0 * M_PI * (ip + 0.5) / resolution;
            const double x = sinTheta * std::cos(phi), y = sinTheta * std::sin(phi);
            size_t nearest = 0;
            double best = -2.0;
            for (size_t k = 0; k < directions.size(); ++k) {
                const vec3& d = directions[k];
                const double dot = x * d.x + y * d.y + z * d.z;
                if (dot > best) {
                    best = dot;
                    nearest = k;
                }
            }
            ++counts[nearest];
        }
    }
    const double total = double(resolution) * resolution;
    std::vector<float> weights;
    for (int64_t c : counts) weights.push_back(static_cast<float>(c / total));
    return weights;
}

const ConeSet& coneSet(int count) {
    // Built on first use, once per count (thread-safe static initialisation).
    switch (count) {
        case 6: {
            static const ConeSet six = makeConeSet(6);
            return six;
        }
        case 16: {
            static const ConeSet sixteen = makeConeSet(16);
            return sixteen;
        }
        case 32: {
            static const ConeSet thirtyTwo = makeConeSet(32);
            return thirtyTwo;
        }
        default: throw SettingsError("cone count " + std::to_string(count) + " is not supported (use 6, 16 or 32)");
    }
}

}  // namespace vl
