#include "core/progress.h"

#include <cstdio>
#include <unistd.h>

namespace vl {

Progress::Progress(std::string stage, uint64_t total, bool quiet)
    : stage_(std::move(stage)), total_(total), quiet_(quiet), terminal_(isatty(2) != 0),
      start_(std::chrono::steady_clock::now()) {
    if (!quiet_ && !terminal_) std::fprintf(stderr, "%s: started (%llu items)\n", stage_.c_str(),
                                            static_cast<unsigned long long>(total_));
}

Progress::~Progress() {
    if (!finished_) finish();
}

void Progress::advance(uint64_t count) {
    const uint64_t done = done_.fetch_add(count) + count;
    if (quiet_ || !terminal_) return;
    const auto now = std::chrono::steady_clock::now();
    const int64_t ms = std::chrono::duration_cast<std::chrono::milliseconds>(now - start_).count();
    int64_t last = lastDrawMs_.load();
    if (ms - last < 100 || !lastDrawMs_.compare_exchange_strong(last, ms)) return;
    draw(done, false);
}

void Progress::draw(uint64_t done, bool final) {
    std::lock_guard<std::mutex> lock(drawMutex_);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double fraction = total_ ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
    if (!terminal_) {
        std::fprintf(stderr, "%s: done, %llu items in %.2f s\n", stage_.c_str(),
                     static_cast<unsigned long long>(done), elapsed);
        return;
    }
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    char bar[kWidth + 1];
    for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '-';
    bar[kWidth] = '\0';
    const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r%-14s [%s] %llu/%llu  %6.1f s%s", stage_.c_str(), bar,
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total_),
                 final ? elapsed : eta, final ? "      \n" : " ETA");
    std::fflush(stderr);
}

double Progress::finish() {
    finished_ = true;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (!quiet_) draw(done_.load(), true);
    return elapsed;
}

}  // namespace vl
