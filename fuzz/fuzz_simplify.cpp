// libFuzzer harness for the simplifier on whatever mesh an input describes. The first 16 bytes pick
// the options (metric, target, flip limit, locks, aggregation, attribute weights, ...), the rest is
// an OFF file (OFF can carry colours, so seams and colour weights get exercised too). The OFF reader
// may refuse the rest; a mesh it accepts must simplify without any exception, to a mesh that
// validates, with a record that replays to that mesh and undoes to the input
// (tests/simplify/simplify_robustness_test.cpp checks the same on generated meshes), and whose
// vertex_successor and vertex_blends describe it; and likewise through lod::surface_form and
// lod::restore_form (double-sided inputs as read, or the mesh flat-shaded first).
#include <cmath>

#include "fuzz_common.h"
#include "lodkit/simplify.h"

namespace {

constexpr size_t option_bytes = 16;
constexpr size_t max_triangles = 4096;  // keeps each run quick

lod::SimplifyOptions decode_options(std::span<const uint8_t, option_bytes> b, const lod::Mesh& mesh) {
  lod::SimplifyOptions o;
  o.metric = lod::Metric(b[0] % 5);
  o.target_ratio = float(b[1]) / 255.0f;
  o.keep_vertices = b[2] & 1;
  o.lock_border = b[2] & 2;
  o.prune = b[2] & 4;
  if (b[2] & 8) o.max_relative_error = float(b[3]) / 2550.0f;
  o.min_normal_dot = float(b[4]) / 127.5f - 1.0f;
  o.max_aspect_ratio = (b[5] & 0x80) ? float(b[5] & 0x7f) : 0.0f;
  o.distance_guard = float(b[6] % 16);
  o.fit_iterations = b[7] % 4;
  o.fit_flips = !(b[14] & 1);
  o.normal_weight = float(b[8] % 8) / 4.0f;
  o.uv_weight = float((b[8] >> 3) % 8) / 4.0f;
  o.color_weight = float(b[9] % 8) / 4.0f;
  if (b[10] && mesh.vertex_count() > 0) {  // a fraction of the bounding box's size
    lod::float3 lo, hi;
    lod::bounding_box(mesh, lo, hi);
    const float tau = (hi.x - lo.x + hi.y - lo.y + hi.z - lo.z) * float(b[10]) / 1020.0f;
    o.aggregate_distance = std::isfinite(tau) ? tau : 0.0f;  // extents near FLT_MAX overflow
    o.aggregate_neighbours = 1 + b[11] % 8;
  }
  if (b[12]) {  // every k-th vertex locked
    o.locked.resize(mesh.vertex_count());
    for (size_t v = 0; v < o.locked.size(); v += b[12]) o.locked[v] = 1;
  }
  if (b[13]) {
    o.importance.resize(mesh.vertex_count());
    for (size_t v = 0; v < o.importance.size(); ++v) o.importance[v] = float((v * b[13]) % 7);
  }
  o.threads = 1;
  return o;
}

// Blends of `output`'s vertices on `input` (vertex_blends) name input vertices, with weights in
// [0, 1] that sum to 1.
void check_blends(const lod::Mesh& input, const std::vector<uint32_t>& successor, const lod::Mesh& output) {
  using namespace lod;
  check_blends(*mesh, r.vertex_successor, r.mesh);
  // Byte 15: a double-sided form as read, or the mesh flat-shaded first.
  if (data[15] & 1) check_form(data[15] & 2 ? flat_shaded(*mesh) : *mesh, options);
  return 0;
}
