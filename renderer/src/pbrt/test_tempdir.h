// A fresh directory under the system temp directory for one test (or one test process),
// removed when it goes out of scope. Unique names (mkdtemp) keep concurrent test runs apart.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace pbrt {
namespace testing_util {

class TempDir {
  public:
    TempDir() {
        std::string tmpl = (std::filesystem::temp_directory_path() / "pbrt-test-XXXXXX").string();
        path = mkdtemp(tmpl.data());
    }
    ~TempDir() { std::filesystem::remove_all(path); }
    TempDir(const TempDir &) = delete;
    TempDir &operator=(const TempDir &) = delete;

    // The path of a file in the directory (not created).
    std::string File(const std::string &name) const { return (std::filesystem::path(path) / name).string(); }
    // Writes bytes to a file in the directory (creating sub-directories); returns its path.
    std::string Write(const std::string &rel, const std::string &bytes) const {
        std::filesystem::path p = std::filesystem::path(path) / rel;
        std::filesystem::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << bytes;
        return p.string();
    }

    std::string path;
};

}  // namespace testing_util
}  // namespace pbrt
