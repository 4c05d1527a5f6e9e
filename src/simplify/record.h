// Internal: the parts of the working mesh that the output and the collapse record need, and the
// one compaction shared by the engine and by replay (so a replay is the engine's output exactly).
#pragma once

#include <algorithm>
#include <iterator>
#include <span>
#include <vector>

#include "simplify/state.h"

namespace lod::collapse {

AttributeLayout attribute_layout(const Mesh& mesh);

// Influences without any weight stand for "the wedges' own" (InfluenceChange::old_value, replay).
inline bool has_weight(const Influences& w) {
  return std::any_of(std::begin(w.weight), std::end(w.weight), [](float x) { return x != 0; });
}
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
  // Per position id, the influences a record chose (SimplifyRecord::influences); empty, or an entry
  // without weight: the wedges' own.
  std::span<const Influences> influences = {};
};

// Live triangles in input order and the vertices they use, in order of first use.
Mesh compact(const Mesh& input, const Snapshot& snapshot, std::vector<uint32_t>* vertex_origin,
             std::vector<uint32_t>* triangle_origin);
// Every vertex and every live triangle, in input order (after a full undo: the input itself).
Mesh materialize(const Mesh& input, const Snapshot& snapshot);

// A collapse record played forwards (apply) or backwards (undo) on the input mesh: what Snapshot
// views. Replay, undo and progressive meshes all run on this.
class Replay {
 public:
  explicit Replay(const Mesh& mesh);
  Snapshot snapshot() const { return {position_of, position, moves, corners, alive, &layout, attributes, influences}; }
  // Collapse i of the record. valid: false if any of its indices is out of range for this mesh (a
  // record of another mesh, or corrupt data), so that applying or undoing it would write out of
  // bounds; check throws usage instead.
  bool valid(const SimplifyRecord& record, size_t i) const;
  void check(const SimplifyRecord& record, size_t i) const;
  void apply(const SimplifyRecord& record, size_t i);
  // Applies collapse i only if it fits the current state exactly (its faces alive, each relink
  // starting from the corner's current wedge, moved wedges on `removed`, old position, values and
  // influences current), so that undo restores this state bit for bit; false (state unspecified)
  // otherwise.
  bool apply_consistent(const SimplifyRecord& record, size_t i);
  void undo(const SimplifyRecord& record, size_t i);
  // The final fit's moves (after the last collapse), forwards or taken back.
  void fit(const SimplifyRecord& record, bool forwards);

 private:
  void set_values(const SimplifyRecord& record, const Collapse& c, const std::vector<float>& values);
  void set_influences(const Collapse& c, const Influences& value);

  std::vector<uint32_t> position_of, moves, corners;
  std::vector<float3> position;
  std::vector<uint8_t> alive;
  AttributeLayout layout;
  std::vector<float> attributes;
  std::vector<Influences> influences;  // per position id, once a record with influences played
  bool skinned = false;                // the mesh has joints and weights
};

}  // namespace lod::collapse
