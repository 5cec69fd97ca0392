// libFuzzer target: the PLY reader (header, ascii and binary bodies). Every input must
// either give a mesh whose indices are all in range or throw PbrtError.
#include <pbrt/util/ply.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    try {
        pbrt::PlyMesh m =
            pbrt::ParsePly(std::string(reinterpret_cast<const char *>(data), size), "fuzz.ply");
        // The reader's promises: triangles, indices in range, one entry per vertex/triangle.
        if (m.indices.empty() || m.indices.size() % 3 != 0) std::abort();
        for (int i : m.indices)
            if (i < 0 || size_t(i) >= m.P.size()) std::abort();
        if ((!m.N.empty() && m.N.size() != m.P.size()) || (!m.uv.empty() && m.uv.size() != m.P.size()))
            std::abort();
        if (!m.faceIndices.empty() && m.faceIndices.size() != m.indices.size() / 3) std::abort();
    } catch (const pbrt::PbrtError &) {
    }
    return 0;
}
