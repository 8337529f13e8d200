// The differential form factor from a point to a parallel rectangle, in closed form: the
// analytic value the lighting and direct-light tests hold emitters to.
#pragma once

#include <cmath>

namespace vl::test {

// Form factor from a point to a parallel rectangle at height c with one corner straight
// above the point, signed so that F(x0..x1, y0..y1) = G(x1,y1) − G(x0,y1) − G(x1,y0) + G(x0,y0).
inline double cornerFormFactor(double x, double y, double c) {
    const double X = x / c, Y = y / c;
    const double sx = std::sqrt(1.0 + X * X), sy = std::sqrt(1.0 + Y * Y);
    return (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / (2.0 * M_PI);
}

// The rectangle [x0, x1] × [y0, y1] (relative to the point) at height c.
inline double rectangleFormFactor(double x0, double x1, double y0, double y1, double c) {
    return cornerFormFactor(x1, y1, c) - cornerFormFactor(x0, y1, c) - cornerFormFactor(x1, y0, c) +
           cornerFormFactor(x0, y0, c);
}

}  // namespace vl::test
