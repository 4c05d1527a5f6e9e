// Internal: the parts of the working mesh that the output and the collapse record need, and the
// one compaction shared by the engine and by replay (so a replay is the engine's output exactly).
#pragma once

#include <span>
#include <vector>

#include "simplify/state.h"

namespace lod::collapse {

AttributeLayout attribute_layout(const Mesh& mesh);
// Normals, UV sets and colour of every vertex, packed per the layout.
std::vector<float> gather_attributes(const Mesh& mesh, const AttributeLayout& layout);

// What changes while collapsing; everything else comes from the input.
struct Snapshot {
  std::span<const uint32_t> position_of;  // per input vertex
  std::span<const float3> position;       // per position id
  std::span<const uint32_t> moves;        // per position id: 0 means it still has its input position
  std::span<const uint32_t> corners;      // 3 per input triangle
  std::span<const uint8_t> alive;         // per input triangle
  const AttributeLayout* layout = nullptr;
  std::span<const float> attributes;      // per input vertex, layout->stride each
};

// Live triangles in input order and the vertices they use, in order of first use.
Mesh compact(const Mesh& input, const Snapshot& snapshot, std::vector<uint32_t>* vertex_origin,
             std::vector<uint32_t>* triangle_origin);
// Every vertex and every live triangle, in input order (after a full undo: the input itself).
Mesh materialize(const Mesh& input, const Snapshot& snapshot);

}  // namespace lod::collapse
