#include <pbrt/parser.h>
#include <pbrt/test_tempdir.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <sstream>

using namespace pbrt;
namespace fs = std::filesystem;

namespace {

std::string Num(Float v) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%g", double(v));
    return buf;
}

std::string Where(const FileLoc &loc) {
    return fs::path(loc.filename).filename().string() + ":" + std::to_string(loc.line) + ":" +
           std::to_string(loc.column);
}

// "type name=v1,v2" for each parameter.
std::string Params(const ParsedParameterVector &params) {
    std::string s;
    for (const ParsedParameter &p : params) {
        s += " [" + p.type + " " + p.name + "=";
        std::string sep;
        for (double f : p.floats) s += sep + Num(Float(f)), sep = ",";
        for (int i : p.ints) s += sep + std::to_string(i), sep = ",";
        for (const std::string &str : p.strings) s += sep + "'" + str + "'", sep = ",";
        for (uint8_t b : p.bools) s += sep + (b ? "true" : "false"), sep = ",";
        s += "]";
    }
    return s;
}

// A ParserTarget that records every call as one line of text, ending in "@file:line:col".
class RecordingTarget : public ParserTarget {
  public:
    std::vector<std::string> calls;
    std::vector<ParsedParameterVector> paramLists;
    int endOfFiles = 0;

    void Add(const std::string &s, const FileLoc &loc) { calls.push_back(s + " @" + Where(loc)); }
    void AddP(const std::string &s, ParsedParameterVector p, const FileLoc &loc) {
        Add(s + Params(p), loc);
        paramLists.push_back(std::move(p));
    }
    static std::string M(const Float m[16]) {
        std::string s;
        for (int i = 0; i < 16; ++i) s += " " + Num(m[i]);
        return s;
    }

    void Identity(FileLoc l) override { Add("Identity", l); }
    void Translate(Float x, Float y, Float z, FileLoc l) override {
        Add("Translate " + Num(x) + " " + Num(y) + " " + Num(z), l);
    }
    void Scale(Float x, Float y, Float z, FileLoc l) override {
        Add("Scale " + Num(x) + " " + Num(y) + " " + Num(z), l);
    }
    void Rotate(Float a, Float x, Float y, Float z, FileLoc l) override {
        Add("Rotate " + Num(a) + " " + Num(x) + " " + Num(y) + " " + Num(z), l);
    }
    void LookAt(Float ex, Float ey, Float ez, Float lx, Float ly, Float lz, Float ux, Float uy,
                Float uz, FileLoc l) override {
        Add("LookAt " + Num(ex) + " " + Num(ey) + " " + Num(ez) + " " + Num(lx) + " " + Num(ly) +
                " " + Num(lz) + " " + Num(ux) + " " + Num(uy) + " " + Num(uz),
            l);
    }
    void Transform(Float m[16], FileLoc l) override { Add("Transform" + M(m), l); }
    void ConcatTransform(Float m[16], FileLoc l) override { Add("ConcatTransform" + M(m), l); }
    void CoordinateSystem(const std::string &n, FileLoc l) override {
        Add("CoordinateSystem " + n, l);
    }
    void CoordSysTransform(const std::string &n, FileLoc l) override {
        Add("CoordSysTransform " + n, l);
    }
    void ActiveTransformAll(FileLoc l) override { Add("ActiveTransformAll", l); }
    void ActiveTransformEndTime(FileLoc l) override { Add("ActiveTransformEndTime", l); }
    void ActiveTransformStartTime(FileLoc l) override { Add("ActiveTransformStartTime", l); }
    void TransformTimes(Float a, Float b, FileLoc l) override {
        Add("TransformTimes " + Num(a) + " " + Num(b), l);
    }
    void ColorSpace(const std::string &n, FileLoc l) override { Add("ColorSpace " + n, l); }
    void Option(const std::string &n, const std::string &v, FileLoc l) override {
        Add("Option " + n + "=" + v, l);
    }
    void PixelFilter(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("PixelFilter " + n, std::move(p), l);
    }
    void Film(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Film " + n, std::move(p), l);
    }
    void Sampler(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Sampler " + n, std::move(p), l);
    }
    void Accelerator(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Accelerator " + n, std::move(p), l);
    }
    void Integrator(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Integrator " + n, std::move(p), l);
    }
    void Camera(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Camera " + n, std::move(p), l);
    }
    void MakeNamedMedium(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("MakeNamedMedium " + n, std::move(p), l);
    }
    void MediumInterface(const std::string &i, const std::string &o, FileLoc l) override {
        Add("MediumInterface " + i + "|" + o, l);
    }
    void WorldBegin(FileLoc l) override { Add("WorldBegin", l); }
    void AttributeBegin(FileLoc l) override { Add("AttributeBegin", l); }
    void AttributeEnd(FileLoc l) override { Add("AttributeEnd", l); }
    void Attribute(const std::string &t, ParsedParameterVector p, FileLoc l) override {
        AddP("Attribute " + t, std::move(p), l);
    }
    void Texture(const std::string &n, const std::string &t, const std::string &c,
                 ParsedParameterVector p, FileLoc l) override {
        AddP("Texture " + n + " " + t + " " + c, std::move(p), l);
    }
    void Material(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Material " + n, std::move(p), l);
    }
    void MakeNamedMaterial(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("MakeNamedMaterial " + n, std::move(p), l);
    }
    void NamedMaterial(const std::string &n, FileLoc l) override { Add("NamedMaterial " + n, l); }
    void LightSource(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("LightSource " + n, std::move(p), l);
    }
    void AreaLightSource(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("AreaLightSource " + n, std::move(p), l);
    }
    void Shape(const std::string &n, ParsedParameterVector p, FileLoc l) override {
        AddP("Shape " + n, std::move(p), l);
    }
    void ReverseOrientation(FileLoc l) override { Add("ReverseOrientation", l); }
    void ObjectBegin(const std::string &n, FileLoc l) override { Add("ObjectBegin " + n, l); }
    void ObjectEnd(FileLoc l) override { Add("ObjectEnd", l); }
    void ObjectInstance(const std::string &n, FileLoc l) override {
        Add("ObjectInstance " + n, l);
    }
    void EndOfFiles() override { ++endOfFiles; }
};

// The message of the PbrtError that parsing `text` throws ("" if none is thrown).
std::string ParseError(const std::string &text, const std::string &name = "bad.pbrt") {
    RecordingTarget t;
    try {
        ParseString(&t, text, name);
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

using pbrt::testing_util::TempDir;

}  // namespace

TEST(Parser, EveryDirectiveDispatchesWithItsArguments) {
    const char *scene = R"(Option "bool disablepixeljitter" true
Option "integer seed" [ 7 ]
ColorSpace "rec2020"
LookAt 0 1 2  3 4 5  6 7 8
Camera "perspective" "float fov" 45
Sampler "halton" "integer pixelsamples" 16
Film "rgb" "string filename" "out.exr"
PixelFilter "gaussian"
Integrator "path" "integer maxdepth" 5
Accelerator "bvh"
Identity
Translate 1 -2 3.5
Scale 2 2 2
Rotate 90 0 0 1
Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1 ]
ConcatTransform 2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1
CoordinateSystem "cam"
CoordSysTransform "cam"
TransformTimes 0 1
ActiveTransform StartTime
ActiveTransform EndTime
ActiveTransform All
MakeNamedMedium "fog" "string type" "homogeneous"
MediumInterface "fog"
MediumInterface "" "fog"
WorldBegin
AttributeBegin
  Attribute "shape" "float radius" 2
  Texture "checks" "spectrum" "checkerboard" "float uscale" 4
  Material "diffuse" "rgb reflectance" [ .5 .5 .5 ]
  MakeNamedMaterial "m" "string type" "conductor"
  NamedMaterial "m"
  LightSource "point" "blackbody I" 3000
  AreaLightSource "diffuse" "spectrum L" [ 400 1 700 2 ]
  ReverseOrientation
  Shape "sphere"
AttributeEnd
ObjectBegin "thing"
  Shape "sphere" "float radius" 1
ObjectEnd
ObjectInstance "thing"
)";
    RecordingTarget t;
    ParseString(&t, scene, "all.pbrt");
    std::vector<std::string> want = {
        "Option disablepixeljitter=true @all.pbrt:1:1",
        "Option seed=7 @all.pbrt:2:1",
        "ColorSpace rec2020 @all.pbrt:3:1",
        "LookAt 0 1 2 3 4 5 6 7 8 @all.pbrt:4:1",
        "Camera perspective [float fov=45] @all.pbrt:5:1",
        "Sampler halton [integer pixelsamples=16] @all.pbrt:6:1",
        "Film rgb [string filename='out.exr'] @all.pbrt:7:1",
        "PixelFilter gaussian @all.pbrt:8:1",
        "Integrator path [integer maxdepth=5] @all.pbrt:9:1",
        "Accelerator bvh @all.pbrt:10:1",
        "Identity @all.pbrt:11:1",
        "Translate 1 -2 3.5 @all.pbrt:12:1",
        "Scale 2 2 2 @all.pbrt:13:1",
        "Rotate 90 0 0 1 @all.pbrt:14:1",
        "Transform 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1 @all.pbrt:15:1",
        "ConcatTransform 2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1 @all.pbrt:16:1",
        "CoordinateSystem cam @all.pbrt:17:1",
        "CoordSysTransform cam @all.pbrt:18:1",
        "TransformTimes 0 1 @all.pbrt:19:1",
        "ActiveTransformStartTime @all.pbrt:20:1",
        "ActiveTransformEndTime @all.pbrt:21:1",
        "ActiveTransformAll @all.pbrt:22:1",
        "MakeNamedMedium fog [string type='homogeneous'] @all.pbrt:23:1",
        "MediumInterface fog|fog @all.pbrt:24:1",
        "MediumInterface |fog @all.pbrt:25:1",
        "WorldBegin @all.pbrt:26:1",
        "AttributeBegin @all.pbrt:27:1",
        "Attribute shape [float radius=2] @all.pbrt:28:3",
        "Texture checks spectrum checkerboard [float uscale=4] @all.pbrt:29:3",
        "Material diffuse [rgb reflectance=0.5,0.5,0.5] @all.pbrt:30:3",
        "MakeNamedMaterial m [string type='conductor'] @all.pbrt:31:3",
        "NamedMaterial m @all.pbrt:32:3",
        "LightSource point [blackbody I=3000] @all.pbrt:33:3",
        "AreaLightSource diffuse [spectrum L=400,1,700,2] @all.pbrt:34:3",
        "ReverseOrientation @all.pbrt:35:3",
        "Shape sphere @all.pbrt:36:3",
        "AttributeEnd @all.pbrt:37:1",
        "ObjectBegin thing @all.pbrt:38:1",
        "Shape sphere [float radius=1] @all.pbrt:39:3",
        "ObjectEnd @all.pbrt:40:1",
        "ObjectInstance thing @all.pbrt:41:1",
    };
    ASSERT_EQ(t.calls.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(t.calls[i], want[i]) << "call " << i;
    EXPECT_EQ(t.endOfFiles, 1);
}

TEST(Parser, EveryParameterTypeAndAlias) {
    const char *scene = R"(Shape "test"
  "float f" [ 1 -2.5 1e3 -.5 +4 2.5E-2 ]
  "integer i" [ 1 -2 300 ]
  "bool b1" true "bool b2" "false" "bool b3" [ false true ]
  "string s" [ "a b" "c" ]
  "point2 p2" [ 1 2 3 4 ]  "vector2 v2" [ 5 6 ]
  "point3 p3" [ 1 2 3 ]  "point p" [ 4 5 6 ]
  "vector3 v3" [ 1 0 0 ] "vector v" [ 0 1 0 ]
  "normal3 n3" [ 0 0 1 ] "normal n" [ 0 0 -1 ]
  "rgb c" [ .1 .2 .3 ] "color c2" [ 1 1 1 ]
  "blackbody bb" 6500
  "spectrum sp" [ 300 .3 800 .8 ]  "spectrum named" "stdillum-D65"  "spectrum file" "lamp.spd"
  "texture tex" "checks"
)";
    RecordingTarget t;
    ParseString(&t, scene);
    ASSERT_EQ(t.calls.size(), 1u);
    EXPECT_EQ(t.calls[0],
              "Shape test [float f=1,-2.5,1000,-0.5,4,0.025] [integer i=1,-2,300] [bool b1=true] "
              "[bool b2=false] [bool b3=false,true] [string s='a b','c'] [point2 p2=1,2,3,4] "
              "[vector2 v2=5,6] [point3 p3=1,2,3] [point3 p=4,5,6] [vector3 v3=1,0,0] "
              "[vector3 v=0,1,0] [normal3 n3=0,0,1] [normal3 n=0,0,-1] [rgb c=0.1,0.2,0.3] "
              "[rgb c2=1,1,1] [blackbody bb=6500] [spectrum sp=300,0.3,800,0.8] "
              "[spectrum named='stdillum-D65'] [spectrum file='lamp.spd'] [texture tex='checks'] "
              "@<string>:1:1");
    // Each parameter knows where its declaration was written.
    const ParsedParameterVector &p = t.paramLists[0];
    EXPECT_EQ(Where(p[0].loc), "<string>:2:3");
    EXPECT_EQ(Where(p[2].loc), "<string>:4:3");
    EXPECT_EQ(Where(p[3].loc), "<string>:4:18");
    // Values are kept to double precision until a getter converts them.
    EXPECT_EQ(p[0].floats[5], 2.5e-2);
}

TEST(Parser, CommentsStringsAndWhitespace) {
    const char *scene =
        "# a comment line\r\n"
        "Shape \"a#b\" # trailing comment \"with quotes\" [ brackets\r\n"
        "  \"string s\" \"say \\\"hi\\\"\\tand\\\\ bye\\n\"#no space before comment\n"
        "\tShape\"x\"\"float r\"[1]WorldBegin";
    RecordingTarget t;
    ParseString(&t, scene);
    ASSERT_EQ(t.calls.size(), 3u);
    EXPECT_EQ(t.calls[0], "Shape a#b [string s='say \"hi\"\tand\\ bye\n'] @<string>:2:1");
    EXPECT_EQ(t.calls[1], "Shape x [float r=1] @<string>:4:2");
    EXPECT_EQ(t.calls[2], "WorldBegin @<string>:4:22");
}

TEST(Parser, TokenizerSplitsAndLocates) {
    Tokenizer tok("Shape\"s\"[1 -2e+3]#c\n  \"q\\\"\" x", "t.pbrt");
    std::vector<std::string> texts;
    std::vector<std::pair<int, int>> locs;
    Token t;
    while (tok.Next(&t)) {
        texts.emplace_back(t.text);
        locs.emplace_back(t.line, t.column);
    }
    std::vector<std::string> want = {"Shape", "\"s\"", "[", "1", "-2e+3", "]", "\"q\\\"\"", "x"};
    EXPECT_EQ(texts, want);
    std::vector<std::pair<int, int>> wantLocs = {{1, 1}, {1, 6}, {1, 9}, {1, 10},
                                                 {1, 12}, {1, 17}, {2, 3}, {2, 9}};
    EXPECT_EQ(locs, wantLocs);
}

TEST(Parser, ByteOrderMarkIsSkipped) {
    RecordingTarget t;
    ParseString(&t, "\xEF\xBB\xBFWorldBegin");
    EXPECT_EQ(t.calls, std::vector<std::string>{"WorldBegin @<string>:1:1"});
}

TEST(Parser, TransformBeginAndWorldEndAreAcceptedForOldScenes) {
    RecordingTarget t;
    ParseString(&t, "TransformBegin Translate 1 2 3 TransformEnd WorldEnd");
    std::vector<std::string> want = {"AttributeBegin @<string>:1:1",
                                     "Translate 1 2 3 @<string>:1:16",
                                     "AttributeEnd @<string>:1:32"};
    EXPECT_EQ(t.calls, want);
}

TEST(Parser, IncludeAndImportAreRelativeToTheIncludingFile) {
    TempDir dir;
    std::string main = dir.Write("scene/main.pbrt", "WorldBegin\nInclude \"parts/a.pbrt\"\n"
                                                    "Import \"parts/b.pbrt\"\nShape \"end\"\n");
    dir.Write("scene/parts/a.pbrt", "# a\nShape \"a\"\nInclude \"deeper/c.pbrt\"\n");
    dir.Write("scene/parts/deeper/c.pbrt", "\n\n  Shape \"c\" \"string filename\" \"c.ply\"\n");
    // b.pbrt names a file relative to the main scene's directory (pbrt-v4's convention).
    dir.Write("scene/parts/b.pbrt", "Include \"other.pbrt\"\n");
    dir.Write("scene/other.pbrt", "Shape \"other\"\n");

    RecordingTarget t;
    ParseFiles(&t, {main});
    std::vector<std::string> want = {
        "WorldBegin @main.pbrt:1:1", "Shape a @a.pbrt:2:1",
        "Shape c [string filename='c.ply'] @c.pbrt:3:3", "Shape other @other.pbrt:1:1",
        "Shape end @main.pbrt:4:1"};
    EXPECT_EQ(t.calls, want);
    EXPECT_EQ(t.endOfFiles, 1);

    // A parameter's file name resolves against the file it was written in.
    const ParsedParameter &fn = t.paramLists[1][0];
    EXPECT_EQ(fs::path(ResolveFilename(fn.strings[0], fn.loc)),
              fs::path(dir.path) / "scene/parts/deeper/c.ply");
}

TEST(Parser, SeveralFilesParseAsOneScene) {
    TempDir dir;
    std::string a = dir.Write("a.pbrt", "AttributeBegin\n");
    std::string b = dir.Write("b.pbrt", "AttributeEnd\n");
    RecordingTarget t;
    ParseFiles(&t, {a, b});
    EXPECT_EQ(t.calls.size(), 2u);
    EXPECT_EQ(t.endOfFiles, 1);
}

TEST(Parser, ResolveFilename) {
    EXPECT_EQ(ResolveFilename("m.ply", FileLoc{"/a/b/scene.pbrt", 1, 1}), "/a/b/m.ply");
    EXPECT_EQ(ResolveFilename("models/m.ply", FileLoc{"rel/scene.pbrt", 1, 1}),
              "rel/models/m.ply");
    EXPECT_EQ(ResolveFilename("/abs/m.ply", FileLoc{"/a/scene.pbrt", 1, 1}), "/abs/m.ply");
    EXPECT_EQ(ResolveFilename("m.ply", FileLoc{"scene.pbrt", 1, 1}), "m.ply");
    EXPECT_EQ(ResolveFilename("m.ply", FileLoc{"<string>", 1, 1}), "m.ply");
    EXPECT_EQ(ResolveFilename("m.ply", FileLoc{"/scene.pbrt", 1, 1}), "/m.ply");
}

// Each class of malformed input gives an error that names file, line and column.
TEST(Parser, MalformedInputNamesFileLineAndColumn) {
    struct Case {
        const char *text;
        const char *where;   // expected "file:line:col" prefix
        const char *reason;  // expected part of the message
    };
    const Case cases[] = {
        {"WorldBegin\n  Foo 1 2", "bad.pbrt:2:3", "unknown directive 'Foo'"},
        {"Shape \"sphere", "bad.pbrt:1:7", "unterminated string"},
        {"Shape \"sph\nere\"", "bad.pbrt:1:7", "unterminated string"},
        {"Shape \"a\\qb\"", "bad.pbrt:1:9", "unknown escape"},
        {"Shape \"s\" \"float r\" [ 1 [ 2 ] ]", "bad.pbrt:1:25", "mismatched brackets"},
        {"Shape \"s\" \"float r\" 1 ]", "bad.pbrt:1:23", "mismatched brackets"},
        {"Shape \"s\" \"float r\" ]", "bad.pbrt:1:21", "mismatched brackets"},
        {"Shape \"s\"\n \"float r\" [ 1 2", "bad.pbrt:2:12", "unterminated '['"},
        {"Shape \"s\" \"float r\"", "bad.pbrt:1:11", "has no values"},
        {"Shape \"s\" \"float r\"\nWorldBegin", "bad.pbrt:1:11", "has no values"},
        {"Shape \"s\" \"float r\" [ ]", "bad.pbrt:1:11", "has no values"},
        {"Shape \"s\" \"floaty r\" 1", "bad.pbrt:1:11", "unknown parameter type \"floaty\""},
        {"Shape \"s\" \"float\" 1", "bad.pbrt:1:11", "not of the form \"type name\""},
        {"Shape \"s\" \"float a b\" 1", "bad.pbrt:1:11", "not of the form \"type name\""},
        {"Shape \"s\" \"float r\" \"one\"", "bad.pbrt:1:21", "expects numbers"},
        {"Shape \"s\" \"float r\" [ 1 two ]", "bad.pbrt:1:25", "expects numbers"},
        {"Shape \"s\" \"integer n\" 1.5", "bad.pbrt:1:23", "expects integers"},
        {"Shape \"s\" \"bool b\" 1", "bad.pbrt:1:20", "true or false"},
        {"Shape \"s\" \"bool b\" \"yes\"", "bad.pbrt:1:20", "true or false"},
        {"Shape \"s\" \"string f\" [ 1 ]", "bad.pbrt:1:24", "quoted string"},
        {"Shape \"s\" \"rgb c\" [ 1 2 ]", "bad.pbrt:1:11", "expects 3 values"},
        {"Shape \"s\" \"point3 P\" [ 1 2 3 4 ]", "bad.pbrt:1:11", "triples"},
        {"Shape \"s\" \"point2 uv\" [ 1 2 3 ]", "bad.pbrt:1:11", "pairs"},
        {"Shape \"s\" \"spectrum L\" [ 400 1 500 ]", "bad.pbrt:1:11", "pairs"},
        {"Shape \"s\" \"spectrum L\" [ 400 \"x\" ]", "bad.pbrt:1:11", "mixes"},
        {"Shape \"s\" \"blackbody L\" [ 3000 1 ]", "bad.pbrt:1:11", "one value"},
        {"Shape \"s\" \"float r\" 1e999", "bad.pbrt:1:21", "expects numbers"},
        {"Shape \"s\" \"float r\" nan", "bad.pbrt:1:21", "expects numbers"},
        {"Shape \"s\" \"float r\" -1e39", "bad.pbrt:1:21", "expects numbers"},
        {"Shape \"s\" \"float r\" -inf", "bad.pbrt:1:21", "expects numbers"},
        {"Translate 1 2", "bad.pbrt:1:1", "unexpected end of file: Translate expects 3 numbers"},
        {"Translate 1 x 3", "bad.pbrt:1:13", "Translate expects a number"},
        {"Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 ]", "bad.pbrt:1:1", "got 15"},
        {"Rotate [ 1 2 3 4", "bad.pbrt:1:1", "unexpected end of file"},
        {"Shape sphere", "bad.pbrt:1:7", "a quoted string"},
        {"Shape", "bad.pbrt:1:1", "unexpected end of file: Shape expects a name"},
        {"Texture \"t\" \"spectrum\"", "bad.pbrt:1:1", "expects a texture class"},
        {"AttributeEnd", "bad.pbrt:1:1", "AttributeEnd without a matching AttributeBegin"},
        {"AttributeBegin\nAttributeEnd\nAttributeEnd", "bad.pbrt:3:1", "without a matching"},
        {"ObjectEnd", "bad.pbrt:1:1", "ObjectEnd without a matching ObjectBegin"},
        {"ObjectBegin \"o\"\nAttributeEnd", "bad.pbrt:2:1", "inside ObjectBegin"},
        {"AttributeBegin ObjectEnd", "bad.pbrt:1:16", "ObjectEnd without"},
        {"ActiveTransform Sometimes", "bad.pbrt:1:17", "All, StartTime or EndTime"},
        {"Attribute \"camera\" \"float x\" 1", "bad.pbrt:1:1", "Attribute target \"camera\""},
        {"Option \"vector v\" 1", "bad.pbrt:1:8", "unknown Option type"},
        {"Option \"integer seed\" 1.5", "bad.pbrt:1:23", "wrong type"},
        {"Option \"bool b\" [ true false ]", "bad.pbrt:1:24", "expects one value"},
        {"WorldBegin 1.5", "bad.pbrt:1:12", "expected a directive, got the number"},
        {"WorldBegin \"Shape\"", "bad.pbrt:1:12", "expected a directive, got the string"},
        {"WorldBegin [ Shape ]", "bad.pbrt:1:12", "mismatched brackets"},
        {"\"Shape\"", "bad.pbrt:1:1", "not a pbrt-v4 scene file"},
        {"# comment\n[ Shape ]", "bad.pbrt:2:1", "not a pbrt-v4 scene file"},
        {"WorldBegin\nInclude \"no-such-file.pbrt\"", "bad.pbrt:2:1", "no-such-file.pbrt"},
        {"Include \"/\"", "bad.pbrt:1:1", "is a directory, not a scene file"},
        {"Include \"x.pbrt.gz\"", "bad.pbrt:1:1", "gzip"},
    };
    for (const Case &c : cases) {
        std::string msg = ParseError(c.text);
        EXPECT_EQ(msg.rfind(std::string(c.where) + ": ", 0), 0u)
            << "input: " << c.text << "\nmessage: " << msg;
        EXPECT_NE(msg.find(c.reason), std::string::npos)
            << "input: " << c.text << "\nmessage: " << msg;
    }
}

TEST(Parser, FilesThatAreNotSceneTextAreNamedNotQuoted) {
    // An Include or Import of a file that is not scene text (a system file) used to repeat
    // its first line in the error: the message names the file and the line, not the content.
    TempDir dir;
    const std::string secret = "root:x:0:0:secret-hash:/root:/bin/bash";
    std::string passwd = dir.Write("passwd", "# a comment line\n" + secret + "\nmore text\n");
    for (const char *directive : {"Include", "Import"}) {
        std::string scene = dir.Write("scene.pbrt", std::string("WorldBegin\n") + directive +
                                                         " \"passwd\"\n");
        RecordingTarget t;
        try {
            ParseFiles(&t, {scene});
            ADD_FAILURE() << directive << ": no error";
        } catch (const PbrtError &e) {
            std::string msg = e.what();
            EXPECT_EQ(msg.rfind(passwd + ":2:1: not a pbrt-v4 scene file", 0), 0u) << msg;
            EXPECT_EQ(msg.find("root"), std::string::npos) << msg;
            EXPECT_EQ(msg.find("secret"), std::string::npos) << msg;
        }
    }
    // The same for a file named on the command line, and for a file of bytes.
    std::string binary = dir.Write("binary", std::string("\x7f" "ELF\x02\x01secret", 11));
    for (const std::string &f : {passwd, binary}) {
        RecordingTarget t;
        try {
            ParseFiles(&t, {f});
            ADD_FAILURE() << f << ": no error";
        } catch (const PbrtError &e) {
            EXPECT_NE(std::string(e.what()).find("not a pbrt-v4 scene file"), std::string::npos) << e.what();
            EXPECT_EQ(std::string(e.what()).find("secret"), std::string::npos) << e.what();
        }
    }
    // Scene text still gets its tokens quoted once it has begun with a directive.
    std::string scene = dir.Write("typo.pbrt", "WorldBegin\nShpae \"sphere\"\n");
    RecordingTarget t;
    try {
        ParseFiles(&t, {scene});
        ADD_FAILURE() << "no error for a misspelt directive";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("unknown directive 'Shpae'"), std::string::npos) << e.what();
    }
}

TEST(Parser, MissingFilesAndIncludeCyclesAreErrors) {
    RecordingTarget t;
    try {
        ParseFiles(&t, {"/nonexistent/dir/scene.pbrt"});
        FAIL() << "no error for a missing scene file";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/scene.pbrt"), std::string::npos)
            << e.what();
    }

    // A file that includes itself stops with an error rather than recursing forever.
    TempDir dir;
    std::string loop = dir.Write("loop.pbrt", "Shape \"s\"\nInclude \"loop.pbrt\"\n");
    try {
        ParseFiles(&t, {loop});
        FAIL() << "no error for an include cycle";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("loop.pbrt:2:1: Include nested"), std::string::npos)
            << e.what();
    }
    // An error inside an included file names that file.
    std::string bad = dir.Write("sub/bad.pbrt", "\n\nShape \"s\" \"float r\" [ 1 \"x\" ]\n");
    std::string main = dir.Write("main.pbrt", "Include \"sub/bad.pbrt\"\n");
    try {
        ParseFiles(&t, {main});
        FAIL() << "no error for a bad included file";
    } catch (const PbrtError &e) {
        EXPECT_EQ(std::string(e.what()).rfind(bad + ":3:25: ", 0), 0u) << e.what();
    }
}

// Damaged scene text (truncated, bytes removed or replaced by syntax characters) must parse or
// throw PbrtError: never crash, hang or throw anything else.
TEST(Parser, DamagedInputNeverCrashes) {
    const std::string good = R"(LookAt 0 0 5 0 0 0 0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" 64 "string filename" "a \"b\".exr"
WorldBegin
AttributeBegin # comment
  Material "diffuse" "rgb reflectance" [ 0.5 0.4 0.3 ] "bool x" true
  Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]
  AreaLightSource "diffuse" "spectrum L" [ 400 1 700 1.5e0 ]
AttributeEnd
ObjectBegin "o" Shape "sphere" ObjectEnd ObjectInstance "o"
)";
    const std::string specials = "\"[]#\n\\ 0-.eTx";
    std::mt19937 rng(12345);
    int parsed = 0, rejected = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::string text = good;
        int edits = 1 + int(rng() % 3);
        for (int e = 0; e < edits && !text.empty(); ++e) {
            size_t at = rng() % text.size();
            switch (rng() % 3) {
            case 0: text.resize(at); break;
            case 1: text.erase(at, 1 + rng() % 8); break;
            default: text[at] = specials[rng() % specials.size()]; break;
            }
        }
        RecordingTarget t;
        try {
            ParseString(&t, text, "damaged.pbrt");
            ++parsed;
        } catch (const PbrtError &e) {
            EXPECT_EQ(std::string(e.what()).rfind("damaged.pbrt:", 0), 0u) << e.what();
            ++rejected;
        }
    }
    // Both outcomes occur, so the damage was neither always harmless nor always fatal.
    EXPECT_GT(parsed, 0);
    EXPECT_GT(rejected, 0);
}

// The evaluation scenes (in /work/shared, outside the repository) parse, every directive of
// the file is dispatched, and every file a parameter names resolves to an existing file.
TEST(Parser, EvaluationScenesParse) {
    const fs::path scenes = fs::path(PBRT_SHARED_DIR) / "scenes";
    if (!fs::is_directory(scenes)) GTEST_SKIP() << scenes << " is not present";
    int count = 0;
    for (const char *name : {"cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase",
                             "glass-of-water"}) {
        fs::path file = scenes / name / "scene-v4.pbrt";
        if (!fs::exists(file)) continue;
        ++count;
        RecordingTarget t;
        ASSERT_NO_THROW(ParseFiles(&t, {file.string()})) << file;
        EXPECT_EQ(t.endOfFiles, 1);

        // Count directives independently: the first word of each uncommented line.
        std::ifstream in(file);
        std::string line;
        std::map<std::string, int> want;
        std::regex directive(R"(^\s*([A-Z][A-Za-z]+)\b)");
        while (std::getline(in, line)) {
            std::smatch m;
            if (std::regex_search(line, m, directive)) ++want[m[1]];
        }
        std::map<std::string, int> got;
        for (const std::string &c : t.calls) ++got[c.substr(0, c.find(' '))];
        EXPECT_EQ(got, want) << file;
        EXPECT_EQ(got["WorldBegin"], 1) << file;

        for (const ParsedParameterVector &params : t.paramLists) {
            for (const ParsedParameter &p : params) {
                fs::path ext = fs::path(p.strings.empty() ? "" : p.strings[0]).extension();
                if (p.type == "string" && p.name == "filename" &&
                    (ext == ".ply" || ext == ".tga")) {
                    EXPECT_TRUE(fs::exists(ResolveFilename(p.strings[0], p.loc)))
                        << p.loc.ToString() << ": " << p.strings[0];
                }
            }
        }
    }
    EXPECT_GT(count, 0);
}
