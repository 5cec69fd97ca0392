#include <pbrt/pbrt.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <set>

namespace pbrt {

namespace {
std::atomic<bool> warningsSuppressed{false};
}  // namespace

void SuppressWarnings(bool suppress) { warningsSuppressed = suppress; }

void Warning(const std::string &msg) {
    if (warningsSuppressed) return;
    // Each distinct warning is printed once, however many threads or pixels hit it.
    static std::mutex mutex;
    static std::set<std::string> seen;
    std::lock_guard<std::mutex> lock(mutex);
    if (!seen.insert(msg).second) return;
    std::fprintf(stderr, "pbrt: warning: %s\n", msg.c_str());
}

void Warning(const FileLoc &loc, const std::string &msg) { Warning(loc.ToString() + ": " + msg); }

}  // namespace pbrt
