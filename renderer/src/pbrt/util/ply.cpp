// PLY reader, written by hand from the PLY format description (Greg Turk, 1994): Debian has
// no PLY library that fits. libassimp reads PLY but merges, reorders and re-indexes vertices
// (and drops face_indices), while the renderer needs the mesh exactly as stored; librply is
// not packaged for C++ use with the types pbrt scenes use; tinyply and happly are not in
// Debian.
#include <pbrt/util/ply.h>

#include <pbrt/util/file.h>

#include <cctype>
#include <charconv>
#include <limits>
#include <utility>
#include <cmath>
#include <cstring>
#include <iterator>
#include <sstream>

namespace pbrt {

namespace {

// A value read from the file, for a message: any double (a cast to an integer type would be
// undefined beyond its range, and the fuzzer found such an index).
std::string FormatValue(double x) {
    std::ostringstream s;
    s.precision(17);
    s << x;
    return s.str();
}

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64, Invalid };

PlyType ParseType(const std::string &s) {
    if (s == "char" || s == "int8") return PlyType::Int8;
    if (s == "uchar" || s == "uint8") return PlyType::UInt8;
    if (s == "short" || s == "int16") return PlyType::Int16;
    if (s == "ushort" || s == "uint16") return PlyType::UInt16;
    if (s == "int" || s == "int32") return PlyType::Int32;
    if (s == "uint" || s == "uint32") return PlyType::UInt32;
    if (s == "float" || s == "float32") return PlyType::Float32;
    if (s == "double" || s == "float64") return PlyType::Float64;
    return PlyType::Invalid;
}

size_t TypeSize(PlyType t) {
    switch (t) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
    default: return 0;
    }
}

bool IsIntegerType(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct Property {
    std::string name;
    PlyType type = PlyType::Invalid;       // the value type (list items for a list)
    PlyType countType = PlyType::Invalid;  // the count type, for a list
    bool isList = false;
    int role = -1;  // what the reader does with the values (set per element below)
};

struct Element {
    std::string name;
    size_t count = 0;
    std::vector<Property> properties;
};

enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

// Reads the values of the body one at a time, in any of the three encodings.
class BodyReader {
  public:
    BodyReader(const std::string &data, size_t pos, Encoding enc, const std::string &path)
        : data(data), pos(pos), enc(enc), path(path) {}

    double Read(PlyType t) {
        if (enc == Encoding::Ascii) return ReadAscii(t);
        size_t n = TypeSize(t);
        if (pos + n > data.size())
            throw PbrtError("\"" + path + "\": unexpected end of file in the PLY data "
                            "(truncated file?)");
        unsigned char b[8];
        std::memcpy(b, data.data() + pos, n);
        pos += n;
        if (NeedsSwap())
            for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
        switch (t) {
        case PlyType::Int8: { int8_t v; std::memcpy(&v, b, 1); return v; }
        case PlyType::UInt8: return b[0];
        case PlyType::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
        case PlyType::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
        case PlyType::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
        case PlyType::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
        case PlyType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
        default: { double v; std::memcpy(&v, b, 8); return v; }
        }
    }

    // A list's item count; a count larger than the remaining bytes is malformed.
    size_t ReadCount(PlyType t) {
        double n = Read(t);
        if (!(n >= 0 && n <= double(Remaining()) + 1))  // NaN too
            throw PbrtError("\"" + path + "\": bad list count " + FormatValue(n) +
                            " in the PLY data");
        return size_t(n);
    }

    size_t Remaining() const { return data.size() - pos; }

  private:
    bool NeedsSwap() const {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
        return enc == Encoding::BinaryLittleEndian;
#else
        return enc == Encoding::BinaryBigEndian;
#endif
    }

    double ReadAscii(PlyType t) {
        // Values are separated by white space; line structure is not needed.
        while (pos < data.size() && std::isspace((unsigned char)data[pos])) ++pos;
        size_t start = pos;
        while (pos < data.size() && !std::isspace((unsigned char)data[pos])) ++pos;
        if (start == pos)
            throw PbrtError("\"" + path + "\": unexpected end of file in the PLY data "
                            "(truncated file?)");
        const char *b = data.data() + start, *e = data.data() + pos;
        if (*b == '+') ++b;
        double v = 0;
        auto [ptr, ec] = std::from_chars(b, e, v);
        if (ec != std::errc() || ptr != e || !std::isfinite(v) ||
            (IsIntegerType(t) && v != std::floor(v)))
            throw PbrtError("\"" + path + "\": bad value '" + std::string(data, start, pos - start) +
                            "' in the ascii PLY data");
        return v;
    }

    const std::string &data;
    size_t pos;
    Encoding enc;
    const std::string &path;
};

// Which vertex attribute a property fills (-1: none).
int VertexSlot(const std::string &n) {
    if (n == "x") return 0;
    if (n == "y") return 1;
    if (n == "z") return 2;
    if (n == "nx") return 3;
    if (n == "ny") return 4;
    if (n == "nz") return 5;
    if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") return 6;
    if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") return 7;
    return -1;
}

}  // namespace

PlyMesh ReadPly(const std::string &path) {
    auto fail = [&](const std::string &why) { return PbrtError("\"" + path + "\": " + why); };

    // Regular files only: a directory, device or FIFO is refused before a byte is read.
    std::string data;
    try {
        data = ReadRegularFile(path, "PLY");
    } catch (const FileReadError &e) {
        throw fail(e.what());
    }
    return ParsePly(data, path);
}

PlyMesh ParsePly(const std::string &data, const std::string &path) {
    auto fail = [&](const std::string &why) { return PbrtError("\"" + path + "\": " + why); };

    // The header: text lines up to "end_header".
    size_t pos = 0;
    int lineNo = 0;
    auto nextLine = [&](std::string *line) {
        if (pos >= data.size()) return false;
        size_t nl = data.find('\n', pos);
        size_t end = nl == std::string::npos ? data.size() : nl;
        *line = data.substr(pos, end - pos);
        if (!line->empty() && line->back() == '\r') line->pop_back();
        pos = nl == std::string::npos ? data.size() : nl + 1;
        ++lineNo;
        return true;
    };
    auto headerError = [&](const std::string &why) {
        return fail("line " + std::to_string(lineNo) + " of the PLY header: " + why);
    };

    std::string line;
    if (!nextLine(&line) || line != "ply") throw fail("not a PLY file (no \"ply\" first line)");
    bool haveFormat = false, haveEnd = false;
    Encoding enc = Encoding::Ascii;
    std::vector<Element> elements;
    while (nextLine(&line)) {
        std::istringstream words(line);
        std::string keyword;
        words >> keyword;
        if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
        if (keyword == "end_header") {
            haveEnd = true;
            break;
        }
        if (keyword == "format") {
            std::string format, version;
            words >> format >> version;
            if (format == "ascii") enc = Encoding::Ascii;
            else if (format == "binary_little_endian") enc = Encoding::BinaryLittleEndian;
            else if (format == "binary_big_endian") enc = Encoding::BinaryBigEndian;
            else throw headerError("unknown format \"" + format + "\"");
            if (version != "1.0") throw headerError("unsupported version \"" + version + "\"");
            haveFormat = true;
        } else if (keyword == "element") {
            Element e;
            std::string countText, extra;
            words >> e.name >> countText >> extra;
            unsigned long long count = 0;
            auto [end, err] = std::from_chars(countText.data(), countText.data() + countText.size(), count);
            if (e.name.empty() || countText.empty() || err != std::errc() ||
                end != countText.data() + countText.size() || !extra.empty())
                throw headerError("bad element line \"" + line + "\" (expected: element NAME COUNT)");
            e.count = size_t(count);
            // One vertex and one face element: a second would leave the normals, texture
            // coordinates or face indices of one of them without entries for the other's
            // vertices or triangles (the fuzzer found both).
            if (e.name == "vertex" || e.name == "face")
                for (const Element &prev : elements)
                    if (prev.name == e.name)
                        throw headerError("a second \"" + e.name + "\" element (a mesh has one)");
            elements.push_back(std::move(e));
        } else if (keyword == "property") {
            if (elements.empty()) throw headerError("property before any element");
            Property p;
            std::string type;
            words >> type;
            if (type == "list") {
                std::string countType, itemType;
                words >> countType >> itemType >> p.name;
                p.isList = true;
                p.countType = ParseType(countType);
                p.type = ParseType(itemType);
                if (p.countType == PlyType::Invalid || !IsIntegerType(p.countType) ||
                    p.type == PlyType::Invalid || p.name.empty())
                    throw headerError("bad list property \"" + line + "\"");
            } else {
                words >> p.name;
                p.type = ParseType(type);
                if (p.type == PlyType::Invalid || p.name.empty())
                    throw headerError("bad property \"" + line + "\"");
            }
            elements.back().properties.push_back(std::move(p));
        } else {
            throw headerError("unknown keyword \"" + keyword + "\"");
        }
    }
    if (!haveEnd) throw fail("PLY header has no end_header (truncated file?)");
    if (!haveFormat) throw fail("PLY header has no format line");

    // Reject counts the remaining bytes cannot hold before allocating anything for them.
    size_t remaining = data.size() - pos;
    for (const Element &e : elements) {
        size_t minRow = 0;
        for (const Property &p : e.properties)
            minRow += enc == Encoding::Ascii ? 2 : TypeSize(p.isList ? p.countType : p.type);
        if (minRow > 0 && e.count > remaining / minRow + 1)
            throw fail("element \"" + e.name + "\" claims " + std::to_string(e.count) +
                       " entries, more than the file holds (truncated file?)");
    }

    PlyMesh mesh;
    BodyReader body(data, pos, enc, path);
    bool sawVertex = false;
    std::vector<double> list;
    constexpr int kIndices = 100, kFaceIndex = 101;
    for (Element &e : elements) {
        if (e.name == "vertex") {
            // Which attributes the vertices carry.
            bool have[8] = {};
            for (Property &p : e.properties) {
                p.role = p.isList ? -1 : VertexSlot(p.name);
                if (p.role >= 0) have[p.role] = true;
            }
            if (!have[0] || !have[1] || !have[2])
                throw fail("vertex element lacks one of the properties x, y, z");
            bool haveN = have[3] && have[4] && have[5];
            if (!haveN && (have[3] || have[4] || have[5]))
                throw fail("vertex element has some but not all of nx, ny, nz");
            bool haveUV = have[6] && have[7];
            if (!haveUV && (have[6] || have[7]))
                throw fail("vertex element has only one texture coordinate (u without v?)");
            sawVertex = true;
            mesh.P.resize(e.count);
            if (haveN) mesh.N.resize(e.count);
            if (haveUV) mesh.uv.resize(e.count);
            for (size_t i = 0; i < e.count; ++i) {
                double v[8] = {};
                for (const Property &p : e.properties) {
                    if (p.isList) {
                        size_t n = body.ReadCount(p.countType);
                        for (size_t k = 0; k < n; ++k) body.Read(p.type);
                        continue;
                    }
                    double x = body.Read(p.type);
                    if (p.role >= 0) v[p.role] = x;
                }
                mesh.P[i] = {Float(v[0]), Float(v[1]), Float(v[2])};
                if (haveN) mesh.N[i] = {Float(v[3]), Float(v[4]), Float(v[5])};
                if (haveUV) mesh.uv[i] = {Float(v[6]), Float(v[7])};
            }
        } else if (e.name == "face") {
            bool haveFaceIndex = false, haveIndices = false;
            for (Property &p : e.properties) {
                if (p.name == "face_indices" && !p.isList) {
                    p.role = kFaceIndex;
                    haveFaceIndex = true;
                }
                if ((p.name == "vertex_indices" || p.name == "vertex_index") && p.isList &&
                    !haveIndices) {
                    if (!IsIntegerType(p.type))
                        throw fail("face property \"" + p.name + "\" has non-integer indices");
                    p.role = kIndices;
                    haveIndices = true;
                }
            }
            if (!haveIndices) throw fail("face element has no vertex_indices list");
            mesh.indices.reserve(3 * e.count);
            for (size_t i = 0; i < e.count; ++i) {
                int faceIndex = 0;
                list.clear();
                for (const Property &p : e.properties) {
                    if (p.isList) {
                        size_t n = body.ReadCount(p.countType);
                        for (size_t k = 0; k < n; ++k) {
                            double x = body.Read(p.type);
                            if (p.role == kIndices) list.push_back(x);
                        }
                    } else {
                        double x = body.Read(p.type);
                        if (p.role == kFaceIndex) {
                            if (!(x >= double(std::numeric_limits<int>::min()) &&
                                  x <= double(std::numeric_limits<int>::max())))
                                throw fail("face " + std::to_string(i) + " has face index " +
                                           FormatValue(x) + ", out of range");
                            faceIndex = int(x);
                        }
                    }
                }
                // Triangles as they are; quads and larger polygons as fans from vertex 0.
                if (list.size() < 3)
                    throw fail("face " + std::to_string(i) + " has " +
                               std::to_string(list.size()) + " vertices (at least 3 needed)");
                for (double x : list)
                    if (!(x >= 0 && x <= double(std::numeric_limits<int>::max())))  // NaN too
                        throw fail("face " + std::to_string(i) + " uses vertex index " +
                                   FormatValue(x) + ", out of range");
                for (size_t k = 1; k + 1 < list.size(); ++k) {
                    mesh.indices.push_back(int(list[0]));
                    mesh.indices.push_back(int(list[k]));
                    mesh.indices.push_back(int(list[k + 1]));
                    if (haveFaceIndex) mesh.faceIndices.push_back(faceIndex);
                }
            }
        } else {
            // Elements the renderer does not use (edges, materials, ...) are skipped. An
            // element without properties holds no data, whatever its count says.
            if (e.properties.empty()) continue;
            for (size_t i = 0; i < e.count; ++i)
                for (const Property &p : e.properties) {
                    size_t n = p.isList ? body.ReadCount(p.countType) : 1;
                    for (size_t k = 0; k < n; ++k) body.Read(p.type);
                }
        }
    }
    if (!sawVertex) throw fail("PLY file has no vertex element");
    if (mesh.indices.empty()) throw fail("PLY file has no faces");
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (size_t(mesh.indices[i]) >= mesh.P.size())
            throw fail("triangle " + std::to_string(i / 3) + " uses vertex index " +
                       std::to_string(mesh.indices[i]) + ", out of range (the mesh has " +
                       std::to_string(mesh.P.size()) + " vertices)");
    return mesh;
}

std::string PlyMeshBrokenPromise(const PlyMesh &m) {
    if (m.indices.empty() || m.indices.size() % 3 != 0)
        return std::to_string(m.indices.size()) + " indices, not a positive multiple of 3";
    for (int i : m.indices)
        if (i < 0 || size_t(i) >= m.P.size())
            return "vertex index " + std::to_string(i) + " out of range (" + std::to_string(m.P.size()) +
                   " vertices)";
    if (!m.N.empty() && m.N.size() != m.P.size())
        return std::to_string(m.N.size()) + " normals for " + std::to_string(m.P.size()) + " vertices";
    if (!m.uv.empty() && m.uv.size() != m.P.size())
        return std::to_string(m.uv.size()) + " texture coordinates for " + std::to_string(m.P.size()) +
               " vertices";
    if (!m.faceIndices.empty() && m.faceIndices.size() != m.indices.size() / 3)
        return std::to_string(m.faceIndices.size()) + " face indices for " +
               std::to_string(m.indices.size() / 3) + " triangles";
    return "";
}

}  // namespace pbrt
