// Internal: the small interface every cost metric implements for the engine (static dispatch).
//
//   void initialize(State&)      once, after the first topology build
//   void begin_pass(State&)      after each topology rebuild (memoryless metrics rebuild here)
//   Placement place(const State&, const EdgeQuery&) const     cost and position of one collapse
//   void collapsed(State&, const EdgeQuery&, const vec3d& position)   merge per-vertex data
//   void attributes_at(const State&, uint32_t wedge, const vec3d& position, float* out) const
//       optimal values of the optimised attribute channels (metrics without attributes: none)
//   bool reads_neighbourhood() const
//       true if an edge's cost depends on more than its two ends' data (memoryless quadrics are
//       rebuilt from the faces around them): a collapse then changes the costs two rings away
//
// Costs are mean squared distances in the normalised frame (largest extent ~1), so a cost's square
// root divided by State::scale is an object-space distance.
#pragma once

#include <span>

#include "simplify/state.h"

namespace lod::collapse {

struct EdgeQuery {
  uint32_t kept = 0, removed = 0;  // positions
  bool fixed = false;              // the result must stay at `kept` (subset placement or a lock)
  std::span<const WedgePair> wedges;        // removed's wedges -> kept's wedges
  std::span<const uint32_t> kept_wedges;    // every wedge of kept
  std::span<const uint32_t> removed_faces;  // triangles holding both
  bool on_edge = false;                     // the result must lie on the edge (a border along itself)
};

struct Placement {
  double cost = 0;
  vec3d position;
};

// Optimised attribute channels: a float range of the wedge attributes and its weight.
struct Channel {
  uint32_t offset = 0, size = 0;
  float weight = 0;
  enum Kind : uint8_t { normal, uv, color } kind = normal;
};

}  // namespace lod::collapse
