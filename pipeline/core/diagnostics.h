// Warnings collected while a job runs; repeated in the job's report. Under --strict a
// warning becomes an InputError at the point it is raised.
#pragma once

#include <string>
#include <vector>

namespace vl {

class Diagnostics {
public:
    explicit Diagnostics(bool strict = false, bool echo = true) : strict_(strict), echo_(echo) {}

    void warn(const std::string& message);
    const std::vector<std::string>& warnings() const { return warnings_; }
    bool strict() const { return strict_; }

private:
    bool strict_;
    bool echo_;
    std::vector<std::string> warnings_;
};

}  // namespace vl
