// Reading triangle meshes from PLY files (pbrt-v4's "plymesh" shape).
#pragma once

#include <pbrt/pbrt.h>

#include <array>
#include <string>
#include <vector>

namespace pbrt {

// A mesh as stored in a PLY file. N and uv are empty when the file has no normals or texture
// coordinates; otherwise they have one entry per vertex, like P. `indices` holds triangles
// (three per triangle): quads are split along their 0-2 diagonal and larger polygons into
// fans. `faceIndices` is empty unless the faces have a "face_indices" property; then it has
// one entry per triangle (the value of the polygon it came from).
struct PlyMesh {
    std::vector<std::array<Float, 3>> P, N;
    std::vector<std::array<Float, 2>> uv;
    std::vector<int> indices;
    std::vector<int> faceIndices;
};

// Reads an ascii, binary_little_endian or binary_big_endian PLY file. Vertex properties
// x y z, nx ny nz, and u v (or s t, texture_u texture_v, texture_s texture_t); face
// properties vertex_indices (or vertex_index; any integer count and index types) and
// face_indices. Other elements and properties are skipped. Throws PbrtError naming the file
// on a malformed header, truncated data or a vertex index out of range.
PlyMesh ReadPly(const std::string &path);

// The same for a PLY file's bytes held in memory; `path` names it in error messages.
PlyMesh ParsePly(const std::string &data, const std::string &path);

// Which of PlyMesh's promises above `m` breaks (at least one triangle, indices in range, N,
// uv and faceIndices each empty or of full length), or "" when it keeps them all: the one
// statement of them that the fuzz target (renderer/fuzz/ply_fuzz.cpp) and the robustness
// test check every mesh the reader returns against.
std::string PlyMeshBrokenPromise(const PlyMesh &m);

}  // namespace pbrt
