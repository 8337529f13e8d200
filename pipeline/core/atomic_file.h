// Write-then-rename, the one way every stage writes output files.
#pragma once

#include <functional>
#include <string>

namespace vl {

// Calls write(tempPath) and renames tempPath to path on success; removes it on failure.
void writeAtomically(const std::string& path, const std::function<void(const std::string& tempPath)>& write);

}  // namespace vl
