#include <pbrt/util/output_path.h>

#include <pbrt/pbrt.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace pbrt {

void CheckOutputImagePath(const std::string &path) {
    namespace fs = std::filesystem;
    auto fail = [&](const std::string &why) { return PbrtError("\"" + path + "\": " + why); };
    if (path.empty()) throw fail("empty output file name");
    std::error_code ec;
    if (fs::is_directory(path, ec))
        throw fail("is a directory; the output needs a file name ending in .exr or .png");
    // The formats WriteImage (util/image.cpp) writes.
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".exr" && ext != ".png")
        throw fail("unsupported output image format \"" + ext + "\" (use .exr or .png)");
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec)) throw fail("the output directory does not exist");
    if (access(dir.c_str(), W_OK) != 0) throw fail("the output directory is not writable");
}

}  // namespace pbrt
