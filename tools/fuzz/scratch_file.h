// The readers take paths: each fuzz input is written to one file in a folder of its own,
// made once per process and removed at exit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace vl::fuzz {

// Writes `data` to <scratch folder>/input<extension> and returns that path.
std::string writeScratch(const uint8_t* data, size_t size, const std::string& extension);

}  // namespace vl::fuzz
