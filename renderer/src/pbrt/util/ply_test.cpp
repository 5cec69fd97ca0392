#include <pbrt/test_tempdir.h>
#include <pbrt/util/ply.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace pbrt;
namespace fs = std::filesystem;

namespace {

using pbrt::testing_util::TempDir;

// A small PLY writer for the tests: each property is (type, name); each row holds the values
// of one element entry, lists written as their count followed by the items.
struct PlyProperty {
    PlyProperty(std::string type, std::string name, std::string countType = "")
        : type(std::move(type)), name(std::move(name)), countType(std::move(countType)) {}
    std::string type, name;
    std::string countType;  // non-empty for a list
};
struct PlyElement {
    std::string name;
    std::vector<PlyProperty> properties;
    std::vector<std::vector<double>> rows;  // lists inline: count, items...
};

void PutBinary(std::string &out, const std::string &type, double v, bool bigEndian) {
    unsigned char b[8];
    size_t n;
    if (type == "uchar" || type == "uint8") { uint8_t x = uint8_t(v); std::memcpy(b, &x, n = 1); }
    else if (type == "char" || type == "int8") { int8_t x = int8_t(v); std::memcpy(b, &x, n = 1); }
    else if (type == "short" || type == "int16") { int16_t x = int16_t(v); std::memcpy(b, &x, n = 2); }
    else if (type == "ushort" || type == "uint16") { uint16_t x = uint16_t(v); std::memcpy(b, &x, n = 2); }
    else if (type == "int" || type == "int32") { int32_t x = int32_t(v); std::memcpy(b, &x, n = 4); }
    else if (type == "uint" || type == "uint32") { uint32_t x = uint32_t(v); std::memcpy(b, &x, n = 4); }
    else if (type == "float" || type == "float32") { float x = float(v); std::memcpy(b, &x, n = 4); }
    else { std::memcpy(b, &v, n = 8); }
    if (bigEndian)  // the test machine is little-endian (x86-64, aarch64)
        for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    out.append(reinterpret_cast<char *>(b), n);
}

std::string MakePly(const std::string &format, const std::vector<PlyElement> &elements,
                    const std::string &eol = "\n") {
    std::string out = "ply" + eol + "format " + format + " 1.0" + eol +
                      "comment written by ply_test" + eol;
    for (const PlyElement &e : elements) {
        out += "element " + e.name + " " + std::to_string(e.rows.size()) + eol;
        for (const PlyProperty &p : e.properties)
            out += p.countType.empty() ? "property " + p.type + " " + p.name + eol
                                       : "property list " + p.countType + " " + p.type + " " +
                                             p.name + eol;
    }
    out += "end_header" + eol;
    for (const PlyElement &e : elements) {
        for (const std::vector<double> &row : e.rows) {
            size_t k = 0;
            std::string line;
            auto put = [&](const std::string &type) {
                double v = row.at(k++);
                if (format == "ascii") {
                    char buf[32];
                    std::snprintf(buf, sizeof(buf), "%.17g ", v);
                    line += buf;
                } else {
                    PutBinary(out, type, v, format == "binary_big_endian");
                }
                return v;
            };
            for (const PlyProperty &p : e.properties) {
                if (p.countType.empty()) {
                    put(p.type);
                } else {
                    int n = int(put(p.countType));
                    for (int i = 0; i < n; ++i) put(p.type);
                }
            }
            if (format == "ascii") out += line + eol;
        }
    }
    return out;
}

// Five vertices with normals and uv; a triangle and a quad with face indices; an extra vertex
// property and an extra element the reader must skip.
std::vector<PlyElement> TestMesh() {
    PlyElement v{"vertex",
                 {{"float", "x"}, {"float", "y"}, {"float", "z"}, {"float", "nx"},
                  {"float", "ny"}, {"float", "nz"}, {"uchar", "red"}, {"float", "u"},
                  {"float", "v"}},
                 {}};
    for (int i = 0; i < 5; ++i)
        v.rows.push_back({0.5 * i, -1.25 * i, 3.0 + i, 0, 0.6, 0.8, double(10 * i), 0.25 * i,
                          1 - 0.125 * i});
    PlyElement f{"face", {{"int", "vertex_indices", "uchar"}, {"int", "face_indices"}}, {}};
    f.rows.push_back({3, 0, 1, 2, 10});
    f.rows.push_back({4, 1, 2, 3, 4, 20});
    PlyElement extra{"edge", {{"int", "vertex1"}, {"int", "ends", "uchar"}}, {}};
    extra.rows.push_back({0, 2, 1, 2});
    return {v, f, extra};
}

void ExpectTestMesh(const PlyMesh &m, const std::string &what) {
    ASSERT_EQ(m.P.size(), 5u) << what;
    ASSERT_EQ(m.N.size(), 5u) << what;
    ASSERT_EQ(m.uv.size(), 5u) << what;
    for (int i = 0; i < 5; ++i) {
        EXPECT_EQ(m.P[i], (std::array<Float, 3>{0.5f * i, -1.25f * i, 3.f + i})) << what;
        EXPECT_EQ(m.N[i], (std::array<Float, 3>{0.f, 0.6f, 0.8f})) << what;
        EXPECT_EQ(m.uv[i], (std::array<Float, 2>{0.25f * i, 1 - 0.125f * i})) << what;
    }
    // The quad (1 2 3 4) becomes triangles (1 2 3) and (1 3 4).
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 1, 2, 3, 1, 3, 4})) << what;
    EXPECT_EQ(m.faceIndices, (std::vector<int>{10, 20, 20})) << what;
}

// The message of the PbrtError that reading `path` throws ("" if none).
std::string ReadError(const std::string &path) {
    try {
        ReadPly(path);
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Ply, AllThreeEncodingsReadTheSameMesh) {
    TempDir dir;
    for (const char *format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
        std::string path = dir.Write(std::string(format) + ".ply", MakePly(format, TestMesh()));
        ExpectTestMesh(ReadPly(path), format);
    }
    // Windows line ends in the header.
    std::string crlf = dir.Write("crlf.ply", MakePly("ascii", TestMesh(), "\r\n"));
    ExpectTestMesh(ReadPly(crlf), "ascii with CRLF");
}

TEST(Ply, OtherTypesAndPropertyNames) {
    // double coordinates, s/t texture coordinates, uint counts and indices, "vertex_index".
    PlyElement v{"vertex", {{"double", "x"}, {"double", "y"}, {"double", "z"},
                            {"float", "s"}, {"float", "t"}}, {}};
    v.rows = {{0, 0, 0, 0, 0}, {1, 0, 0, 1, 0}, {1, 1, 0, 1, 1}, {0, 1, 0, 0, 1},
              {0.5, 1.5, 0, 0.5, 1.5}};
    PlyElement f{"face", {{"uint", "vertex_index", "uint"}}, {}};
    f.rows = {{5, 0, 1, 2, 4, 3}};  // a pentagon: a fan of three triangles
    TempDir dir;
    for (const char *format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
        PlyMesh m = ReadPly(dir.Write("m.ply", MakePly(format, {v, f})));
        EXPECT_TRUE(m.N.empty()) << format;
        EXPECT_TRUE(m.faceIndices.empty()) << format;
        ASSERT_EQ(m.uv.size(), 5u) << format;
        EXPECT_EQ(m.uv[4], (std::array<Float, 2>{0.5f, 1.5f})) << format;
        EXPECT_EQ(m.P[4], (std::array<Float, 3>{0.5f, 1.5f, 0.f})) << format;
        EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 0, 2, 4, 0, 4, 3})) << format;
    }
    // texture_u / texture_v, short indices with a char count, no uv at all.
    PlyElement v2{"vertex", {{"float", "x"}, {"float", "y"}, {"float", "z"},
                             {"float", "texture_u"}, {"float", "texture_v"}}, {}};
    v2.rows = {{0, 0, 0, .1, .2}, {1, 0, 0, .3, .4}, {0, 1, 0, .5, .6}};
    PlyElement f2{"face", {{"short", "vertex_indices", "char"}}, {}};
    f2.rows = {{3, 2, 1, 0}};
    PlyMesh m = ReadPly(dir.Write("tex.ply", MakePly("binary_little_endian", {v2, f2})));
    ASSERT_EQ(m.uv.size(), 3u);
    EXPECT_EQ(m.uv[2], (std::array<Float, 2>{.5f, .6f}));
    EXPECT_EQ(m.indices, (std::vector<int>{2, 1, 0}));
}

TEST(Ply, MalformedFilesGiveErrorsNamingTheFile) {
    TempDir dir;
    std::string good = MakePly("binary_little_endian", TestMesh());
    std::string goodAscii = MakePly("ascii", TestMesh());
    size_t body = good.find("end_header\n") + 11;

    struct Case {
        std::string name, bytes, reason;
    };
    std::vector<Case> cases = {
        {"empty.ply", "", "not a PLY file"},
        {"magic.ply", "plx\n" + good.substr(4), "not a PLY file"},
        {"format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format"},
        {"noformat.ply", "ply\nelement vertex 0\nend_header\n", "no format"},
        {"keyword.ply", "ply\nformat ascii 1.0\nelephant 3\nend_header\n", "unknown keyword"},
        {"proptype.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
         "bad property"},
        {"noend.ply", good.substr(0, good.find("end_header")), "no end_header"},
        {"truncated.ply", good.substr(0, good.size() - 3), "truncated"},
        {"truncated-body.ply", good.substr(0, body + 10), "truncated"},
        {"truncated-ascii.ply", goodAscii.substr(0, goodAscii.size() - 12), "truncated"},
        {"huge.ply",
         "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
         "property float y\nproperty float z\nend_header\n\1\2\3\4",
         "more than the file holds"},
        {"badvalue.ply",
         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 zero\n3 0 0 0\n",
         "bad value"},
        {"range.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
         "out of range"},
        {"negative.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n",
         "out of range"},
        {"line.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n2 0 1\n",
         "at least 3"},
        {"normal.ply",
         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
         "property float z\nproperty float nx\nend_header\n0 0 0 1\n",
         "nx, ny, nz"},
        {"noface.ply",
         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
         "property float z\nend_header\n0 0 0\n",
         "no faces"},
    };
    for (const Case &c : cases) {
        std::string path = dir.Write(c.name, c.bytes);
        std::string msg = ReadError(path);
        EXPECT_NE(msg.find(path), std::string::npos) << c.name << ": " << msg;
        EXPECT_NE(msg.find(c.reason), std::string::npos) << c.name << ": " << msg;
    }
    std::string missing = (fs::path(dir.path) / "missing.ply").string();
    EXPECT_NE(ReadError(missing).find(missing), std::string::npos);

    // Every truncation of a valid file, and random byte damage, gives an error or a mesh
    // with valid indices: never a crash.
    auto readDamaged = [&](const std::string &bytes) {
        std::string path = dir.Write("damaged.ply", bytes);
        try {
            PlyMesh m = ReadPly(path);
            for (int i : m.indices) ASSERT_TRUE(i >= 0 && size_t(i) < m.P.size());
        } catch (const PbrtError &e) {
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    };
    for (size_t n = 0; n < good.size(); ++n) readDamaged(good.substr(0, n));
    std::mt19937 rng(7);
    for (int trial = 0; trial < 400; ++trial) {
        std::string bytes = trial % 2 ? good : goodAscii;
        for (int k = 0; k < 3; ++k) bytes[rng() % bytes.size()] = char(rng() % 256);
        readDamaged(bytes);
    }
}

// The meshes of the evaluation scenes (outside the repository) read, with consistent data.
TEST(Ply, EvaluationSceneMeshes) {
    const fs::path scenes = fs::path(PBRT_SHARED_DIR) / "scenes";
    if (!fs::is_directory(scenes)) GTEST_SKIP() << scenes << " is not present";
    int files = 0;
    for (const fs::directory_entry &scene : fs::directory_iterator(scenes)) {
        fs::path models = scene.path() / "models";
        if (!fs::is_directory(models)) continue;
        for (const fs::directory_entry &f : fs::directory_iterator(models)) {
            if (f.path().extension() != ".ply") continue;
            ++files;
            const std::string path = f.path().string();
            PlyMesh m = ReadPly(path);

            // The face count in the header bounds the triangle count (tris and quads).
            std::ifstream in(path, std::ios::binary);
            std::string line;
            long faces = -1;
            while (std::getline(in, line) && line.rfind("end_header", 0) != 0)
                std::sscanf(line.c_str(), "element face %ld", &faces);
            long tris = long(m.indices.size() / 3);
            EXPECT_EQ(m.indices.size() % 3, 0u) << path;
            EXPECT_GE(tris, faces) << path;
            EXPECT_LE(tris, 2 * faces) << path;

            EXPECT_TRUE(m.N.empty() || m.N.size() == m.P.size()) << path;
            EXPECT_TRUE(m.uv.empty() || m.uv.size() == m.P.size()) << path;
            for (const auto &p : m.P)
                ASSERT_TRUE(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
                    << path;
            for (const auto &n : m.N) {
                float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                ASSERT_NEAR(len, 1.f, 1e-2f) << path;
            }
        }
    }
    EXPECT_GT(files, 0);
}

TEST(Ply, BrokenPromiseNamesEachBrokenPromise) {
    // The oracle the fuzz target and the robustness test share: silent on a whole mesh, and
    // naming each promise a mesh can break.
    PlyMesh ok;
    ok.P = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    ok.indices = {0, 1, 2};
    EXPECT_EQ(PlyMeshBrokenPromise(ok), "");
    ok.N = ok.P;
    ok.uv = {{0, 0}, {1, 0}, {0, 1}};
    ok.faceIndices = {7};
    EXPECT_EQ(PlyMeshBrokenPromise(ok), "");
    auto broken = [&](auto change, const std::string &what) {
        PlyMesh m = ok;
        change(m);
        EXPECT_NE(PlyMeshBrokenPromise(m).find(what), std::string::npos) << PlyMeshBrokenPromise(m);
    };
    broken([](PlyMesh &m) { m.indices.clear(); }, "0 indices");
    broken([](PlyMesh &m) { m.indices.push_back(0); }, "4 indices");
    broken([](PlyMesh &m) { m.indices[1] = 3; }, "vertex index 3 out of range");
    broken([](PlyMesh &m) { m.indices[1] = -1; }, "vertex index -1");
    broken([](PlyMesh &m) { m.N.pop_back(); }, "2 normals for 3 vertices");
    broken([](PlyMesh &m) { m.uv.push_back({0, 0}); }, "4 texture coordinates");
    broken([](PlyMesh &m) { m.faceIndices.push_back(1); }, "2 face indices for 1 triangles");
}
