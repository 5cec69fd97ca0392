// Basic definitions shared by every part of the renderer: the floating-point type,
// mathematical constants, source locations and the error type.
#pragma once

#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace pbrt {

using Float = float;

constexpr Float Pi = 3.14159265358979323846f;
constexpr Float InvPi = 0.31830988618379067154f;
constexpr Float Inv2Pi = 0.15915494309189533577f;
constexpr Float Inv4Pi = 0.07957747154594766788f;
constexpr Float PiOver2 = 1.57079632679489661923f;
constexpr Float PiOver4 = 0.78539816339744830961f;
constexpr Float Infinity = std::numeric_limits<Float>::infinity();

// Where something was read: a file, a 1-based line and column. Errors about input name it.
struct FileLoc {
    std::string filename;
    int line = 0, column = 0;
    std::string ToString() const {
        if (filename.empty()) return "<input>";
        return filename + ":" + std::to_string(line) + ":" + std::to_string(column);
    }
};

// The one error type for bad input (scene, table, image, option). The command catches it,
// prints "pbrt: <what>" and exits with status 1; tests check it with EXPECT_THROW.
class PbrtError : public std::runtime_error {
  public:
    explicit PbrtError(const std::string &msg) : std::runtime_error(msg) {}
    PbrtError(const FileLoc &loc, const std::string &msg)
        : std::runtime_error(loc.ToString() + ": " + msg) {}
};

// Prints a warning to stderr ("pbrt: warning: ..."), once per distinct message.
void Warning(const std::string &msg);
void Warning(const FileLoc &loc, const std::string &msg);
// Drops every warning from now on (true) or prints them again (false): for fuzzing, where
// millions of distinct warnings would fill stderr and the set of messages already printed.
void SuppressWarnings(bool suppress);
// --log-level verbose: Verbose() prints what was loaded and how ("pbrt: ..."); otherwise it
// prints nothing. SetLogFile sends warnings and verbose lines to f instead of stderr (the
// caller keeps f open; nullptr: stderr again).
void SetVerbose(bool on);
bool IsVerbose();
void Verbose(const std::string &msg);
void SetLogFile(std::FILE *f);

}  // namespace pbrt
