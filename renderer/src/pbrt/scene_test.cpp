// Scene building: instancing, textures, named materials, "interface" surfaces, coordinate
// systems and the reporting of unsupported input.
#include <pbrt/scene.h>

#include <pbrt/test_util.h>

#include <gtest/gtest.h>

#include <filesystem>

#include <unistd.h>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

const char *kHeader = R"(
LookAt 0 3 4  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [24] "integer yresolution" [24]
Sampler "sobol" "integer pixelsamples" [64]
Integrator "path" "integer maxdepth" [3]
WorldBegin
LightSource "infinite" "float scale" [1]
AttributeBegin
  AreaLightSource "diffuse" "float scale" [5]
  Shape "trianglemesh" "point3 P" [-0.5 2 -0.5  0.5 2 -0.5  0.5 2 0.5  -0.5 2 0.5] "integer indices" [0 1 2 0 2 3]
AttributeEnd
Material "diffuse" "rgb reflectance" [0.6 0.5 0.4]
Shape "trianglemesh" "point3 P" [-3 0 -3  3 0 -3  3 0 3  -3 0 3] "integer indices" [0 1 2 0 2 3]
)";

double MeanY(const Image &img) { return XYZStat(img, 1).mean; }

}  // namespace

TEST(Scene, ObjectInstancesMatchPlainShapes) {
    const char *box = R"(Shape "trianglemesh" "point3 P" [0 0 0  0.5 0 0  0.5 0.8 0  0 0.8 0] "integer indices" [0 1 2 0 2 3])";
    std::string instanced = std::string(kHeader) + "ObjectBegin \"panel\"\n" + box +
                            "\nObjectEnd\nAttributeBegin Translate -1 0 0 Rotate 30 0 1 0 ObjectInstance \"panel\" AttributeEnd\n"
                            "AttributeBegin Translate 0.5 0 0.5 ObjectInstance \"panel\" AttributeEnd\n";
    std::string plain = std::string(kHeader) + "AttributeBegin Translate -1 0 0 Rotate 30 0 1 0\n" + box +
                        "\nAttributeEnd\nAttributeBegin Translate 0.5 0 0.5\n" + box + "\nAttributeEnd\n";
    std::string none = std::string(kHeader);
    double a = MeanY(RenderString(instanced)), b = MeanY(RenderString(plain)), c = MeanY(RenderString(none));
    EXPECT_LT(std::abs(a - b), 0.005 * b) << "instanced " << a << " plain " << b;
    EXPECT_GT(std::abs(b - c), 0.02 * c) << "the panels must change the picture";
}

TEST(Scene, CheckerboardTexture) {
    // Top view of a floor under a constant sky (E = pi L): radiance = reflectance * L.
    std::string scene = R"(
LookAt 0 0 1  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-1 1 -1 1]
Film "rgb" "integer xresolution" [8] "integer yresolution" [8]
Sampler "independent" "integer pixelsamples" [64]
PixelFilter "box"
Integrator "path" "integer maxdepth" [1]
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1]
Texture "checks" "spectrum" "checkerboard" "float uscale" [2] "float vscale" [2]
    "spectrum tex1" [300 0.2 900 0.2] "spectrum tex2" [300 0.8 900 0.8]
MakeNamedMaterial "floor" "string type" "diffuse" "texture reflectance" "checks"
NamedMaterial "floor"
Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]
    "point2 uv" [0 0 1 0 1 1 0 1]
)";
    Image img = RenderString(scene);
    // pbrt's LookAt down -z with +y up puts world -x on the image's right (camera +x =
    // Cross(up, dir)). Pixel (1, 6) sees world (0.625, -0.625): uv = (0.81, 0.19), st =
    // (1.6, 0.4), floor(s) + floor(t) = 1: tex2. Raster row 0 is the top (world y = +1).
    auto Y = [&](int x, int y) { return PixelXYZ(img, x, y).Y; };
    EXPECT_NEAR(Y(1, 6), 0.8, 0.03) << "world (+x, -y)";
    EXPECT_NEAR(Y(6, 6), 0.2, 0.01) << "world (-x, -y)";
    EXPECT_NEAR(Y(1, 1), 0.2, 0.01) << "world (+x, +y)";
    EXPECT_NEAR(Y(6, 1), 0.8, 0.03) << "world (-x, +y)";
}

TEST(Scene, ImageMapTexture) {
    // A 4 x 4 linear EXR of four constant 2 x 2 blocks on the floor of the checkerboard test.
    auto dir = std::filesystem::temp_directory_path() / ("pbrt_scene_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::string path = (dir / "blocks.exr").string();
    Image tex;
    tex.width = tex.height = 4;
    tex.channels = 3;
    tex.pixels.resize(48);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            float v = y < 2 ? (x < 2 ? 0.2f : 0.8f) : (x < 2 ? 0.5f : 0.1f);  // rows from the top
            for (int c = 0; c < 3; ++c) tex.pixels[(y * 4 + x) * 3 + c] = v;
        }
    WriteImage(path, tex);
    std::string scene = R"(
LookAt 0 0 1  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-1 1 -1 1]
Film "rgb" "integer xresolution" [8] "integer yresolution" [8]
Sampler "independent" "integer pixelsamples" [64]
PixelFilter "box"
Integrator "path" "integer maxdepth" [1]
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1]
Texture "blocks" "spectrum" "imagemap" "string filename" ")" + path + R"(" "string wrap" "clamp"
Material "diffuse" "texture reflectance" "blocks"
Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]
    "point2 uv" [0 0 1 0 1 1 0 1]
)";
    Image img = RenderString(scene);
    std::filesystem::remove_all(dir);
    // v = 0 is the image's bottom row; world -x is on the image's right (see above).
    auto Y = [&](int x, int y) { return PixelXYZ(img, x, y).Y; };
    EXPECT_NEAR(Y(1, 6), 0.1, 0.005) << "uv (0.81, 0.19): bottom-right block";
    EXPECT_NEAR(Y(6, 6), 0.5, 0.02) << "uv (0.19, 0.19): bottom-left block";
    EXPECT_NEAR(Y(1, 1), 0.8, 0.03) << "uv (0.81, 0.81): top-right block";
    EXPECT_NEAR(Y(6, 1), 0.2, 0.01) << "uv (0.19, 0.81): top-left block";
}

TEST(Scene, InterfaceSurfacesAreInvisible) {
    std::string base = std::string(kHeader);
    std::string withInterface = base + R"(AttributeBegin Material "interface" Translate 0 0.5 0
                                          Shape "sphere" "float radius" [0.7] AttributeEnd)";
    double a = MeanY(RenderString(base)), b = MeanY(RenderString(withInterface));
    EXPECT_LT(std::abs(a - b), 0.005 * a) << "an interface sphere must not change the picture: " << a << " vs " << b;
}

TEST(Scene, CoordSysTransformAndAttributes) {
    // A point light placed at the camera through CoordSysTransform "camera" lights the
    // floor like one placed at the camera position directly.
    std::string viaCamera = std::string(kHeader) +
                            R"(AttributeBegin CoordSysTransform "camera" LightSource "point" "float scale" [9] AttributeEnd)";
    std::string direct = std::string(kHeader) + R"(LightSource "point" "float scale" [9] "point3 from" [0 3 4])";
    double a = MeanY(RenderString(viaCamera)), b = MeanY(RenderString(direct));
    EXPECT_LT(std::abs(a - b), 0.002 * b) << a << " vs " << b;
    // Attribute "shape" supplies parameters to later shapes in the block.
    std::string attr = std::string(kHeader) +
                       R"(AttributeBegin Attribute "shape" "float radius" [0.4] Translate 0 0.4 0 Shape "sphere" AttributeEnd)";
    std::string explicitRadius = std::string(kHeader) +
                                 R"(AttributeBegin Translate 0 0.4 0 Shape "sphere" "float radius" [0.4] AttributeEnd)";
    EXPECT_EQ(RenderString(attr).pixels, RenderString(explicitRadius).pixels);
}

TEST(Scene, BilinearMeshIsTwoTriangles) {
    // Corners (0,0), (1,0), (0,1), (1,1) of a planar patch; the same two triangles inline.
    std::string blp = std::string(kHeader) +
                      R"(Shape "bilinearmesh" "point3 P" [-1 0.01 -1  1 0.01 -1  -1 1 -1  1 1 -1])";
    std::string tri = std::string(kHeader) +
                      R"(Shape "trianglemesh" "point3 P" [-1 0.01 -1  1 0.01 -1  -1 1 -1  1 1 -1]
                         "integer indices" [0 1 3 0 3 2] "point2 uv" [0 0 1 0 0 1 1 1])";
    EXPECT_EQ(RenderString(blp).pixels, RenderString(tri).pixels);
}

TEST(Scene, UnsupportedInputIsReported) {
    auto error = [](const std::string &text) -> std::string {
        try {
            RenderString(text);
        } catch (const PbrtError &e) {
            return e.what();
        }
        return "";
    };
    EXPECT_NE(error("WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"no-such.png\"\n").find("test.pbrt:2"),
              std::string::npos);
    EXPECT_NE(error("WorldBegin\nTexture \"t\" \"float\" \"fbm\"\n").find("fbm"), std::string::npos);
    EXPECT_NE(error("WorldBegin\nMaterial \"diffuse\" \"texture reflectance\" \"missing\"\n").find("missing"),
              std::string::npos);
    EXPECT_NE(error("WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n").find("media"),
              std::string::npos);
    EXPECT_NE(error("WorldBegin\nShape \"sphere\" \"float radius\" [1] \"float bogus\" [2]\n").find("bogus"),
              std::string::npos);
    EXPECT_NE(error("Film \"rgb\" \"string sensor\" \"canon_eos_5d\"\nWorldBegin\n").find("sensor"), std::string::npos);
    EXPECT_NE(error("WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [1.5 0 0]\n").find("> 1"), std::string::npos);
    EXPECT_NE(error("WorldBegin\nObjectInstance \"nothing\"\n").find("nothing"), std::string::npos);
    // Integrators other than "path" render with one warning, not an error.
    EXPECT_EQ(error("Integrator \"bdpt\" \"integer maxdepth\" [3]\n"
                    "Film \"rgb\" \"integer xresolution\" [4] \"integer yresolution\" [4]\nWorldBegin\n"),
              "");
}
