#include <pbrt/util/output_path.h>

#include <pbrt/pbrt.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>

namespace pbrt {

namespace {

auto Failure(const std::string &path) {
    return [&path](const std::string &why) { return PbrtError("\"" + path + "\": " + why); };
}

// A name, and not a directory's (`needs` says what the output needs instead).
void CheckName(const std::string &path, const std::string &needs) {
    auto fail = Failure(path);
    if (path.empty()) throw fail("empty output file name");
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw fail("is a directory; the output needs " + needs);
}

// Its directory exists and is writable.
void CheckDirectory(const std::string &path) {
    namespace fs = std::filesystem;
    auto fail = Failure(path);
    std::error_code ec;
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec)) throw fail("the output directory does not exist");
    if (access(dir.c_str(), W_OK) != 0) throw fail("the output directory is not writable");
}

}  // namespace

void CheckOutputFilePath(const std::string &path) {
    CheckName(path, "a file name");
    CheckDirectory(path);
    RemoveStaleTemporaries(path);
}

void CheckOutputImagePath(const std::string &path) {
    CheckName(path, "a file name ending in .exr or .png");
    // The formats WriteImage (util/image.cpp) writes.
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".exr" && ext != ".png")
        throw Failure(path)("unsupported output image format \"" + ext + "\" (use .exr or .png)");
    CheckDirectory(path);
    RemoveStaleTemporaries(path);
}

// ---------------------------------------------------------------------------------------
// Temporaries

namespace {

constexpr const char *kTemporaryTag = ".pbrt-tmp-";

const std::string &HostName() {
    static const std::string host = [] {
        char buf[256] = {};
        if (gethostname(buf, sizeof buf - 1) != 0) return std::string("localhost");
        return std::string(buf);
    }();
    return host;
}

// The temporaries a signal must remove: a fixed table of paths, since a handler may only
// make async-signal-safe calls (unlink, signal, raise: no allocation, no locks). A slot is
// 0 (free), 1 (being filled, or being emptied) or 2 (holds a path to remove).
constexpr int kSlots = 8;
constexpr size_t kMaxPath = 4096;
char slotPath[kSlots][kMaxPath];
std::atomic<int> slotState[kSlots];

extern "C" void RemoveTemporariesAndDie(int sig) {
    for (int i = 0; i < kSlots; ++i)
        if (slotState[i].load() == 2) unlink(slotPath[i]);
    // The default action (the process ends as it would have without the handler), once the
    // handler returns and the signal is unblocked.
    signal(sig, SIG_DFL);
    raise(sig);
}

// The handler for the signals that stop a process politely, unless the signal is ignored
// (nohup ignores SIGHUP) or already handled by someone else; once per process.
void InstallHandlers() {
    static std::once_flag once;
    std::call_once(once, [] {
        for (int sig : {SIGTERM, SIGINT, SIGHUP}) {
            struct sigaction old;
            if (sigaction(sig, nullptr, &old) != 0) continue;
            if ((old.sa_flags & SA_SIGINFO) || old.sa_handler != SIG_DFL) continue;
            struct sigaction act = {};
            act.sa_handler = RemoveTemporariesAndDie;
            sigemptyset(&act.sa_mask);
            sigaction(sig, &act, nullptr);
        }
    });
}

int Register(const std::string &path) {
    if (path.size() >= kMaxPath) return -1;  // not removed on a signal; still on errors
    InstallHandlers();
    for (int i = 0; i < kSlots; ++i) {
        int expected = 0;
        if (!slotState[i].compare_exchange_strong(expected, 1)) continue;
        std::memcpy(slotPath[i], path.c_str(), path.size() + 1);
        slotState[i].store(2);
        return i;
    }
    return -1;
}

void Unregister(int slot) {
    if (slot < 0) return;
    slotState[slot].store(1);
    slotState[slot].store(0);
}

}  // namespace

std::string TemporaryPath(const std::string &path, long pid, const std::string &host) {
    return path + kTemporaryTag + std::to_string(pid) + "@" + host;
}

void RemoveStaleTemporaries(const std::string &path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    const std::string prefix = fs::path(path).filename().string() + kTemporaryTag;
    const std::string suffix = "@" + HostName();
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
        if (digits.empty() || digits.size() > 9 ||
            !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
            continue;
        const long pid = std::stol(digits);
        // kill(pid, 0) fails with ESRCH when no such process exists (EPERM: it exists).
        if (pid > 0 && kill(pid_t(pid), 0) != 0 && errno == ESRCH) {
            std::error_code rm;
            fs::remove(it->path(), rm);
        }
    }
}

TemporaryOutput::TemporaryOutput(const std::string &target)
    : target(target), path(TemporaryPath(target, long(getpid()), HostName())) {
    slot = Register(path);
}

TemporaryOutput::~TemporaryOutput() {
    if (!done) unlink(path.c_str());
    Unregister(slot);
}

bool TemporaryOutput::Commit() {
    done = true;
    const bool ok = std::rename(path.c_str(), target.c_str()) == 0;
    if (!ok) unlink(path.c_str());
    Unregister(slot);
    slot = -1;
    return ok;
}

}  // namespace pbrt
