// Bump mapping (pbrt-v4's "displacement" material parameter; Blinn 1978, as in the pbrt
// book, 4th ed., section 10.5.1): the surface is displaced along its shading normal by a
// float texture d(u, v), and the shading frame becomes that of the displaced surface,
//   dp'/du = dp/du + (d(u + du, v) - d(u, v)) / du * n,   likewise for v,
//   n'     = normalize(dp'/du x dp'/dv), on the side of the geometric normal.
// The term d * dn/du of the book is left out: this renderer keeps no normal derivatives
// (it vanishes for flat triangles; on spheres it scales both tangents alike and so does not
// turn the normal).
//
// Finite differences: pbrt-v4 takes du = (|du/dx| + |du/dy|) / 2 from ray differentials
// and falls back to du = 0.0005 without them. This renderer traces no ray differentials,
// so it always uses the fallback (kBumpDelta), which pbrt-v4 also uses for secondary rays
// that lack differentials.
#pragma once

#include <pbrt/interaction.h>
#include <pbrt/textures.h>

namespace pbrt {

// pbrt-v4's fallback finite-difference step in (u, v) (BumpMap in its materials.h).
constexpr Float kBumpDelta = 0.0005f;

struct BumpedFrame {
    Normal3f ns;    // bumped shading normal
    Vector3f dpdu;  // bumped tangent along u (the BSDF frame's x before orthogonalization)
};

// The shading frame at si after displacement by the texture.
BumpedFrame BumpMap(const FloatTexture &displacement, const SurfaceInteraction &si);

}  // namespace pbrt
