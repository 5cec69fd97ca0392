// libFuzzer target: the PLY reader (header, ascii and binary bodies). Every input must
// either give a mesh whose indices are all in range or throw PbrtError.
#include <pbrt/util/ply.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    try {
        pbrt::PlyMesh m =
            pbrt::ParsePly(std::string(reinterpret_cast<const char *>(data), size), "fuzz.ply");
        // The reader's promises (ply.h): a mesh that breaks one is a crash for the fuzzer.
        std::string broken = pbrt::PlyMeshBrokenPromise(m);
        if (!broken.empty()) {
            std::fprintf(stderr, "ply_fuzz: the reader returned a mesh with %s\n", broken.c_str());
            std::abort();
        }
    } catch (const pbrt::PbrtError &) {
    }
    return 0;
}
