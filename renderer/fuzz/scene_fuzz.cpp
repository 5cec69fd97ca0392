// libFuzzer target: scene text through the tokenizer, the parser and the scene builder
// (shapes, materials, textures, lights, film, camera, sampler). Every input must either load
// or throw PbrtError; a crash, a sanitizer report, a hang or a leak is a bug. The film is
// forced to 8x8 pixels so that a large "xresolution" costs nothing (the refusal of films that
// cannot fit in memory is tested in robustness_test.cpp).
#include <pbrt/scene.h>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    pbrt::SuppressWarnings(true);
    pbrt::RenderOptions opts;
    opts.quiet = true;
    opts.resolution = {8, 8};
    opts.outfile = "fuzz.exr";  // never written; skips the film's "filename" check
    try {
        pbrt::LoadSceneFromString(std::string(reinterpret_cast<const char *>(data), size), opts,
                                  "fuzz.pbrt");
    } catch (const pbrt::PbrtError &) {
    }
    return 0;
}
