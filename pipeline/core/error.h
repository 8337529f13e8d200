// Errors a user can act on. Messages name the file and the element (mesh, primitive,
// accessor, setting) so the user knows what to fix.
#pragma once

#include <stdexcept>
#include <string>

namespace vl {

struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// The input file is malformed, unsupported or would produce NaN.
struct InputError : Error {
    using Error::Error;
};

// A setting is out of its valid range; raised before any work starts.
struct SettingsError : Error {
    using Error::Error;
};

}  // namespace vl
