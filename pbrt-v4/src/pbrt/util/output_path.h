// Checking where an image will be written, before any long work (parsing big meshes,
// rendering) starts: a bad output path must fail in the first second, not after the render.
#pragma once

#include <string>

namespace pbrt {

// Throws PbrtError ("\"PATH\": reason") unless an image can be written at `path`: its
// extension is one WriteImage writes (.exr or .png, any case), it is not a directory, and
// its directory exists and is writable.
void CheckOutputImagePath(const std::string &path);

// The same for any other output file (pbrt --emission-spectrum, --material-reflectances):
// not a directory, in a directory that exists and is writable.
void CheckOutputFilePath(const std::string &path);

}  // namespace pbrt
