// Bad input that once crashed, hung or silently lost part of the picture: each case must now
// stop scene loading with a PbrtError naming the scene file, line and reason (before any
// rendering), and inputs just inside the limits must still load.
#include <pbrt/accel.h>
#include <pbrt/interaction.h>
#include <pbrt/test_tempdir.h>
#include <pbrt/test_util.h>
#include <pbrt/util/output_path.h>
#include <pbrt/util/ply.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include <sys/stat.h>
#include <unistd.h>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

// The message of the PbrtError that loading `text` throws ("" if it loads); any other
// exception fails the test.
std::string LoadError(const std::string &text, RenderOptions opts = {},
                      const std::string &name = "test.pbrt") {
    opts.quiet = true;
    try {
        LoadSceneFromString(text, opts, name);
    } catch (const PbrtError &e) {
        return e.what();
    } catch (const std::exception &e) {
        ADD_FAILURE() << "not a PbrtError: " << typeid(e).name() << ": " << e.what();
        return e.what();
    }
    return "";
}

#define EXPECT_ERROR_AT(text, where, reason)                                           \
    do {                                                                               \
        std::string msg_ = LoadError(text);                                            \
        EXPECT_NE(msg_.find(where), std::string::npos) << "message: " << msg_;         \
        EXPECT_NE(msg_.find(reason), std::string::npos) << "message: " << msg_;        \
    } while (0)

const char *kWorld = R"(
WorldBegin
LightSource "infinite"
Shape "sphere"
)";

std::string WithOptions(const std::string &options) { return options + kWorld; }

}  // namespace

// --- Resource bounds: refused with the size they would need -------------------------------

TEST(Robustness, HugeFilmIsRefusedWithTheMemoryItNeeds) {
    EXPECT_ERROR_AT(WithOptions("Film \"rgb\" \"integer xresolution\" [ 2000000000 ] \"integer yresolution\" [ 2000000000 ]\n"),
                    "test.pbrt:1:1", "GB of memory");
    // The same message when the film is big only after --resolution.
    RenderOptions opts;
    opts.resolution = {1 << 16, 1 << 16};
    std::string msg = LoadError(WithOptions("Film \"rgb\"\n"), opts);
    double memory = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    if (memory < 189e9) EXPECT_NE(msg.find("65536x65536 film needs 189 GB"), std::string::npos) << msg;
}

TEST(Robustness, ResolutionScaleBeyondIntIsRefused) {
    RenderOptions opts;
    opts.resolutionScale = 1e9f;
    std::string msg = LoadError(WithOptions("Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" [ 32 ]\n"), opts);
    EXPECT_NE(msg.find("test.pbrt:1:1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("64x32 scaled by"), std::string::npos) << msg;
    EXPECT_NE(msg.find("6.4e+10x3.2e+10 pixels"), std::string::npos) << msg;
    // A scale that fits still scales.
    opts.resolutionScale = 0.5f;
    auto scene = LoadSceneFromString(WithOptions("Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" [ 32 ]\n"), opts);
    EXPECT_EQ(scene->film->FullResolution().x, 32);
    EXPECT_EQ(scene->film->FullResolution().y, 16);
}

// --- Camera rays that would overflow: refused before they reach Embree -----------------------

TEST(Robustness, HugeCameraTransformIsRefused) {
    // The camera 1e30 away from the origin, in a Transform entry or a Translate.
    EXPECT_ERROR_AT(WithOptions("Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  1e30 0 0 1 ]\nCamera \"perspective\"\n"),
                    "test.pbrt:2:1", "camera rays");
    EXPECT_ERROR_AT(WithOptions("Translate 1e13 0 0\nCamera \"perspective\"\n"), "test.pbrt:2:1", "beyond +-1e12");
    // A scale of 1e-30 before LookAt: camera-space directions grow by 1e30 and overflow.
    EXPECT_ERROR_AT(WithOptions("Scale 1e-30 1e-30 1e-30\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\n"),
                    "test.pbrt:3:1", "camera rays");
    // An off-diagonal entry of 1e30, and a 1e30 Scale before LookAt: the inverse overflows.
    EXPECT_ERROR_AT(WithOptions("Transform [ 1 1e30 0 0  0 1 0 0  0 0 1 0  0 0 0 1 ]\nCamera \"perspective\"\n"),
                    "test.pbrt:2:1", "camera rays");
    EXPECT_ERROR_AT(WithOptions("Scale 1e30 1e30 1e30\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\n"),
                    "test.pbrt:3:1", "camera rays");
    // Huge but harmless: 1e30 on the diagonal squeezes the world along one camera axis; the
    // rays stay finite and the scene loads.
    EXPECT_EQ(LoadError(WithOptions("Transform [ 1e30 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1 ]\nCamera \"perspective\"\n")), "");
    EXPECT_EQ(LoadError(WithOptions("Translate 1e9 0 0\nCamera \"perspective\"\n")), "");
}

TEST(Robustness, HugeScreenWindowIsRefused) {
    EXPECT_ERROR_AT(WithOptions("Camera \"orthographic\" \"float screenwindow\" [ -1e38 1e38 -1e38 1e38 ]\n"),
                    "test.pbrt:1:1", "screen window");
    EXPECT_ERROR_AT(WithOptions("Camera \"orthographic\" \"float screenwindow\" [ -3e38 3e38 -1 1 ]\n"),
                    "test.pbrt:1:23", "screenwindow\" is too large");
    EXPECT_ERROR_AT(WithOptions("Camera \"orthographic\" \"float screenwindow\" [ -1e20 1e20 -1e20 1e20 ]\n"),
                    "test.pbrt:1:1", "camera rays");
    EXPECT_EQ(LoadError(WithOptions("Camera \"orthographic\" \"float screenwindow\" [ -1e6 1e6 -1e6 1e6 ]\n")), "");
}

TEST(Robustness, HugeFilterRadiusIsRefused) {
    for (const char *f : {"box", "triangle"}) {
        std::string text = std::string("PixelFilter \"") + f +
                           "\" \"float xradius\" [ 1e30 ] \"float yradius\" [ 1e30 ]\n";
        EXPECT_ERROR_AT(WithOptions(text), "test.pbrt:1:1", "too large");
    }
    // A gaussian's integral stays finite, but its samples would land 1e30 pixels away.
    EXPECT_ERROR_AT(WithOptions("PixelFilter \"gaussian\" \"float xradius\" [ 1e30 ]\n"), "test.pbrt:1:1", "pixel filter radius");
    EXPECT_EQ(LoadError(WithOptions("PixelFilter \"box\" \"float xradius\" [ 100 ] \"float yradius\" [ 100 ]\n")), "");
}

TEST(Robustness, NonFiniteRaysNeverReachEmbree) {
    // The last line of defence: a ray Embree would abort on is dropped, whatever made it.
    auto scene = LoadSceneFromString(WithOptions(""), RenderOptions{});
    SurfaceInteraction si;
    const Float inf = Infinity, nan = std::numeric_limits<Float>::quiet_NaN();
    for (Ray r : {Ray(Point3f(nan, 0, 0), Vector3f(0, 0, 1)), Ray(Point3f(0, 0, -5), Vector3f(inf, 0, 1)),
                  Ray(Point3f(1e19f, 0, 0), Vector3f(0, 0, 1)), Ray(Point3f(0, 0, -5), Vector3f(0, 0, 1), nan)}) {
        EXPECT_FALSE(scene->accel->Intersect(r, &si));
        EXPECT_TRUE(scene->accel->Occluded(r));
    }
    // A valid ray still hits the unit sphere.
    EXPECT_TRUE(scene->accel->Intersect(Ray(Point3f(0, 0, -5), Vector3f(0, 0, 1)), &si));
    EXPECT_NEAR(si.tHit, 4, 1e-4);
}

// --- Geometry beyond the ray tracer's range: an error, not a vanished object --------------

TEST(Robustness, GeometryBeyondRangeIsRefused) {
    EXPECT_ERROR_AT("WorldBegin\nAttributeBegin\nScale 1e30 1e30 1e30\nShape \"sphere\"\nAttributeEnd\n",
                    "test.pbrt:4:1", "sphere of radius");
    EXPECT_ERROR_AT("WorldBegin\nShape \"sphere\" \"float radius\" [ 1e20 ]\n", "test.pbrt:2:1", "beyond the +-1e12");
    EXPECT_ERROR_AT("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0  1e20 0 0  0 1e20 0 ]\n",
                    "test.pbrt:2:1", "vertex 1 lies at (1e+20, 0, 0)");
    // Big but traceable geometry loads, and is hit.
    EXPECT_EQ(LoadError("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ -1e11 -1e11 5  1e11 -1e11 5  0 1e11 5 ]\n"), "");
    auto scene = LoadSceneFromString("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ -1e11 -1e11 5  1e11 -1e11 5  0 1e11 5 ]\n",
                                     RenderOptions{});
    SurfaceInteraction si;
    EXPECT_TRUE(scene->accel->Intersect(Ray(Point3f(0, 0, 0), Vector3f(0, 0, 1)), &si));
}

TEST(Robustness, InstancesBeyondRangeAreRefused) {
    // Each shape of the object is within range; the instance's transformation is not.
    const std::string obj = "WorldBegin\nObjectBegin \"ball\"\nShape \"sphere\"\nObjectEnd\n";
    EXPECT_ERROR_AT(obj + "AttributeBegin\nScale 1e30 1e30 1e30\nObjectInstance \"ball\"\nAttributeEnd\n",
                    "test.pbrt:7:1", "ObjectInstance \"ball\": the object reaches");
    EXPECT_ERROR_AT(obj + "Translate 1e13 0 0\nObjectInstance \"ball\"\n", "test.pbrt:6:1", "beyond the +-1e12");
    // A projective transformation (one of the two 0.5 lands in the last row, whichever way
    // the matrix is read): Embree would silently use its affine part.
    EXPECT_ERROR_AT(obj + "ConcatTransform [ 1 0 0 0  0 1 0 0  0 0 1 0.5  0 0 0.5 1 ]\nObjectInstance \"ball\"\n",
                    "test.pbrt:6:1", "projective");
    // Shrunk by 1e-30: the camera's rays would reach 5e30 in the object's space (Embree
    // aborted on them). Shrunk by 1e-6 in a small scene: fine.
    EXPECT_ERROR_AT(obj + "Scale 1e-30 1e-30 1e-30\nObjectInstance \"ball\"\n", "test.pbrt:6:1",
                    "shrinks the object");
    EXPECT_EQ(LoadError("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\n" + obj +
                        "Scale 1e-6 1e-6 1e-6\nObjectInstance \"ball\"\n"),
              "");
    // An empty object has nothing to lose: no error.
    EXPECT_EQ(LoadError("WorldBegin\nObjectBegin \"none\"\nObjectEnd\nScale 1e30 1e30 1e30\n"
                        "ObjectInstance \"none\"\n"),
              "");
    // Big but traceable instances load, and are hit where they are.
    const std::string far = obj + "Translate 0 0 1e11\nObjectInstance \"ball\"\n";
    EXPECT_EQ(LoadError(far), "");
    auto scene = LoadSceneFromString(far, RenderOptions{});
    SurfaceInteraction si;
    ASSERT_TRUE(scene->accel->Intersect(Ray(Point3f(0, 0, 0), Vector3f(0, 0, 1)), &si));
    EXPECT_NEAR(si.tHit, 1e11 - 1, 1e11 * 1e-6);
}

// --- Devices and FIFOs where files are expected: refused before any read (design §5.5) ------

TEST(Robustness, DevicesAndFifosAreRefusedWithoutReading) {
    // A FIFO nobody writes to blocked pbrt for ever; /dev/zero was read until memory ran out.
    TempDir dir;
    for (const char *name : {"fifo.spd", "fifo.pbrt", "fifo.ply"})
        ASSERT_EQ(mkfifo(dir.File(name).c_str(), 0600), 0) << name;
    std::filesystem::create_symlink("/dev/zero", dir.File("zero.spd"));
    std::filesystem::create_symlink("/dev/zero", dir.File("zero.pbrt"));
    std::string name = dir.File("scene.pbrt");
    auto expect = [&](const std::string &text, const std::string &where, const std::string &kind) {
        std::string msg = LoadError(text, {}, name);
        EXPECT_NE(msg.find(name + where), std::string::npos) << msg;
        EXPECT_NE(msg.find("not a regular file (a device, FIFO or socket), not a " + kind + " file"),
                  std::string::npos)
            << msg;
    };
    for (const char *spd : {"fifo.spd", "zero.spd"})
        expect(std::string("WorldBegin\nLightSource \"infinite\" \"spectrum L\" \"") + spd + "\"\n", ":2:24",
               "spectrum");
    for (const char *inc : {"fifo.pbrt", "zero.pbrt"})
        expect(std::string("WorldBegin\nInclude \"") + inc + "\"\n", ":2:1", "scene");
    expect("WorldBegin\nShape \"plymesh\" \"string filename\" \"fifo.ply\"\n", ":2:17", "PLY");
    // The scene itself.
    try {
        LoadScene({dir.File("fifo.pbrt")}, RenderOptions{});
        ADD_FAILURE() << "a FIFO loaded as a scene";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
}

TEST(Robustness, SpectrumFileLargerThan64MiBIsRefused) {
    TempDir dir;
    std::string text = "400 1\n500 1\n";
    while (text.size() <= (size_t(64) << 20)) text += "#" + std::string(1023, 'x') + "\n";
    dir.Write("big.spd", text);
    std::string name = dir.File("scene.pbrt");
    std::string msg = LoadError("WorldBegin\nLightSource \"infinite\" \"spectrum L\" \"big.spd\"\n", {}, name);
    EXPECT_NE(msg.find("big.spd: larger than 64 MiB, not a spectrum file"), std::string::npos) << msg;
}

// --- Directories where files are expected --------------------------------------------------

TEST(Robustness, DirectoriesAreNamedAsSuch) {
    TempDir dir;
    std::filesystem::create_directories(dir.File("d.ply"));
    std::filesystem::create_directories(dir.File("inc.pbrt"));
    std::filesystem::create_directories(dir.File("s.spd"));
    std::string name = dir.File("scene.pbrt");
    auto expect = [&](const std::string &text, const std::string &where, const std::string &reason) {
        std::string msg = LoadError(text, {}, name);
        EXPECT_NE(msg.find(name + where), std::string::npos) << msg;
        EXPECT_NE(msg.find(reason), std::string::npos) << msg;
    };
    expect("WorldBegin\nShape \"plymesh\" \"string filename\" \"d.ply\"\n", ":2:17", "is a directory");
    expect("WorldBegin\nInclude \"inc.pbrt\"\n", ":2:1", "is a directory");
    expect("WorldBegin\nLightSource \"infinite\" \"spectrum L\" \"s.spd\"\n", ":2:24", "is a directory");
    // A directory given as the scene itself.
    try {
        LoadScene({dir.path}, RenderOptions{});
        ADD_FAILURE() << "a directory loaded as a scene";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
    }
}

TEST(Robustness, PlyErrorsNameTheShapeStatement) {
    TempDir dir;
    dir.Write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n0\n1\n2\n");
    std::string name = dir.File("scene.pbrt");
    std::string msg = LoadError("WorldBegin\n\nShape \"plymesh\" \"string filename\" \"bad.ply\"\n", {}, name);
    EXPECT_NE(msg.find(name + ":3:17"), std::string::npos) << msg;
    EXPECT_NE(msg.find("bad.ply\": vertex element lacks"), std::string::npos) << msg;
}

TEST(Robustness, PlyElementWithoutPropertiesAndAHugeCountIsQuick) {
    // It holds no data whatever its count: skipped at once, not counted through.
    TempDir dir;
    std::string path = dir.Write("m.ply",
                                 "ply\nformat ascii 1.0\nelement nothing 1000000000000000000\n"
                                 "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                 "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    auto t0 = std::chrono::steady_clock::now();
    PlyMesh m = ReadPly(path);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
    EXPECT_EQ(m.P.size(), 3u);
    EXPECT_EQ(m.indices.size(), 3u);
    // A count written as a float is malformed, not read as "1".
    std::string bad = dir.Write("f.ply", "ply\nformat ascii 1.0\nelement nothing 1e18\nend_header\n");
    try {
        ReadPly(bad);
        ADD_FAILURE() << "count 1e18 accepted";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("line 3 of the PLY header: bad element line"), std::string::npos)
            << e.what();
    }
}

// --- Output paths: checked before any work ----------------------------------------------------

TEST(Robustness, OutputImagePathIsCheckedUpFront) {
    TempDir dir;
    auto error = [](const std::string &path) -> std::string {
        try {
            CheckOutputImagePath(path);
        } catch (const PbrtError &e) {
            return e.what();
        }
        return "";
    };
    EXPECT_NE(error(dir.File("x.jpg")).find("unsupported output image format \".jpg\""), std::string::npos);
    EXPECT_NE(error(dir.path).find("is a directory"), std::string::npos);
    std::filesystem::create_directories(dir.File("d.exr"));
    EXPECT_NE(error(dir.File("d.exr")).find("is a directory"), std::string::npos);
    EXPECT_NE(error(dir.File("no/such/x.exr")).find("does not exist"), std::string::npos);
    EXPECT_NE(error("").find("empty"), std::string::npos);
    EXPECT_EQ(error(dir.File("x.exr")), "");
    EXPECT_EQ(error(dir.File("x.PNG")), "");
    // The film's own "filename" is checked when loading the scene, at its statement.
    EXPECT_ERROR_AT(WithOptions("Film \"rgb\" \"string filename\" \"out.jpg\"\n"), "test.pbrt:1:12", "unsupported output image format");
    RenderOptions opts;
    opts.outfile = dir.File("x.exr");  // --outfile replaces it
    EXPECT_EQ(LoadError(WithOptions("Film \"rgb\" \"string filename\" \"out.jpg\"\n"), opts), "");
}

// --- The fuzzing seeds and every input that ever crashed a fuzz target ---------------------

namespace {
std::vector<std::filesystem::path> FilesIn(const std::vector<std::string> &dirs) {
    std::vector<std::filesystem::path> files;
    for (const std::string &d : dirs)
        for (const auto &e : std::filesystem::directory_iterator(std::string(PBRT_FUZZ_DIR) + "/" + d))
            if (e.is_regular_file() && e.path().filename() != "README.md") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}
std::string ReadAll(const std::filesystem::path &p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
}  // namespace

TEST(Robustness, SceneSeedsAndRegressionsLoadOrFailCleanly) {
    // As scene_fuzz.cpp runs them: each loads or throws PbrtError, nothing else. The
    // regressions are the table's bad inputs, so each must be refused (with a location),
    // except the point light beyond range, which loads and renders without reaching Embree.
    auto files = FilesIn({"corpus/scene", "regressions/scene"});
    ASSERT_GE(files.size(), 15u);
    for (const auto &f : files) {
        RenderOptions opts;
        std::string msg = LoadError(ReadAll(f), opts, f.string());
        bool regression = f.parent_path().filename() == "scene" &&
                          f.parent_path().parent_path().filename() == "regressions";
        if (!regression) {
            EXPECT_EQ(msg, "") << f;
        } else if (f.filename() == "point-light-1e30.pbrt") {
            EXPECT_EQ(msg, "") << f;
            RenderOptions small;
            small.resolution = {4, 4};
            small.spp = 1;
            Image img = RenderString(ReadAll(f), small);
            EXPECT_EQ(img.width, 4);
        } else {
            EXPECT_NE(msg.find(f.string() + ":"), std::string::npos) << f << ": " << msg;
        }
    }
}

TEST(Robustness, AnEmptyMaterialNameIsANameLikeAnyOther) {
    // NamedMaterial "" once read as "no name" and indexed the materials at -1 (the fuzzer's
    // regressions/scene/named-material-empty-name.pbrt): "" is refused while undefined, and
    // once MakeNamedMaterial defines it, it is that material.
    RenderOptions opts;
    EXPECT_NE(LoadError("WorldBegin\nNamedMaterial \"\"\nShape \"sphere\"\n", opts, "e.pbrt")
                  .find("e.pbrt:2:1: NamedMaterial \"\" is not defined"),
              std::string::npos);
    EXPECT_EQ(LoadError("WorldBegin\nMakeNamedMaterial \"\" \"string type\" \"diffuse\"\n"
                        "NamedMaterial \"\"\nShape \"sphere\"\n",
                        opts, "e.pbrt"),
              "");
}

TEST(Robustness, PlySeedsAndRegressionsReadOrFailCleanly) {
    // The seeds, and the regression kept from a hang (empty-element-*), are meshes; the
    // other regressions (inputs that once crashed) must be refused with a message naming the
    // file. Under the sanitizer build any undefined behaviour on the way fails the run.
    auto files = FilesIn({"corpus/ply", "regressions/ply"});
    ASSERT_GE(files.size(), 5u);
    for (const auto &f : files) {
        const bool mustRead = f.parent_path().parent_path().filename() == "corpus" ||
                              f.filename().string().rfind("empty-element", 0) == 0;
        try {
            // The reader's promises, as renderer/fuzz/ply_fuzz.cpp checks them.
            PlyMesh m = ReadPly(f.string());
            if (!mustRead) ADD_FAILURE() << f << ": an input that once crashed, read as a mesh";
            EXPECT_EQ(PlyMeshBrokenPromise(m), "") << f;
        } catch (const PbrtError &e) {
            if (mustRead) ADD_FAILURE() << f << ": a valid mesh, refused: " << e.what();
            else EXPECT_NE(std::string(e.what()).find(f.string() + "\": "), std::string::npos) << e.what();
        }
    }
}

TEST(Robustness, NonFiniteRadianceWarningNamesTheShapeStatement) {
    // An emitter whose radiance overflows float: the samples that see it become 0 and the
    // warning names the Shape statement the camera rays hit.
    const std::string text = R"(LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" [ 30 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ]
Sampler "independent" "integer pixelsamples" [ 2 ]
WorldBegin
AreaLightSource "diffuse" "rgb L" [ 1e30 1e30 1e30 ] "float scale" [ 1e30 ]

  Shape "sphere" "float radius" [ 1.25 ]
)";
    RenderOptions opts;
    opts.quiet = true;
    std::unique_ptr<pbrt::Scene> scene = LoadSceneFromString(text, opts, "nonfinite.pbrt");
    ::testing::internal::CaptureStderr();
    Render(*scene, 1, true);
    std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("nonfinite.pbrt:8:3: paths whose camera ray first hits this shape returned a "
                       "non-finite radiance value"),
              std::string::npos)
        << err;
    Image img = scene->film->GetImage();
    for (float v : img.pixels) EXPECT_TRUE(std::isfinite(v));
}

TEST(Robustness, HugeFilmIsRefusedBeforeTheWorldIsRead) {
    // The Film statement fails at once: the mesh after WorldBegin is never built (it would
    // fail with its own, later error).
    std::string msg = LoadError("Film \"rgb\" \"integer xresolution\" [ 2000000000 ] \"integer yresolution\" [ 2000000000 ]\n"
                                "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 ]\n");
    EXPECT_NE(msg.find("test.pbrt:1:1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("GB of memory"), std::string::npos) << msg;
}
