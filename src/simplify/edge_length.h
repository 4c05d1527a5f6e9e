// Internal: the shortest-edge metric (Houle's SEM): cost is the squared edge length, the result sits
// at the midpoint. Fastest, ignores the surface around the edge, so thin parts go first.
#pragma once

#include <algorithm>

#include "simplify/metric.h"

namespace lod::collapse {

class EdgeLengthMetric {
 public:
  void initialize(State&) {}
  void begin_pass(State&) {}

  Placement place(const State& state, const EdgeQuery& edge) const {
    const vec3d a = state.normalized(edge.kept), b = state.normalized(edge.removed);
    const double importance =
        state.importance.empty() ? 1.0 : std::max(state.importance[edge.kept], state.importance[edge.removed]);
    return {length_squared(b - a) * importance, edge.fixed ? a : (a + b) * 0.5};
  }
  void collapsed(State&, const EdgeQuery&, const vec3d&) {}
  void attributes_at(const State&, uint32_t, const vec3d&, float*) const {}
  bool reads_neighbourhood() const { return false; }
};

}  // namespace lod::collapse
