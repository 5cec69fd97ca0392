// A progress bar with elapsed time and an estimate of the time left, on stderr. Thread
// safe: workers call Update() as they finish work; at most a few redraws per second.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace pbrt {

class ProgressReporter {
  public:
    ProgressReporter(int64_t totalWork, std::string title, bool quiet);
    ~ProgressReporter() { Done(); }
    void Update(int64_t work = 1);
    // Draws the finished bar (once).
    void Done();
    double ElapsedSeconds() const;

  private:
    void Draw(int64_t done);
    const int64_t total;
    const std::string title;
    const bool quiet;
    std::atomic<int64_t> done{0};
    std::atomic<bool> finished{false};
    std::mutex drawMutex;
    std::chrono::steady_clock::time_point start, lastDraw;
};

}  // namespace pbrt
