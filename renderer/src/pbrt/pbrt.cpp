#include <pbrt/pbrt.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <set>

namespace pbrt {

namespace {
std::atomic<bool> warningsSuppressed{false};
std::atomic<bool> verbose{false};
std::atomic<std::FILE *> logFile{nullptr};  // nullptr: standard error
std::mutex logMutex;

void Print(const std::string &line) {
    std::FILE *f = logFile.load();
    std::fprintf(f ? f : stderr, "%s\n", line.c_str());
    if (f) std::fflush(f);
}
}  // namespace

void SuppressWarnings(bool suppress) { warningsSuppressed = suppress; }

void SetVerbose(bool on) { verbose = on; }
bool IsVerbose() { return verbose; }

void SetLogFile(std::FILE *f) { logFile = f; }

void Verbose(const std::string &msg) {
    if (!verbose) return;
    std::lock_guard<std::mutex> lock(logMutex);
    Print("pbrt: " + msg);
}

void Warning(const std::string &msg) {
    if (warningsSuppressed) return;
    // Each distinct warning is printed once, however many threads or pixels hit it.
    static std::set<std::string> seen;
    std::lock_guard<std::mutex> lock(logMutex);
    if (!seen.insert(msg).second) return;
    Print("pbrt: warning: " + msg);
}

void Warning(const FileLoc &loc, const std::string &msg) { Warning(loc.ToString() + ": " + msg); }

}  // namespace pbrt
