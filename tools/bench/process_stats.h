// This process's resources as the bench measures them around a point or a run: its peak
// resident set since the last reset, and the CPU time of all its threads.
#pragma once

namespace vl {

// Resets the peak resident set size (Linux: "5" written to /proc/self/clear_refs); false when
// it cannot, and peakMemoryBytes is then the process's peak since it started.
bool resetPeakMemory();

// The resident high-water mark (VmHWM) since the last reset, in bytes.
double peakMemoryBytes();

// User + system CPU seconds of the whole process so far.
double cpuSeconds();

// CPU seconds every process on the machine has used since boot (/proc/stat: user, nice,
// system, irq, softirq, steal); 0 where there is no /proc/stat. Less this process's
// cpuSeconds over an interval, it is the load others put on the machine meanwhile.
double systemBusySeconds();

}  // namespace vl
