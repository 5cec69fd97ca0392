// Reading input files (scenes, their Includes, .spd spectra, PLY meshes): regular files
// only, with a cap on the size where the design sets one (design §3.3, §5.5).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace pbrt {

// Why a file could not be read; what() is the reason alone ("no such file", "not a regular
// file (a device, FIFO or socket), not a scene file", ...), for the caller to place after
// the path (and the FileLoc that named it).
class FileReadError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// The size cap of spectrum files (design §3.3), as for tables (§2.3): far above any real one.
constexpr size_t kMaxSpectrumFileBytes = size_t(64) << 20;

// The bytes of the regular file `path` (`what` names the kind of file in messages: "scene",
// "spectrum", ...), at most maxBytes of them (0: no cap). A device, FIFO, socket or
// directory is refused before anything is read: the file is opened without blocking (a
// FIFO's open would wait for a writer) and the opened descriptor is checked, so a rename in
// between cannot slip another file in; at most maxBytes + 1 bytes are ever read.
// Throws FileReadError.
std::string ReadRegularFile(const std::string &path, const std::string &what, size_t maxBytes = 0);

}  // namespace pbrt
