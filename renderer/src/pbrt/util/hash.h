// SHA-256 of a byte string, for provenance: the renderer records the hash of the wavelength
// table it read in the image it writes, so an image can be matched to its table with
// `sha256sum TABLE`.
//
// Written here because none of the renderer's dependencies (Embree, TBB, OpenEXR, stb)
// offers a hash of file contents, and one function does not warrant a crypto library.
// The algorithm is FIPS 180-4's (NIST, "Secure Hash Standard", 2015, section 6.2).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace pbrt {

std::array<uint8_t, 32> SHA256(std::string_view bytes);
// The digest as 64 lower-case hexadecimal digits (as sha256sum prints it).
std::string SHA256Hex(std::string_view bytes);

}  // namespace pbrt
