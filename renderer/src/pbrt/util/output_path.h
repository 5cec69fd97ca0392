// Checking where an image will be written, before any long work (parsing big meshes,
// rendering) starts: a bad output path must fail in the first second, not after the render.
// And writing outputs under a temporary name that is renamed into place, so that no partial
// file is ever left: not on an error, not when pbrt is stopped by SIGTERM, SIGINT or SIGHUP
// (the temporary is removed and the signal's default action follows), and not for long
// when it is killed (SIGKILL): the next run that writes beside it removes the stale one.
#pragma once

#include <pbrt/pbrt.h>

#include <cstdio>
#include <string>

namespace pbrt {

// Throws PbrtError ("\"PATH\": reason") unless an image can be written at `path`: its
// extension is one WriteImage writes (.exr or .png, any case), it is not a directory, and
// its directory exists and is writable. Then removes stale temporaries of `path`
// (RemoveStaleTemporaries).
void CheckOutputImagePath(const std::string &path);

// The same for any other output file (pbrt --emission-spectrum, --material-reflectances):
// not a directory, in a directory that exists and is writable.
void CheckOutputFilePath(const std::string &path);

// The temporary that process `pid` on host `host` writes for `path`:
// "PATH.pbrt-tmp-PID@HOST", beside it (a rename within one directory is atomic).
std::string TemporaryPath(const std::string &path, long pid, const std::string &host);

// Removes the temporaries of `path` (TemporaryPath) left by processes of this host that no
// longer run (pbrt killed while writing); those of running processes and of other hosts
// (a shared folder) are left alone.
void RemoveStaleTemporaries(const std::string &path);

// The temporary of one output file: construct it, write to Path(), then Commit() to rename it
// onto the target. Until then a SIGTERM, SIGINT or SIGHUP removes it (the handler only calls
// unlink, then the signal's default action ends the process), and the destructor removes it
// if it was not committed (an error on the way).
class TemporaryOutput {
  public:
    explicit TemporaryOutput(const std::string &target);
    ~TemporaryOutput();
    TemporaryOutput(const TemporaryOutput &) = delete;
    TemporaryOutput &operator=(const TemporaryOutput &) = delete;

    const std::string &Path() const { return path; }
    // Renames the temporary onto the target; false (and the temporary removed) on failure.
    bool Commit();

  private:
    std::string target, path;
    int slot = -1;  // in the signal handler's table; -1 when not registered
    bool done = false;
};

// Writes `path` through body(FILE *) -> bool (false: a write failed) under a TemporaryOutput,
// renamed into place only when every write succeeded: never a partial file. Throws PbrtError
// ("\"PATH\": cannot be written" / "writing failed").
template <typename Body>
void WriteAtomically(const std::string &path, Body body) {
    TemporaryOutput tmp(path);
    std::FILE *f = std::fopen(tmp.Path().c_str(), "w");
    if (!f) throw PbrtError("\"" + path + "\": cannot be written");
    bool ok = body(f);
    ok = (std::fclose(f) == 0) && ok;
    if (!ok || !tmp.Commit()) throw PbrtError("\"" + path + "\": writing failed");
}

}  // namespace pbrt
