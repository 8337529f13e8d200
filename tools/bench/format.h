// How the bench writes numbers in its reports and progress lines.
#pragma once

#include <string>

namespace vl {

// One number through a printf format: fmt("%.1f%%", 12.34) = "12.3%".
std::string fmt(const char* format, double v);

// Seconds with two decimals under 10 s, one above; "—" when not measured (0).
std::string secs(double s);

}  // namespace vl
