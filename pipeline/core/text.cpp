#include "core/text.h"

#include <cstdio>
#include <sstream>

namespace vl {

std::string numberText(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

std::string lengthText(double metres) {
    char text[32];
    if (metres >= 1.0) std::snprintf(text, sizeof text, "%.3g m", metres);
    else if (metres >= 0.01) std::snprintf(text, sizeof text, "%.3g cm", metres * 100.0);
    else std::snprintf(text, sizeof text, "%.3g mm", metres * 1000.0);
    return text;
}

}  // namespace vl
