// Progress of one stage on stderr: a bar with counts and ETA when stderr is a terminal,
// a start and an end line otherwise. advance() is safe to call from worker threads.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace vl {

class Progress {
public:
    Progress(std::string stage, uint64_t total, bool quiet = false);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void advance(uint64_t count = 1);
    // Prints the closing line; returns the stage's wall time in seconds.
    double finish();

private:
    void draw(uint64_t done, bool final);

    std::string stage_;
    uint64_t total_;
    bool quiet_;
    bool terminal_;
    bool finished_ = false;
    std::atomic<uint64_t> done_{0};
    std::chrono::steady_clock::time_point start_;
    std::atomic<int64_t> lastDrawMs_{-1000};
    std::mutex drawMutex_;
};

}  // namespace vl
