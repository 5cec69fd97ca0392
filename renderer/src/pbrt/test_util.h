// Helpers shared by the renderer's tests: render scene text in memory and summarize the
// image (per-channel XYZ means with their standard errors).
#pragma once

#include <pbrt/render.h>
#include <pbrt/scene.h>
#include <pbrt/util/color.h>
#include <pbrt/util/image.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace pbrt {
namespace testing_util {

inline Image RenderString(const std::string &text, RenderOptions opts = {}, int nThreads = 0) {
    opts.quiet = true;
    std::unique_ptr<Scene> scene = LoadSceneFromString(text, opts, "test.pbrt");
    Render(*scene, nThreads, true);
    return scene->film->GetImage();
}

inline XYZ PixelXYZ(const Image &img, int x, int y) {
    return RGBColorSpace::sRGB->ToXYZ(RGB(img.Get(x, y, 0), img.Get(x, y, 1), img.Get(x, y, 2)));
}

struct Stat {
    double mean = 0, stderror = 0;
};

// Mean over all pixels of XYZ channel c (0..2), and the standard error of that mean
// (meaningful when every pixel has the same expected value).
inline Stat XYZStat(const Image &img, int c) {
    double s = 0, s2 = 0;
    int n = img.width * img.height;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            double v = PixelXYZ(img, x, y)[c];
            s += v;
            s2 += v * v;
        }
    Stat st;
    st.mean = s / n;
    st.stderror = n > 1 ? std::sqrt(std::max(0.0, s2 / n - st.mean * st.mean) / (n - 1)) : 0;
    return st;
}

}  // namespace testing_util
}  // namespace pbrt
