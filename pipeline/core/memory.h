// What the machine has free now: the bake's memory budget, and the bound on what a file from
// elsewhere may make a reader allocate.
#pragma once

namespace vl {

// /proc/meminfo's MemAvailable, in bytes (the available physical pages where it is absent).
double availableMemoryBytes();

}  // namespace vl
