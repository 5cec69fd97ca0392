#include <pbrt/util/paramdict.h>

#include <gtest/gtest.h>

#include <algorithm>

using namespace pbrt;

namespace {

// The parameter list of the one directive in `text` (parsed by the real parser).
class ParamsOf : public ParserTarget {
  public:
    explicit ParamsOf(const std::string &text) { ParseString(this, text, "p.pbrt"); }
    ParsedParameterVector params;

    void Shape(const std::string &, ParsedParameterVector p, FileLoc) override {
        params = std::move(p);
    }
    void Identity(FileLoc) override {}
    void Translate(Float, Float, Float, FileLoc) override {}
    void Scale(Float, Float, Float, FileLoc) override {}
    void Rotate(Float, Float, Float, Float, FileLoc) override {}
    void LookAt(Float, Float, Float, Float, Float, Float, Float, Float, Float, FileLoc) override {}
    void Transform(Float[16], FileLoc) override {}
    void ConcatTransform(Float[16], FileLoc) override {}
    void CoordinateSystem(const std::string &, FileLoc) override {}
    void CoordSysTransform(const std::string &, FileLoc) override {}
    void ActiveTransformAll(FileLoc) override {}
    void ActiveTransformEndTime(FileLoc) override {}
    void ActiveTransformStartTime(FileLoc) override {}
    void TransformTimes(Float, Float, FileLoc) override {}
    void ColorSpace(const std::string &, FileLoc) override {}
    void Option(const std::string &, const std::string &, FileLoc) override {}
    void PixelFilter(const std::string &, ParsedParameterVector, FileLoc) override {}
    void Film(const std::string &, ParsedParameterVector, FileLoc) override {}
    void Sampler(const std::string &, ParsedParameterVector, FileLoc) override {}
    void Accelerator(const std::string &, ParsedParameterVector, FileLoc) override {}
    void Integrator(const std::string &, ParsedParameterVector, FileLoc) override {}
    void Camera(const std::string &, ParsedParameterVector, FileLoc) override {}
    void MakeNamedMedium(const std::string &, ParsedParameterVector, FileLoc) override {}
    void MediumInterface(const std::string &, const std::string &, FileLoc) override {}
    void WorldBegin(FileLoc) override {}
    void AttributeBegin(FileLoc) override {}
    void AttributeEnd(FileLoc) override {}
    void Attribute(const std::string &, ParsedParameterVector, FileLoc) override {}
    void Texture(const std::string &, const std::string &, const std::string &,
                 ParsedParameterVector, FileLoc) override {}
    void Material(const std::string &, ParsedParameterVector, FileLoc) override {}
    void MakeNamedMaterial(const std::string &, ParsedParameterVector, FileLoc) override {}
    void NamedMaterial(const std::string &, FileLoc) override {}
    void LightSource(const std::string &, ParsedParameterVector, FileLoc) override {}
    void AreaLightSource(const std::string &, ParsedParameterVector, FileLoc) override {}
    void ReverseOrientation(FileLoc) override {}
    void ObjectBegin(const std::string &, FileLoc) override {}
    void ObjectEnd(FileLoc) override {}
    void ObjectInstance(const std::string &, FileLoc) override {}
    void EndOfFiles() override {}
};

ParameterDictionary Dict(const std::string &params) {
    return ParameterDictionary(ParamsOf("Shape \"x\" " + params).params);
}

// The message of the PbrtError `f` throws ("" if none).
template <typename F>
std::string ErrorOf(F f) {
    try {
        f();
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

std::vector<std::string> UnusedNames(const ParameterDictionary &d) {
    std::vector<std::string> names;
    for (const ParsedParameter *p : d.Unused()) names.push_back(p->name);
    return names;
}

}  // namespace

TEST(ParameterDictionary, TypedGettersReturnValuesOrDefaults) {
    ParameterDictionary d = Dict(
        R"("float f" 2.5 "integer i" -3 "bool b" false "string s" "hello"
           "point3 from" [ 1 2 3 ] "vector3 dir" [ 0 0 -1 ])");
    EXPECT_EQ(d.GetOneFloat("f", 0), 2.5f);
    EXPECT_EQ(d.GetOneInt("i", 0), -3);
    EXPECT_EQ(d.GetOneBool("b", true), false);
    EXPECT_EQ(d.GetOneString("s", ""), "hello");
    EXPECT_EQ(d.GetOnePoint3("from", {}), (std::array<Float, 3>{1, 2, 3}));
    EXPECT_EQ(d.GetOneVector3("dir", {}), (std::array<Float, 3>{0, 0, -1}));
    // Absent parameters give the default and are not errors.
    EXPECT_EQ(d.GetOneFloat("absent", 7.f), 7.f);
    EXPECT_EQ(d.GetOneInt("absent", 9), 9);
    EXPECT_EQ(d.GetOneBool("absent", true), true);
    EXPECT_EQ(d.GetOneString("absent", "def"), "def");
    EXPECT_EQ(d.GetOnePoint3("absent", {4, 5, 6}), (std::array<Float, 3>{4, 5, 6}));
    EXPECT_TRUE(d.GetFloatArray("absent").empty());
    EXPECT_TRUE(d.GetPoint3Array("absent").empty());
    EXPECT_FALSE(d.GetOneRGB("absent").has_value());
    EXPECT_EQ(d.GetTexture("absent"), "");
    EXPECT_EQ(d.Find("absent"), nullptr);
    EXPECT_EQ(d.Loc("absent").line, 0);
}

TEST(ParameterDictionary, ArraysComeInTuples) {
    ParameterDictionary d = Dict(
        R"("point3 P" [ 0 0 0  1 0 0  0 1 0 ] "normal N" [ 0 0 1 0 0 1 0 0 1 ]
           "point2 uv" [ 0 0 1 0 0 1 ] "integer indices" [ 0 1 2 ] "float w" [ .5 .25 ]
           "string names" [ "a" "b" ] "vector3 v" [ 1 2 3 4 5 6 ])");
    auto P = d.GetPoint3Array("P");
    ASSERT_EQ(P.size(), 3u);
    EXPECT_EQ(P[1], (std::array<Float, 3>{1, 0, 0}));
    auto N = d.GetNormal3Array("N");
    ASSERT_EQ(N.size(), 3u);
    EXPECT_EQ(N[2], (std::array<Float, 3>{0, 0, 1}));
    auto uv = d.GetPoint2Array("uv");
    ASSERT_EQ(uv.size(), 3u);
    EXPECT_EQ(uv[2], (std::array<Float, 2>{0, 1}));
    EXPECT_EQ(d.GetIntArray("indices"), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(d.GetFloatArray("w"), (std::vector<Float>{.5f, .25f}));
    EXPECT_EQ(d.GetStringArray("names"), (std::vector<std::string>{"a", "b"}));
    auto v = d.GetVector3Array("v");
    ASSERT_EQ(v.size(), 2u);
    EXPECT_EQ(v[1], (std::array<Float, 3>{4, 5, 6}));
    EXPECT_TRUE(d.Unused().empty());
}

TEST(ParameterDictionary, TypeMismatchAndWrongCountNameTheParameter) {
    ParameterDictionary d = Dict("\"integer n\" 3\n  \"float radius\" [ 1 2 ]\n"
                                 "  \"point3 P\" [ 1 2 3 4 5 6 ] \"rgb c\" [ 1 1 1 ]");
    // Wrong type: the message names the parameter, both types and where it was written.
    std::string msg = ErrorOf([&] { d.GetOneFloat("n", 0); });
    EXPECT_EQ(msg.rfind("p.pbrt:1:11: ", 0), 0u) << msg;
    EXPECT_NE(msg.find("\"integer n\" has type \"integer\", expected \"float\""),
              std::string::npos) << msg;
    EXPECT_NE(ErrorOf([&] { d.GetPoint2Array("P"); }), "");
    EXPECT_NE(ErrorOf([&] { d.GetNormal3Array("P"); }), "");
    EXPECT_NE(ErrorOf([&] { d.GetOneString("n", ""); }), "");
    EXPECT_NE(ErrorOf([&] { d.GetOneBool("c", false); }), "");
    // Wrong count for a single value.
    msg = ErrorOf([&] { d.GetOneFloat("radius", 0); });
    EXPECT_EQ(msg.rfind("p.pbrt:2:3: ", 0), 0u) << msg;
    EXPECT_NE(msg.find("expects one value, got 2"), std::string::npos) << msg;
    EXPECT_NE(ErrorOf([&] { d.GetOnePoint3("P", {}); }).find("expects 3 values, got 6"),
              std::string::npos);
    // The array getters accept any count.
    EXPECT_EQ(d.GetFloatArray("radius").size(), 2u);
}

TEST(ParameterDictionary, PolymorphicParametersDoNotThrow) {
    ParameterDictionary d = Dict(
        R"("rgb reflectance" [ .1 .2 .3 ] "texture tex" "checks" "spectrum L" [ 400 1 700 2 ]
           "blackbody T" 5000 "float roughness" 0.1)");
    // rgb: value; texture: name; other types: nothing, and the parameter stays unused.
    EXPECT_EQ(d.GetOneRGB("reflectance"), (std::array<Float, 3>{.1f, .2f, .3f}));
    EXPECT_FALSE(d.GetOneRGB("L").has_value());
    EXPECT_EQ(d.GetTexture("roughness"), "");
    EXPECT_EQ(d.GetTexture("tex"), "checks");
    EXPECT_FALSE(d.GetOneRGB("tex").has_value());
    EXPECT_EQ(UnusedNames(d), (std::vector<std::string>{"L", "T", "roughness"}));
    // Raw access for spectra marks them used.
    const ParsedParameter *L = d.Find("L");
    ASSERT_NE(L, nullptr);
    EXPECT_EQ(L->type, "spectrum");
    EXPECT_EQ(L->floats, (std::vector<double>{400, 1, 700, 2}));
    EXPECT_EQ(d.Find("T")->floats, (std::vector<double>{5000}));
    EXPECT_EQ(UnusedNames(d), (std::vector<std::string>{"roughness"}));
    EXPECT_EQ(d.GetOneFloat("roughness", 0), 0.1f);
    EXPECT_TRUE(d.Unused().empty());
}

TEST(ParameterDictionary, FirstOfDuplicateNamesWins) {
    // As when the scene builder appends "Attribute" defaults after a shape's own parameters.
    ParsedParameterVector own = ParamsOf("Shape \"s\" \"float radius\" 2").params;
    ParsedParameterVector defaults =
        ParamsOf("Shape \"s\" \"float radius\" 5 \"float zmax\" 1").params;
    own.insert(own.end(), defaults.begin(), defaults.end());
    ParameterDictionary d(own);
    EXPECT_EQ(d.GetOneFloat("radius", 0), 2.f);
    // The shadowed default counts as used with the one that shadows it.
    EXPECT_EQ(UnusedNames(d), (std::vector<std::string>{"zmax"}));
}

TEST(ParameterDictionary, LocNamesWhereTheParameterWasWritten) {
    ParameterDictionary d = Dict("\n\n   \"float fov\" 45");
    FileLoc loc = d.Loc("fov");
    EXPECT_EQ(loc.filename, "p.pbrt");
    EXPECT_EQ(loc.line, 3);
    EXPECT_EQ(loc.column, 4);
    // Loc does not count as a use.
    EXPECT_EQ(UnusedNames(d), (std::vector<std::string>{"fov"}));
}
