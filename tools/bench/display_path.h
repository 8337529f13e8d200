// How the bench's reports (bench.md, bench.json, bench.csv) name files: relative to the
// repository or to the bench folder, never by the absolute paths of the machine they ran on,
// so a report committed to the repository reads the same on every checkout.
#pragma once

#include <string>

namespace vl {

// `path` as a report names it: an absolute path inside the repository is made relative to
// its root, one inside ../shared beside it becomes "../shared/…" (both as the README's
// commands, run from the root, name them); else, inside `outputDir` (the bench folder;
// empty: none), relative to that folder; else as given. A relative path is kept as given:
// it names no machine.
std::string displayPath(const std::string& path, const std::string& outputDir);

}  // namespace vl
