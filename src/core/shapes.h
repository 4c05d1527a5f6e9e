// Procedural test meshes: every unit test can build its input without downloaded data.
// All shapes are counter-clockwise seen from outside; each says which streams it carries.
#pragma once

#include <cstdint>

#include "lodkit/mesh.h"

namespace lod::shapes {

// Unit-radius icosphere: the icosahedron with `subdivisions` 1->4 splits, vertices pushed to the
// sphere. 10 * 4^n + 2 vertices and 20 * 4^n triangles; closed, genus 0. Normals; no uvs (no seam).
Mesh icosphere(uint32_t subdivisions);

// Torus around +z with major radius R and minor radius r; `segments` x `sides` quads split in two.
// Closed, genus 1. UVs are continuous: the seam rows are duplicated vertices (same positions).
Mesh torus(float major_radius = 1.0f, float minor_radius = 0.25f, uint32_t segments = 32, uint32_t sides = 16);

// Flat grid in the z = 0 plane over [0, 1]^2 with nx x ny cells; one boundary loop, disk topology.
Mesh grid(uint32_t nx, uint32_t ny);

// Axis-aligned cube [-1, 1]^3 with hard edges: 24 vertices (4 per face, own normal and uvs),
// 8 unique positions, 12 triangles.
Mesh cube();

// Closed cylinder of radius 1 from z = -h/2 to z = h/2 with flat caps; side vertices are split
// from cap vertices (hard edge) and along the uv seam.
Mesh cylinder(uint32_t segments = 16, float height = 2.0f);

// A non-manifold "fin": three triangles sharing one edge (0,0,0)-(0,0,1). 5 positions, no other stream.
Mesh fin();

}  // namespace lod::shapes
