#include <pbrt/util/progress.h>

#include <cstdio>

namespace pbrt {

namespace {
std::string FormatSeconds(double s) {
    char buf[32];
    if (s < 60) std::snprintf(buf, sizeof(buf), "%.1fs", s);
    else if (s < 3600) std::snprintf(buf, sizeof(buf), "%dm%02ds", int(s) / 60, int(s) % 60);
    else std::snprintf(buf, sizeof(buf), "%dh%02dm", int(s) / 3600, (int(s) / 60) % 60);
    return buf;
}
}  // namespace

ProgressReporter::ProgressReporter(int64_t totalWork, std::string title, bool quiet)
    : total(totalWork > 0 ? totalWork : 1), title(std::move(title)), quiet(quiet),
      start(std::chrono::steady_clock::now()), lastDraw(start) {}

double ProgressReporter::ElapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void ProgressReporter::Update(int64_t work) {
    int64_t d = done.fetch_add(work) + work;
    if (quiet) return;
    // Whoever gets the lock redraws, at most every 0.25 s; the others carry on.
    std::unique_lock<std::mutex> lock(drawMutex, std::try_to_lock);
    if (!lock.owns_lock()) return;
    auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - lastDraw).count() < 0.25) return;
    lastDraw = now;
    Draw(d);
}

void ProgressReporter::Done() {
    if (finished.exchange(true)) return;
    if (quiet) return;
    std::lock_guard<std::mutex> lock(drawMutex);
    Draw(total);
    std::fputc('\n', stderr);
    std::fflush(stderr);
}

void ProgressReporter::Draw(int64_t d) {
    double frac = std::min(1.0, double(d) / double(total));
    const int width = 40;
    int filled = int(frac * width);
    std::string bar(size_t(filled), '+');
    bar.append(size_t(width - filled), ' ');
    double elapsed = ElapsedSeconds();
    std::string eta = frac > 0 && frac < 1 ? FormatSeconds(elapsed / frac - elapsed) : "0s";
    std::fprintf(stderr, "\r%s [%s] %3d%% (%s elapsed, %s left) ", title.c_str(), bar.c_str(),
                 int(frac * 100), FormatSeconds(elapsed).c_str(), eta.c_str());
    std::fflush(stderr);
}

}  // namespace pbrt
