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
  const auto blends = *fuzz::run_step("vertex_blends", false, [&] { return vertex_blends(input, successor, output); });
  for (const VertexBlend& b : blends) {
    float sum = 0;
    for (size_t k = 0; k < 3; ++k) {
      if (b.vertex[k] >= input.vertex_count()) fuzz::fail("vertex_blends", "a blend names no input vertex");
      if (!(b.weight[k] >= -1e-3f && b.weight[k] <= 1.001f)) fuzz::fail("vertex_blends", "a blend weight is outside [0, 1]");
      sum += b.weight[k];
    }
    if (!(std::fabs(sum - 1.0f) < 1e-3f)) fuzz::fail("vertex_blends", "blend weights do not sum to 1");
  }
}

// The mesh as a soup whose corners carry one normal per triangle (OFF has no normals, so this is how
// a flat-shaded form reaches the harness; the form needs no true face normals, only one per face).
lod::Mesh flat_shaded(const lod::Mesh& mesh) {
  lod::Mesh flat;
  flat.materials = mesh.materials, flat.material_names = mesh.material_names;
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      flat.indices.push_back(uint32_t(flat.positions.size()));
      lod::append_vertex(flat, mesh, mesh.indices[3 * t + k]);
      flat.normals.push_back({float(t % 3 == 0), float(t % 3 == 1), float(t % 3 == 2)});
    }
  return flat;
}

// Through a form (form_test.cpp): the form simplified and restored validates, and the restored
// successors are per input vertex, in range, and blend.
void check_form(const lod::Mesh& input, lod::SimplifyOptions options) {
  using namespace lod;
  const SurfaceForm form = *fuzz::run_step("surface_form", false, [&] { return surface_form(input); });
  if (!form.changed()) return;
  options.keep_vertices = false, options.locked.clear(), options.importance.clear();  // (per input vertex)
  SimplifyResult r = *fuzz::run_step("simplify a form", false, [&] { return simplify(form.mesh, options); });
  fuzz::run_step("restore_form", false, [&] { restore_form(form, r.mesh, r.vertex_successor); return 0; });
  fuzz::run_step("validate the restored result", false, [&] { validate(r.mesh, "restored"); return 0; });
  if (r.vertex_successor.size() != input.vertex_count()) fuzz::fail("restore_form", "vertex_successor has the wrong size");
  for (const uint32_t s : r.vertex_successor)
    if (s != ~0u && s >= r.mesh.vertex_count()) fuzz::fail("restore_form", "a successor is out of range");
  check_blends(input, r.vertex_successor, r.mesh);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace lod;
  if (size < option_bytes) return 0;
  const std::span<const uint8_t> off(data + option_bytes, size - option_bytes);
  const std::optional<Mesh> mesh = fuzz::run_step("off read", true, [&] { return read_off(off, "fuzz.off"); });
  if (!mesh || mesh->triangle_count() > max_triangles) return 0;
  fuzz::check_mesh(*mesh, "off read");
  const SimplifyOptions options = decode_options(std::span<const uint8_t, option_bytes>(data, option_bytes), *mesh);
  const SimplifyResult r = *fuzz::run_step("simplify", false, [&] { return simplify(*mesh, options); });
  fuzz::run_step("validate the result", false, [&] { validate(r.mesh, "simplified"); return 0; });
  if (r.output_triangles != r.mesh.triangle_count() || r.output_triangles > mesh->triangle_count())
    fuzz::fail("simplify", "the reported triangle count does not match the result");
  // Replay describes the mesh before pruning (SimplifyOptions::prune).
  if (!options.prune && fuzz::run_step("replay", false, [&] { return replay(*mesh, r.record, r.record.collapses.size()); }) != r.mesh)
    fuzz::fail("replay", "replaying the record does not give the result");
  if (fuzz::run_step("undo", false, [&] { return replay_and_undo(*mesh, r.record); }) != *mesh)
    fuzz::fail("undo", "undoing the record does not give the input back");
  // Each output vertex continues an input vertex that became it, and is a blend of input vertices.
  if (r.vertex_successor.size() != mesh->vertex_count()) fuzz::fail("simplify", "vertex_successor has the wrong size");
  for (size_t v = 0; v < r.mesh.vertex_count(); ++v)
    if (r.vertex_successor[r.vertex_origin[v]] != v) fuzz::fail("simplify", "an output vertex's origin did not become it");
  check_blends(*mesh, r.vertex_successor, r.mesh);
  // Byte 15: a double-sided form as read, or the mesh flat-shaded first.
  if (data[15] & 1) check_form(data[15] & 2 ? flat_shaded(*mesh) : *mesh, options);
  return 0;
}
