// Reading pbrt-v4 scene files: a tokenizer (text -> tokens) and a directive dispatcher
// (tokens -> calls on a ParserTarget). The parser knows the syntax of the format only; what
// a directive means (transforms, graphics state, named objects) is the target's business.
//
// Format reference: the pbrt-v4 "File Format" documentation (pbrt.org/fileformat-v4).
#pragma once

#include <pbrt/pbrt.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pbrt {

// One parameter of a directive's parameter list, as written: "type name" value(s).
// `type` is canonical: the aliases "point", "vector", "normal" and "color" are stored as
// "point3", "vector3", "normal3" and "rgb". Values go to the vector that fits the type:
//   float, point2, vector2, point3, vector3, normal3, rgb, blackbody -> floats
//   integer -> ints;  bool -> bools;  string, texture -> strings
//   spectrum -> floats (interleaved lambda/value pairs) or strings (one file or named spectrum)
// The parser has already checked that the values fit the type (numbers for numeric types,
// exact integers for "integer", pairs for "point2", triples for "point3", three values for
// "rgb", one for "blackbody", an even count or one string for "spectrum").
struct ParsedParameter {
    std::string type, name;
    FileLoc loc;  // where the "type name" declaration was written
    std::vector<double> floats;
    std::vector<int> ints;
    std::vector<std::string> strings;
    std::vector<uint8_t> bools;
    mutable bool lookedUp = false;
};
using ParsedParameterVector = std::vector<ParsedParameter>;

// The receiver of the directives, one virtual per directive. Every call gets the FileLoc of
// the directive's keyword.
class ParserTarget {
  public:
    virtual ~ParserTarget() = default;

    // Transformations.
    virtual void Identity(FileLoc loc) = 0;
    virtual void Translate(Float dx, Float dy, Float dz, FileLoc loc) = 0;
    virtual void Scale(Float sx, Float sy, Float sz, FileLoc loc) = 0;
    virtual void Rotate(Float angle, Float ax, Float ay, Float az, FileLoc loc) = 0;
    virtual void LookAt(Float ex, Float ey, Float ez, Float lx, Float ly, Float lz, Float ux,
                        Float uy, Float uz, FileLoc loc) = 0;
    virtual void Transform(Float m[16], FileLoc loc) = 0;
    virtual void ConcatTransform(Float m[16], FileLoc loc) = 0;
    virtual void CoordinateSystem(const std::string &name, FileLoc loc) = 0;
    virtual void CoordSysTransform(const std::string &name, FileLoc loc) = 0;
    virtual void ActiveTransformAll(FileLoc loc) = 0;
    virtual void ActiveTransformEndTime(FileLoc loc) = 0;
    virtual void ActiveTransformStartTime(FileLoc loc) = 0;
    virtual void TransformTimes(Float start, Float end, FileLoc loc) = 0;

    // Scene-wide options.
    virtual void ColorSpace(const std::string &name, FileLoc loc) = 0;
    // `Option "type name" value`: `name` is the option's name without its type word
    // ("disablepixeljitter"), `value` the value's text without quotes ("true", "4", "foo").
    virtual void Option(const std::string &name, const std::string &value, FileLoc loc) = 0;
    virtual void PixelFilter(const std::string &name, ParsedParameterVector params,
                             FileLoc loc) = 0;
    virtual void Film(const std::string &type, ParsedParameterVector params, FileLoc loc) = 0;
    virtual void Sampler(const std::string &name, ParsedParameterVector params,
                         FileLoc loc) = 0;
    virtual void Accelerator(const std::string &name, ParsedParameterVector params,
                             FileLoc loc) = 0;
    virtual void Integrator(const std::string &name, ParsedParameterVector params,
                            FileLoc loc) = 0;
    virtual void Camera(const std::string &name, ParsedParameterVector params, FileLoc loc) = 0;
    virtual void MakeNamedMedium(const std::string &name, ParsedParameterVector params,
                                 FileLoc loc) = 0;
    virtual void MediumInterface(const std::string &insideName, const std::string &outsideName,
                                 FileLoc loc) = 0;

    // The world.
    virtual void WorldBegin(FileLoc loc) = 0;
    virtual void AttributeBegin(FileLoc loc) = 0;
    virtual void AttributeEnd(FileLoc loc) = 0;
    virtual void Attribute(const std::string &target, ParsedParameterVector params,
                           FileLoc loc) = 0;
    virtual void Texture(const std::string &name, const std::string &type,
                         const std::string &texname, ParsedParameterVector params,
                         FileLoc loc) = 0;
    virtual void Material(const std::string &name, ParsedParameterVector params,
                          FileLoc loc) = 0;
    virtual void MakeNamedMaterial(const std::string &name, ParsedParameterVector params,
                                   FileLoc loc) = 0;
    virtual void NamedMaterial(const std::string &name, FileLoc loc) = 0;
    virtual void LightSource(const std::string &name, ParsedParameterVector params,
                             FileLoc loc) = 0;
    virtual void AreaLightSource(const std::string &name, ParsedParameterVector params,
                                 FileLoc loc) = 0;
    virtual void Shape(const std::string &name, ParsedParameterVector params, FileLoc loc) = 0;
    virtual void ReverseOrientation(FileLoc loc) = 0;
    virtual void ObjectBegin(const std::string &name, FileLoc loc) = 0;
    virtual void ObjectEnd(FileLoc loc) = 0;
    virtual void ObjectInstance(const std::string &name, FileLoc loc) = 0;

    // Called once, after the last directive of the last file.
    virtual void EndOfFiles() = 0;
};

// Parses the files in order as one scene (standard input when `filenames` is empty) and
// calls `target` for each directive, then target->EndOfFiles(). Include and Import name a
// file relative to the directory of the file they are written in (if it is not found there,
// relative to the directory of the first scene file, as pbrt-v4 resolves them). Import is
// parsed like Include. Throws PbrtError ("file:line:col: reason") on malformed input.
void ParseFiles(ParserTarget *target, const std::vector<std::string> &filenames);

// Parses scene text held in memory; `name` is the file name used in error messages, and its
// directory (none for "<string>": the working directory) is where Include looks for files.
void ParseString(ParserTarget *target, const std::string &text,
                 const std::string &name = "<string>");

// A file name written in a parameter (a PLY mesh, an image, a .spd file), made relative to
// the directory of the file it was written in (`loc.filename`). Absolute names and names
// written in a file without a directory are returned unchanged.
std::string ResolveFilename(const std::string &name, const FileLoc &loc);

// ---------------------------------------------------------------------------------------
// The tokenizer, exposed for tests and for tools that want the raw token stream.

struct Token {
    std::string_view text;  // the token as written (quoted strings keep their quotes)
    int line = 0, column = 0;
    bool IsQuoted() const { return !text.empty() && text.front() == '"'; }
    bool IsOpenBracket() const { return text == "["; }
    bool IsCloseBracket() const { return text == "]"; }
};

// Splits scene text into tokens: '[' and ']', quoted strings (with the escapes \" \\ \n \t
// \r \b \f \'), and bare words (directives, numbers, true/false). '#' starts a comment that
// runs to the end of the line. Tokens are views into the text the tokenizer holds.
class Tokenizer {
  public:
    Tokenizer(std::string text, std::string filename);
    // The next token; false at the end of the text. Throws PbrtError on an unterminated
    // string, a newline inside a string or an unknown escape.
    bool Next(Token *token);
    const std::string &Filename() const { return filename; }
    FileLoc Loc(const Token &t) const { return FileLoc{filename, t.line, t.column}; }

  private:
    std::string text, filename;
    size_t pos = 0;
    int line = 1;
    size_t lineStart = 0;
};

// The contents of a quoted token without quotes, escapes replaced.
std::string Dequote(const Token &token);

}  // namespace pbrt
