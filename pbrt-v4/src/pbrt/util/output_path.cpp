#include <pbrt/util/output_path.h>

#include <pbrt/pbrt.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

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
}

void CheckOutputImagePath(const std::string &path) {
    CheckName(path, "a file name ending in .exr or .png");
    // The formats WriteImage (util/image.cpp) writes.
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".exr" && ext != ".png")
        throw Failure(path)("unsupported output image format \"" + ext + "\" (use .exr or .png)");
    CheckDirectory(path);
}

}  // namespace pbrt
