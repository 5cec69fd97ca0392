#include <pbrt/util/file.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace pbrt {

std::string ReadRegularFile(const std::string &path, const std::string &what, size_t maxBytes) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        if (err == ENOENT || err == ENOTDIR) throw FileReadError("no such " + what + " file");
        if (err == EISDIR) throw FileReadError("is a directory, not a " + what + " file");
        throw FileReadError(std::string("cannot read (") + std::strerror(err) + ")");
    }
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st;
    if (::fstat(fd, &st) != 0) throw FileReadError(std::string("cannot read (") + std::strerror(errno) + ")");
    if (S_ISDIR(st.st_mode)) throw FileReadError("is a directory, not a " + what + " file");
    if (!S_ISREG(st.st_mode))
        throw FileReadError("not a regular file (a device, FIFO or socket), not a " + what + " file");
    const std::string tooLarge = "larger than " + std::to_string(maxBytes >> 20) + " MiB, not a " + what + " file";
    if (maxBytes && static_cast<unsigned long long>(st.st_size) > maxBytes) throw FileReadError(tooLarge);
    // Into memory reserved for the size fstat gave (big meshes), on to the end of the file:
    // it may have changed since.
    std::string bytes;
    bytes.reserve(size_t(st.st_size));
    char chunk[1 << 16];
    while (true) {
        const ssize_t got = ::read(fd, chunk, sizeof chunk);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) throw FileReadError(std::string("cannot read (") + std::strerror(errno) + ")");
        if (got == 0) break;
        bytes.append(chunk, size_t(got));
        if (maxBytes && bytes.size() > maxBytes) throw FileReadError(tooLarge);
    }
    return bytes;
}

}  // namespace pbrt
