#include "core/diagnostics.h"

#include "core/error.h"

#include <iostream>

namespace vl {

void Diagnostics::warn(const std::string& message) {
    if (strict_) throw InputError(message + " (an error under --strict)");
    warnings_.push_back(message);
    if (echo_) std::cerr << "warning: " << message << '\n';
}

}  // namespace vl
