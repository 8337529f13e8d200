// Numbers and lengths as messages and reports write them.
#pragma once

#include <string>

namespace vl {

// As `std::ostream << v` writes it (up to 6 significant digits): a setting's value in its error.
std::string numberText(double v);

// Three significant digits in m, cm or mm, whichever reads best ("1.5 cm").
std::string lengthText(double metres);

}  // namespace vl
