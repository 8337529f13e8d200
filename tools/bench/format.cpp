#include "bench/format.h"

#include <cstdio>

namespace vl {

std::string fmt(const char* format, double v) {
    char text[64];
    std::snprintf(text, sizeof text, format, v);
    return text;
}

std::string secs(double s) { return s > 0.0 ? fmt(s < 10.0 ? "%.2f" : "%.1f", s) : "—"; }

}  // namespace vl
