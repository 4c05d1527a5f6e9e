// Internal: the nodes' world matrices at rest, shared by flatten (scene.cpp) and the glTF writer's
// animation key tolerances (gltf.cpp).
#pragma once

#include <array>
#include <vector>

#include "lodkit/io.h"

namespace lod::io {

using Matrix = std::array<double, 16>;  // column-major, like glTF

Matrix multiply(const Matrix& a, const Matrix& b);  // a * b

// Every node's world matrix in the nodes' own transforms (the pose the file was saved in), through
// Node::parent; a node on a malformed parent cycle counts as a root.
std::vector<Matrix> rest_world_matrices(const Scene& scene);

}  // namespace lod::io
