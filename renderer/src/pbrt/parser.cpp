// The pbrt-v4 scene-file parser: tokenizer, parameter lists and directive dispatch.
// Written from the pbrt-v4 file-format documentation (pbrt.org/fileformat-v4).
#include <pbrt/parser.h>

#include <pbrt/util/file.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <sstream>

namespace pbrt {

// ---------------------------------------------------------------------------------------
// Files and paths

namespace {

// The directory part of a path ("" when it has none; "/" for a file in the root).
std::string DirectoryOf(const std::string &path) {
    size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) return "";
    if (slash == 0) return "/";
    return path.substr(0, slash);
}

std::string JoinPath(const std::string &dir, const std::string &name) {
    if (dir.empty()) return name;
    if (dir.back() == '/') return dir + name;
    return dir + "/" + name;
}

bool IsRegularFile(const std::string &path) {
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec);
}

bool HasSuffix(const std::string &s, const char *suffix) {
    size_t n = std::strlen(suffix);
    return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

// The whole file in memory (the tokenizer then works on views into it). `from` is where the
// file was asked for (an Include), or null for a file named on the command line. Regular
// files only (a device or FIFO is refused before a byte is read, design §5.5).
std::string ReadSceneFile(const std::string &path, const FileLoc *from) {
    auto fail = [&](const std::string &why) -> PbrtError {
        std::string msg = "\"" + path + "\": " + why;
        return from ? PbrtError(*from, msg) : PbrtError(msg);
    };
    if (HasSuffix(path, ".gz"))
        throw fail("gzip-compressed scene files are not supported; decompress it first");
    try {
        return ReadRegularFile(path, "scene");
    } catch (const FileReadError &e) {
        throw fail(e.what());
    }
}

}  // namespace

std::string ResolveFilename(const std::string &name, const FileLoc &loc) {
    if (name.empty() || name.front() == '/') return name;
    return JoinPath(DirectoryOf(loc.filename), name);
}

// ---------------------------------------------------------------------------------------
// Tokenizer

Tokenizer::Tokenizer(std::string text_, std::string filename_)
    : text(std::move(text_)), filename(std::move(filename_)) {
    // Skip a UTF-8 byte-order mark, which some editors write.
    if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) pos = lineStart = 3;
}

bool Tokenizer::Next(Token *token) {
    // Skip white space and comments, counting lines.
    const size_t n = text.size();
    while (true) {
        if (pos >= n) return false;
        char c = text[pos];
        if (c == '\n') {
            ++pos;
            ++line;
            lineStart = pos;
        } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
            ++pos;
        } else if (c == '#') {
            while (pos < n && text[pos] != '\n') ++pos;
        } else {
            break;
        }
    }

    const size_t start = pos;
    token->line = line;
    token->column = int(start - lineStart) + 1;
    char c = text[pos];
    if (c == '[' || c == ']') {
        ++pos;
    } else if (c == '"') {
        // A quoted string ends on the same line; escapes are checked here so that Dequote
        // cannot fail.
        ++pos;
        while (true) {
            if (pos >= n || text[pos] == '\n')
                throw PbrtError(Loc(*token), "unterminated string (missing closing '\"')");
            char s = text[pos];
            if (s == '"') {
                ++pos;
                break;
            }
            if (s == '\\') {
                if (pos + 1 >= n || !std::strchr("\"\\ntrbf'", text[pos + 1]) ||
                    text[pos + 1] == '\0') {
                    FileLoc loc{filename, line, int(pos - lineStart) + 1};
                    throw PbrtError(loc, "unknown escape sequence in string");
                }
                pos += 2;
                continue;
            }
            ++pos;
        }
    } else {
        // A bare word runs to white space, a bracket, a quote or a comment.
        while (pos < n) {
            char b = text[pos];
            if (b == ' ' || b == '\n' || b == '\t' || b == '\r' || b == '\f' || b == '\v' ||
                b == '[' || b == ']' || b == '"' || b == '#')
                break;
            ++pos;
        }
    }
    token->text = std::string_view(text.data() + start, pos - start);
    return true;
}

std::string Dequote(const Token &token) {
    std::string_view body = token.text.substr(1, token.text.size() - 2);
    if (body.find('\\') == std::string_view::npos) return std::string(body);
    std::string out;
    out.reserve(body.size());
    for (size_t i = 0; i < body.size(); ++i) {
        if (body[i] != '\\' || i + 1 >= body.size()) {
            out += body[i];
            continue;
        }
        switch (body[++i]) {
        case 'n': out += '\n'; break;
        case 't': out += '\t'; break;
        case 'r': out += '\r'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        default: out += body[i]; break;  // \" \\ \'
        }
    }
    return out;
}

// ---------------------------------------------------------------------------------------
// Directive dispatcher

namespace {

// How a printed token looks in an error message.
std::string Show(const Token &t) {
    constexpr size_t kMax = 40;
    if (t.text.size() <= kMax) return "'" + std::string(t.text) + "'";
    return "'" + std::string(t.text.substr(0, kMax)) + "...'";
}

// Parses a bare token as a number the renderer's Float can hold; false if it is not one
// (also for "inf", "nan" and values beyond the float range).
bool ParseNumber(std::string_view s, double *v) {
    if (s.empty()) return false;
    const char *b = s.data(), *e = s.data() + s.size();
    if (*b == '+') ++b;
    if (b == e || !(std::isdigit((unsigned char)*b) || *b == '-' || *b == '.')) return false;
    auto [ptr, ec] = std::from_chars(b, e, *v);
    return ec == std::errc() && ptr == e && std::abs(*v) <= std::numeric_limits<Float>::max();
}

// Canonical parameter type names ("" for an unknown type).
std::string_view CanonicalType(std::string_view t) {
    static const char *const known[] = {"float",   "integer", "bool",      "string",   "point2",
                                        "vector2", "point3",  "vector3",   "normal3",  "rgb",
                                        "spectrum", "blackbody", "texture"};
    for (const char *k : known)
        if (t == k) return k;
    if (t == "point") return "point3";
    if (t == "vector") return "vector3";
    if (t == "normal") return "normal3";
    if (t == "color") return "rgb";
    return {};
}

// A token stream over one file with one token of look-ahead.
class TokenStream {
  public:
    TokenStream(std::string text, std::string filename)
        : tokenizer(std::move(text), std::move(filename)) {}
    bool Next(Token *t) {
        if (havePeek) {
            *t = peeked;
            havePeek = false;
            return true;
        }
        return tokenizer.Next(t);
    }
    bool Peek(Token *t) {
        if (!havePeek) havePeek = tokenizer.Next(&peeked);
        if (havePeek) *t = peeked;
        return havePeek;
    }
    FileLoc Loc(const Token &t) const { return tokenizer.Loc(t); }
    const std::string &Filename() const { return tokenizer.Filename(); }
    // Whether the file has begun with a directive: only then do error messages quote its
    // text (see Dispatcher::Parse).
    bool sceneText = false;

  private:
    Tokenizer tokenizer;
    Token peeked;
    bool havePeek = false;
};

class Dispatcher {
  public:
    Dispatcher(ParserTarget *target, std::string mainDirectory)
        : target(target), mainDirectory(std::move(mainDirectory)) {}

    void ParseFile(const std::string &path, const FileLoc *includedFrom, int depth) {
        TokenStream ts(ReadSceneFile(path, includedFrom), path);
        Parse(ts, depth);
    }
    void Parse(TokenStream &ts, int depth);

  private:
    // A token the directive needs; an error naming the directive at the end of the file.
    Token Require(TokenStream &ts, const Token &directive, const char *what) {
        Token t;
        if (!ts.Next(&t))
            throw PbrtError(ts.Loc(directive), "unexpected end of file: " +
                                                   std::string(directive.text) + " expects " +
                                                   what);
        return t;
    }
    std::string RequireString(TokenStream &ts, const Token &directive, const char *what) {
        Token t = Require(ts, directive, what);
        if (!t.IsQuoted())
            throw PbrtError(ts.Loc(t), std::string(directive.text) + " expects " + what +
                                           " (a quoted string), got " + Show(t));
        return Dequote(t);
    }
    Float RequireNumber(TokenStream &ts, const Token &directive, const Token &t) {
        double v;
        if (t.IsQuoted() || !ParseNumber(t.text, &v))
            throw PbrtError(ts.Loc(t), std::string(directive.text) + " expects a number, got " +
                                           Show(t));
        return Float(v);
    }
    // `n` numbers, written bare or inside [ ].
    void RequireNumbers(TokenStream &ts, const Token &directive, int n, Float *out);
    ParsedParameterVector ReadParameters(TokenStream &ts);
    enum class ValueKind { Number, Integer, Bool, String, Spectrum };
    void AddValue(TokenStream &ts, ParsedParameter &p, ValueKind kind, const Token &v);
    void CheckCounts(const ParsedParameter &p);
    void Include(TokenStream &ts, const Token &directive, int depth);
    void OptionDirective(TokenStream &ts, const Token &directive);
    void PopScope(TokenStream &ts, const Token &directive, char kind);

    ParserTarget *target;
    std::string mainDirectory;
    // Open AttributeBegin ('A'), TransformBegin ('T') and ObjectBegin ('O') blocks, across
    // included files.
    std::vector<char> scopes;
    bool warnedTransformBegin = false;
};

void Dispatcher::RequireNumbers(TokenStream &ts, const Token &directive, int n, Float *out) {
    std::string what = std::to_string(n) + " numbers";
    Token t = Require(ts, directive, what.c_str());
    if (t.IsOpenBracket()) {
        int count = 0;
        while (true) {
            Token v = Require(ts, directive, what.c_str());
            if (v.IsCloseBracket()) break;
            Float x = RequireNumber(ts, directive, v);
            if (count < n) out[count] = x;
            ++count;
        }
        if (count != n)
            throw PbrtError(ts.Loc(directive), std::string(directive.text) + " expects " + what +
                                                   ", got " + std::to_string(count));
        return;
    }
    out[0] = RequireNumber(ts, directive, t);
    for (int i = 1; i < n; ++i) out[i] = RequireNumber(ts, directive, Require(ts, directive, what.c_str()));
}

void Dispatcher::AddValue(TokenStream &ts, ParsedParameter &p, ValueKind kind, const Token &v) {
    auto bad = [&](const char *expected) {
        return PbrtError(ts.Loc(v), "parameter \"" + p.type + " " + p.name + "\" expects " +
                                        expected + ", got " + Show(v));
    };
    if (v.IsQuoted()) {
        if (kind == ValueKind::String || kind == ValueKind::Spectrum) {
            p.strings.push_back(Dequote(v));
        } else if (kind == ValueKind::Bool) {
            std::string_view body = v.text.substr(1, v.text.size() - 2);
            if (body == "true") p.bools.push_back(1);
            else if (body == "false") p.bools.push_back(0);
            else throw bad("true or false");
        } else {
            throw bad(kind == ValueKind::Integer ? "integers" : "numbers");
        }
        return;
    }
    if (kind == ValueKind::Bool) {
        if (v.text == "true") p.bools.push_back(1);
        else if (v.text == "false") p.bools.push_back(0);
        else throw bad("true or false");
        return;
    }
    if (kind == ValueKind::String) throw bad("a quoted string");
    double x;
    if (!ParseNumber(v.text, &x)) throw bad(kind == ValueKind::Integer ? "integers" : "numbers");
    if (kind == ValueKind::Integer) {
        if (x != std::floor(x) || x < std::numeric_limits<int>::min() ||
            x > std::numeric_limits<int>::max())
            throw bad("integers");
        p.ints.push_back(int(x));
    } else {
        p.floats.push_back(x);
    }
}

void Dispatcher::CheckCounts(const ParsedParameter &p) {
    auto fail = [&](const std::string &why) {
        throw PbrtError(p.loc, "parameter \"" + p.type + " " + p.name + "\": " + why);
    };
    size_t nf = p.floats.size();
    if ((p.type == "point2" || p.type == "vector2") && nf % 2 != 0)
        fail("expects pairs of numbers, got " + std::to_string(nf) + " values");
    if ((p.type == "point3" || p.type == "vector3" || p.type == "normal3") && nf % 3 != 0)
        fail("expects triples of numbers, got " + std::to_string(nf) + " values");
    if (p.type == "rgb" && nf != 3) fail("expects 3 values, got " + std::to_string(nf));
    if (p.type == "blackbody" && nf != 1)
        fail("expects one value (a temperature in kelvin), got " + std::to_string(nf));
    if (p.type == "spectrum") {
        if (!p.floats.empty() && !p.strings.empty())
            fail("mixes numbers and strings");
        if (p.strings.size() > 1) fail("expects one file or spectrum name");
        if (nf % 2 != 0)
            fail("expects (wavelength, value) pairs, got " + std::to_string(nf) + " values");
    }
}

ParsedParameterVector Dispatcher::ReadParameters(TokenStream &ts) {
    ParsedParameterVector params;
    Token decl;
    while (ts.Peek(&decl) && decl.IsQuoted()) {
        ts.Next(&decl);
        ParsedParameter p;
        p.loc = ts.Loc(decl);

        // The declaration: exactly two words, "type name".
        std::string text = Dequote(decl);
        std::istringstream words(text);
        std::string type, name, extra;
        words >> type >> name >> extra;
        if (type.empty() || name.empty() || !extra.empty())
            throw PbrtError(p.loc, "parameter declaration \"" + text +
                                       "\" is not of the form \"type name\"");
        std::string_view canonical = CanonicalType(type);
        if (canonical.empty())
            throw PbrtError(p.loc, "unknown parameter type \"" + type + "\" in \"" + text + "\"");
        p.type = std::string(canonical);
        p.name = std::move(name);
        const ValueKind kind = p.type == "integer"                          ? ValueKind::Integer
                               : p.type == "bool"                           ? ValueKind::Bool
                               : p.type == "string" || p.type == "texture" ? ValueKind::String
                               : p.type == "spectrum"                       ? ValueKind::Spectrum
                                                                            : ValueKind::Number;

        // The values: one token, or a bracketed list.
        auto noValues = [&] {
            return PbrtError(p.loc, "parameter \"" + text + "\" has no values");
        };
        Token v;
        if (!ts.Peek(&v)) throw noValues();
        if (v.IsOpenBracket()) {
            ts.Next(&v);
            const Token open = v;
            while (true) {
                if (!ts.Next(&v))
                    throw PbrtError(ts.Loc(open), "unterminated '[' (missing ']') in parameter \"" +
                                                      text + "\"");
                if (v.IsCloseBracket()) break;
                if (v.IsOpenBracket())
                    throw PbrtError(ts.Loc(v), "mismatched brackets: '[' inside the values of \"" +
                                                   text + "\"");
                AddValue(ts, p, kind, v);
            }
        } else if (v.IsCloseBracket()) {
            throw PbrtError(ts.Loc(v), "mismatched brackets: ']' without '['");
        } else {
            // A capitalized bare word that is not a value is the next directive: the
            // declaration had no values.
            double x;
            if (!v.IsQuoted() && v.text != "true" && v.text != "false" &&
                !ParseNumber(v.text, &x) && std::isupper((unsigned char)v.text[0]))
                throw noValues();
            ts.Next(&v);
            AddValue(ts, p, kind, v);
        }
        if (p.floats.empty() && p.ints.empty() && p.strings.empty() && p.bools.empty())
            throw noValues();
        CheckCounts(p);
        params.push_back(std::move(p));
    }
    return params;
}

void Dispatcher::Include(TokenStream &ts, const Token &directive, int depth) {
    FileLoc loc = ts.Loc(directive);
    std::string name = RequireString(ts, directive, "a file name");
    if (depth >= 64)
        throw PbrtError(loc, "Include nested more than 64 levels deep (does a file include "
                             "itself?)");
    // Relative to the including file; failing that, to the first scene file's directory.
    std::string path = ResolveFilename(name, loc);
    if (!IsRegularFile(path) && !name.empty() && name.front() != '/') {
        std::string alt = JoinPath(mainDirectory, name);
        if (IsRegularFile(alt)) path = alt;
    }
    ParseFile(path, &loc, depth + 1);
}

void Dispatcher::OptionDirective(TokenStream &ts, const Token &directive) {
    FileLoc loc = ts.Loc(directive);
    Token decl = Require(ts, directive, "a \"type name\" declaration");
    if (!decl.IsQuoted())
        throw PbrtError(ts.Loc(decl), "Option expects a \"type name\" declaration, got " +
                                          Show(decl));
    std::string text = Dequote(decl);
    std::istringstream words(text);
    std::string type, name, extra;
    words >> type >> name >> extra;
    if (type.empty() || name.empty() || !extra.empty())
        throw PbrtError(ts.Loc(decl),
                        "Option declaration \"" + text + "\" is not of the form \"type name\"");
    if (type != "bool" && type != "integer" && type != "float" && type != "string")
        throw PbrtError(ts.Loc(decl), "unknown Option type \"" + type + "\"");

    // One value, bare or in brackets.
    Token v = Require(ts, directive, "a value");
    bool bracketed = v.IsOpenBracket();
    if (bracketed) v = Require(ts, directive, "a value");
    if (v.IsOpenBracket() || v.IsCloseBracket())
        throw PbrtError(ts.Loc(v), "Option \"" + text + "\" expects one value, got " + Show(v));
    if (bracketed) {
        Token close = Require(ts, directive, "']'");
        if (!close.IsCloseBracket())
            throw PbrtError(ts.Loc(close), "Option \"" + text + "\" expects one value");
    }
    std::string value = v.IsQuoted() ? Dequote(v) : std::string(v.text);
    double x;
    bool ok = type == "string"    ? v.IsQuoted()
              : type == "bool"    ? (value == "true" || value == "false")
              : type == "integer" ? (!v.IsQuoted() && ParseNumber(value, &x) && x == std::floor(x))
                                  : (!v.IsQuoted() && ParseNumber(value, &x));
    if (!ok)
        throw PbrtError(ts.Loc(v), "Option \"" + text + "\" has a value of the wrong type: " +
                                       Show(v));
    target->Option(name, value, loc);
}

void Dispatcher::PopScope(TokenStream &ts, const Token &directive, char kind) {
    const char *opener = kind == 'O' ? "ObjectBegin" : "AttributeBegin";
    bool ok = !scopes.empty() && (kind == 'O' ? scopes.back() == 'O' : scopes.back() != 'O');
    if (!ok) {
        std::string msg = std::string(directive.text) + " without a matching " + opener;
        if (!scopes.empty() && scopes.back() == 'O' && kind != 'O')
            msg += " (inside ObjectBegin ... ObjectEnd)";
        throw PbrtError(ts.Loc(directive), msg);
    }
    scopes.pop_back();
}

// The directives of the format (those Parse dispatches on).
bool IsDirective(std::string_view d) {
    static const char *const names[] = {
        "Shape", "Material", "MakeNamedMaterial", "LightSource", "AreaLightSource", "Camera",
        "Film", "Sampler", "PixelFilter", "Integrator", "Accelerator", "MakeNamedMedium",
        "AttributeBegin", "AttributeEnd", "NamedMaterial", "Texture", "Translate", "Scale",
        "Rotate", "LookAt", "Transform", "ConcatTransform", "Identity", "CoordinateSystem",
        "CoordSysTransform", "ActiveTransform", "TransformTimes", "ReverseOrientation",
        "WorldBegin", "Attribute", "ObjectBegin", "ObjectEnd", "ObjectInstance", "ColorSpace",
        "Option", "MediumInterface", "Include", "Import", "TransformBegin", "TransformEnd",
        "WorldEnd"};
    for (const char *n : names)
        if (d == n) return true;
    return false;
}

void Dispatcher::Parse(TokenStream &ts, int depth) {
    Token t;
    while (ts.Next(&t)) {
        // A file is scene text once it begins with a directive; one that does not (a system
        // file an Include names, a binary file) is refused at its first token, naming the file
        // and the line but not quoting its content, which an error message could otherwise
        // disclose (design §5.5). Comments and white space before the first directive are fine.
        if (!ts.sceneText) {
            if (t.IsQuoted() || !IsDirective(t.text))
                throw PbrtError(ts.Loc(t), "not a pbrt-v4 scene file: it does not begin with a "
                                           "directive (its content is not shown)");
            ts.sceneText = true;
        }
        if (t.IsQuoted() || t.IsOpenBracket() || t.IsCloseBracket()) {
            const char *why = t.IsQuoted() ? "expected a directive, got the string "
                                           : "mismatched brackets: expected a directive, got ";
            throw PbrtError(ts.Loc(t), why + Show(t));
        }
        const std::string_view d = t.text;
        FileLoc loc = ts.Loc(t);
        Float v[16];

        // Directives with a name and a parameter list.
        using NamedCall = void (ParserTarget::*)(const std::string &, ParsedParameterVector,
                                                 FileLoc);
        NamedCall named = nullptr;
        if (d == "Shape") named = &ParserTarget::Shape;
        else if (d == "Material") named = &ParserTarget::Material;
        else if (d == "MakeNamedMaterial") named = &ParserTarget::MakeNamedMaterial;
        else if (d == "LightSource") named = &ParserTarget::LightSource;
        else if (d == "AreaLightSource") named = &ParserTarget::AreaLightSource;
        else if (d == "Camera") named = &ParserTarget::Camera;
        else if (d == "Film") named = &ParserTarget::Film;
        else if (d == "Sampler") named = &ParserTarget::Sampler;
        else if (d == "PixelFilter") named = &ParserTarget::PixelFilter;
        else if (d == "Integrator") named = &ParserTarget::Integrator;
        else if (d == "Accelerator") named = &ParserTarget::Accelerator;
        else if (d == "MakeNamedMedium") named = &ParserTarget::MakeNamedMedium;
        if (named) {
            std::string name = RequireString(ts, t, "a name");
            (target->*named)(name, ReadParameters(ts), loc);
            continue;
        }

        if (d == "AttributeBegin") {
            scopes.push_back('A');
            target->AttributeBegin(loc);
        } else if (d == "AttributeEnd") {
            PopScope(ts, t, 'A');
            target->AttributeEnd(loc);
        } else if (d == "NamedMaterial") {
            target->NamedMaterial(RequireString(ts, t, "a material name"), loc);
        } else if (d == "Texture") {
            std::string name = RequireString(ts, t, "a texture name");
            std::string type = RequireString(ts, t, "a texture type (\"float\" or \"spectrum\")");
            std::string texname = RequireString(ts, t, "a texture class");
            target->Texture(name, type, texname, ReadParameters(ts), loc);
        } else if (d == "Translate") {
            RequireNumbers(ts, t, 3, v);
            target->Translate(v[0], v[1], v[2], loc);
        } else if (d == "Scale") {
            RequireNumbers(ts, t, 3, v);
            target->Scale(v[0], v[1], v[2], loc);
        } else if (d == "Rotate") {
            RequireNumbers(ts, t, 4, v);
            target->Rotate(v[0], v[1], v[2], v[3], loc);
        } else if (d == "LookAt") {
            RequireNumbers(ts, t, 9, v);
            target->LookAt(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], loc);
        } else if (d == "Transform") {
            RequireNumbers(ts, t, 16, v);
            target->Transform(v, loc);
        } else if (d == "ConcatTransform") {
            RequireNumbers(ts, t, 16, v);
            target->ConcatTransform(v, loc);
        } else if (d == "Identity") {
            target->Identity(loc);
        } else if (d == "CoordinateSystem") {
            target->CoordinateSystem(RequireString(ts, t, "a name"), loc);
        } else if (d == "CoordSysTransform") {
            target->CoordSysTransform(RequireString(ts, t, "a name"), loc);
        } else if (d == "ActiveTransform") {
            Token w = Require(ts, t, "All, StartTime or EndTime");
            if (w.text == "All") target->ActiveTransformAll(loc);
            else if (w.text == "StartTime") target->ActiveTransformStartTime(loc);
            else if (w.text == "EndTime") target->ActiveTransformEndTime(loc);
            else
                throw PbrtError(ts.Loc(w), "ActiveTransform expects All, StartTime or EndTime, "
                                           "got " + Show(w));
        } else if (d == "TransformTimes") {
            RequireNumbers(ts, t, 2, v);
            target->TransformTimes(v[0], v[1], loc);
        } else if (d == "ReverseOrientation") {
            target->ReverseOrientation(loc);
        } else if (d == "WorldBegin") {
            target->WorldBegin(loc);
        } else if (d == "Attribute") {
            std::string which = RequireString(ts, t, "a target (\"shape\", \"light\", "
                                                     "\"material\", \"medium\" or \"texture\")");
            if (which != "shape" && which != "light" && which != "material" &&
                which != "medium" && which != "texture")
                throw PbrtError(loc, "Attribute target \"" + which + "\" is not one of "
                                     "\"shape\", \"light\", \"material\", \"medium\", \"texture\"");
            target->Attribute(which, ReadParameters(ts), loc);
        } else if (d == "ObjectBegin") {
            std::string name = RequireString(ts, t, "an object name");
            scopes.push_back('O');
            target->ObjectBegin(name, loc);
        } else if (d == "ObjectEnd") {
            PopScope(ts, t, 'O');
            target->ObjectEnd(loc);
        } else if (d == "ObjectInstance") {
            target->ObjectInstance(RequireString(ts, t, "an object name"), loc);
        } else if (d == "ColorSpace") {
            target->ColorSpace(RequireString(ts, t, "a colour space name"), loc);
        } else if (d == "Option") {
            OptionDirective(ts, t);
        } else if (d == "MediumInterface") {
            // One name (inside = outside) or two (inside, outside).
            std::string inside = RequireString(ts, t, "a medium name");
            std::string outside = inside;
            Token next;
            if (ts.Peek(&next) && next.IsQuoted()) {
                ts.Next(&next);
                outside = Dequote(next);
            }
            target->MediumInterface(inside, outside, loc);
        } else if (d == "Include" || d == "Import") {
            Include(ts, t, depth);
        } else if (d == "TransformBegin" || d == "TransformEnd") {
            // pbrt-v3's transform-only blocks: pbrt-v4 treats them as attribute blocks.
            if (!warnedTransformBegin)
                Warning(loc, "TransformBegin/TransformEnd are deprecated; treated as "
                             "AttributeBegin/AttributeEnd");
            warnedTransformBegin = true;
            if (d == "TransformBegin") {
                scopes.push_back('T');
                target->AttributeBegin(loc);
            } else {
                PopScope(ts, t, 'T');
                target->AttributeEnd(loc);
            }
        } else if (d == "WorldEnd") {
            Warning(loc, "WorldEnd is not part of the pbrt-v4 format; ignored");
        } else {
            double x;
            if (ParseNumber(d, &x))
                throw PbrtError(loc, "expected a directive, got the number " + Show(t) +
                                     " (too many values, or a parameter missing its brackets?)");
            throw PbrtError(loc, "unknown directive " + Show(t));
        }
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Entry points

void ParseFiles(ParserTarget *target, const std::vector<std::string> &filenames) {
    if (filenames.empty()) {
        // No file: the scene comes on standard input.
        std::string text((std::istreambuf_iterator<char>(std::cin)),
                         std::istreambuf_iterator<char>());
        ParseString(target, text, "<stdin>");
        return;
    }
    Dispatcher dispatcher(target, DirectoryOf(filenames.front()));
    for (const std::string &f : filenames) dispatcher.ParseFile(f, nullptr, 0);
    target->EndOfFiles();
}

void ParseString(ParserTarget *target, const std::string &text, const std::string &name) {
    Dispatcher dispatcher(target, DirectoryOf(name));
    TokenStream ts(text, name);
    dispatcher.Parse(ts, 0);
    target->EndOfFiles();
}

}  // namespace pbrt
