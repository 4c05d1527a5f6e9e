// Helpers for the renderer's tests: small meshes built by hand and the sRGB formula.
#pragma once

#include <cmath>
#include <cstdint>

#include "lodkit/mesh.h"

namespace lod::test {

// An axis-aligned rectangle [x0, x1] x [y0, y1] in the plane z, facing +z, in one colour (linear RGB)
// when `color` has a positive alpha.
inline void add_rectangle(Mesh& mesh, float x0, float y0, float x1, float y1, float z, float4 color = {}) {
  const uint32_t base = uint32_t(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}});
  mesh.normals.insert(mesh.normals.end(), 4, float3{0, 0, 1});
  if (color.w > 0) mesh.colors.insert(mesh.colors.end(), 4, color);
  mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

// The IEC 61966-2-1 sRGB encoding of a linear value, as an 8-bit byte.
inline int srgb_byte(double linear) {
  const double c = linear <= 0 ? 0 : linear >= 1 ? 1 : linear;
  return int(std::lround(255 * (c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055)));
}

}  // namespace lod::test
