// Output compaction, and replay / undo of a collapse record.
#include "simplify/record.h"

#include <algorithm>

#include "lodkit/error.h"

namespace lod {
namespace collapse {

AttributeLayout attribute_layout(const Mesh& mesh) {
  AttributeLayout layout;
  if (!mesh.normals.empty()) layout.normal = int(layout.stride), layout.stride += 3;
  layout.uv_sets = uint32_t(mesh.uv_set_count());
  for (uint32_t k = 0; k < layout.uv_sets; ++k) layout.uv[k] = int(layout.stride), layout.stride += 2;
  if (!mesh.colors.empty()) layout.color = int(layout.stride), layout.stride += 4;
  return layout;
}

std::vector<float> gather_attributes(const Mesh& mesh, const AttributeLayout& layout) {
  std::vector<float> values(mesh.vertex_count() * layout.stride);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    float* out = values.data() + v * layout.stride;
    if (layout.normal >= 0) {
      const float3& n = mesh.normals[v];
      out[layout.normal] = n.x, out[layout.normal + 1] = n.y, out[layout.normal + 2] = n.z;
    }
    for (uint32_t k = 0; k < layout.uv_sets; ++k) {
      const float2& t = mesh.uvs[k][v];
      out[layout.uv[k]] = t.x, out[layout.uv[k] + 1] = t.y;
    }
    if (layout.color >= 0) {
      const float4& c = mesh.colors[v];
      out[layout.color] = c.x, out[layout.color + 1] = c.y, out[layout.color + 2] = c.z, out[layout.color + 3] = c.w;
    }
  }
  return values;
}

namespace {

// Appends input vertex v with its current position and attributes.
void append_current(Mesh& out, const Mesh& input, const Snapshot& s, uint32_t v) {
  append_vertex(out, input, v);
  const uint32_t p = s.position_of[v];
  if (s.moves[p]) out.positions.back() = s.position[p];
  if (!s.influences.empty() && has_weight(s.influences[p])) {
    const Influences& w = s.influences[p];
    out.joints.back() = {w.joint[0], w.joint[1], w.joint[2], w.joint[3]};
    out.weights.back() = {w.weight[0], w.weight[1], w.weight[2], w.weight[3]};
    if (!out.joints1.empty()) {
      out.joints1.back() = {w.joint[4], w.joint[5], w.joint[6], w.joint[7]};
      out.weights1.back() = {w.weight[4], w.weight[5], w.weight[6], w.weight[7]};
    }
  }
  const AttributeLayout& layout = *s.layout;
  if (!layout.stride) return;
  const float* a = s.attributes.data() + size_t(v) * layout.stride;
  if (layout.normal >= 0) out.normals.back() = {a[layout.normal], a[layout.normal + 1], a[layout.normal + 2]};
  for (uint32_t k = 0; k < layout.uv_sets; ++k) out.uvs[k].back() = {a[layout.uv[k]], a[layout.uv[k] + 1]};
  if (layout.color >= 0)
    out.colors.back() = {a[layout.color], a[layout.color + 1], a[layout.color + 2], a[layout.color + 3]};
}

Mesh empty_like(const Mesh& input) {
  Mesh out;
  copy_id_tables(out, input);
  return out;
}

void append_triangle(Mesh& out, const Mesh& input, uint32_t t, const uint32_t* corners) {
  out.indices.insert(out.indices.end(), corners, corners + 3);
  if (!input.materials.empty()) out.materials.push_back(input.materials[t]);
  if (!input.groups.empty()) out.groups.push_back(input.groups[t]);
}

}  // namespace

Mesh compact(const Mesh& input, const Snapshot& s, std::vector<uint32_t>* vertex_origin,
             std::vector<uint32_t>* triangle_origin) {
  Mesh out = empty_like(input);
  std::vector<uint32_t> remap(input.vertex_count(), ~0u);
  if (vertex_origin) vertex_origin->clear();
  if (triangle_origin) triangle_origin->clear();
  const size_t triangles = s.corners.size() / 3;
  for (size_t t = 0; t < triangles; ++t) {
    if (!s.alive[t]) continue;
    uint32_t corners[3];
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = s.corners[3 * t + k];
      if (remap[v] == ~0u) {
        remap[v] = uint32_t(out.positions.size());
        append_current(out, input, s, v);
        if (vertex_origin) vertex_origin->push_back(v);
      }
      corners[k] = remap[v];
    }
    append_triangle(out, input, uint32_t(t), corners);
    if (triangle_origin) triangle_origin->push_back(uint32_t(t));
  }
  return out;
}

Mesh materialize(const Mesh& input, const Snapshot& s) {
  Mesh out = empty_like(input);
  for (uint32_t v = 0; v < input.vertex_count(); ++v) append_current(out, input, s, v);
  const size_t triangles = s.corners.size() / 3;
  for (size_t t = 0; t < triangles; ++t)
    if (s.alive[t]) append_triangle(out, input, uint32_t(t), &s.corners[3 * t]);
  return out;
}

Replay::Replay(const Mesh& mesh) {
  const PositionIds ids = position_ids(mesh);
  position_of = ids.id;
  position.resize(ids.count);
  for (size_t v = mesh.vertex_count(); v-- > 0;) position[ids.id[v]] = mesh.positions[v];
  moves.assign(ids.count, 0);
  corners = mesh.indices;
  alive.assign(mesh.triangle_count(), 1);
  layout = attribute_layout(mesh);
  attributes = gather_attributes(mesh, layout);
  skinned = !mesh.joints.empty() && !mesh.weights.empty();
}

void Replay::check(const SimplifyRecord& record, size_t i) const {
  if (!valid(record, i)) throw_usage("replay: the collapse record does not belong to this mesh");
}

bool Replay::valid(const SimplifyRecord& record, size_t i) const {
  if (i >= record.collapses.size()) return false;
  const Collapse& c = record.collapses[i];
  if (c.kept >= position.size() || c.removed >= position.size()) return false;
  if (size_t(c.faces_begin) + c.removed_face_count > record.removed_faces.size()) return false;
  if (size_t(c.relinks_begin) + c.relink_count > record.relinks.size()) return false;
  if (size_t(c.wedges_begin) + c.wedge_count > record.wedges.size()) return false;
  if (record.stride != layout.stride) return false;
  // Influences: one per collapse, for a mesh that has joints and weights.
  if (!record.influences.empty() && (record.influences.size() != record.collapses.size() || !skinned)) return false;
  for (uint32_t k = 0; k < c.removed_face_count; ++k)
    if (record.removed_faces[c.faces_begin + k] >= alive.size()) return false;
  for (uint32_t k = 0; k < c.relink_count; ++k) {
    const Relink& r = record.relinks[c.relinks_begin + k];
    if (r.triangle >= alive.size() || r.corner > 2 || r.from >= position_of.size() || r.to >= position_of.size())
      return false;
  }
  for (uint32_t k = 0; k < c.wedge_count; ++k) {
    const WedgeChange& w = record.wedges[c.wedges_begin + k];
    if (w.vertex >= position_of.size() || size_t(w.values_begin) + layout.stride > record.new_values.size() ||
        size_t(w.values_begin) + layout.stride > record.old_values.size())
      return false;
  }
  if (size_t(c.moved_begin) + c.moved_count > record.moved_wedges.size()) return false;
  for (uint32_t k = 0; k < c.moved_count; ++k)
    if (record.moved_wedges[c.moved_begin + k] >= position_of.size()) return false;
  return true;
}

void Replay::apply(const SimplifyRecord& record, size_t i) {
  check(record, i);
  const Collapse& c = record.collapses[i];
  for (uint32_t k = 0; k < c.removed_face_count; ++k) alive[record.removed_faces[c.faces_begin + k]] = 0;
  for (uint32_t k = 0; k < c.relink_count; ++k) {
    const Relink& r = record.relinks[c.relinks_begin + k];
    corners[3 * r.triangle + r.corner] = r.to;
  }
  for (uint32_t k = 0; k < c.moved_count; ++k) position_of[record.moved_wedges[c.moved_begin + k]] = c.kept;
  // Wedges moved in from a virtual pair sit at kept's position even when it stays put.
  if (!(c.new_position == c.old_position) || c.moved_count) position[c.kept] = c.new_position, ++moves[c.kept];
  set_values(record, c, record.new_values);
  if (!record.influences.empty()) set_influences(c, record.influences[i].new_value);
}

bool Replay::apply_consistent(const SimplifyRecord& record, size_t i) {
  if (!valid(record, i)) return false;
  const Collapse& c = record.collapses[i];
  if (c.kept == c.removed || !(position[c.kept] == c.old_position)) return false;
  for (uint32_t k = 0; k < c.removed_face_count; ++k)
    if (!alive[record.removed_faces[c.faces_begin + k]]) return false;
  for (uint32_t k = 0; k < c.relink_count; ++k) {
    const Relink& r = record.relinks[c.relinks_begin + k];
    if (!alive[r.triangle] || corners[3 * r.triangle + r.corner] != r.from) return false;
  }
  for (uint32_t k = 0; k < c.moved_count; ++k)
    if (position_of[record.moved_wedges[c.moved_begin + k]] != c.removed) return false;
  for (uint32_t k = 0; k < c.wedge_count; ++k) {
    const WedgeChange& w = record.wedges[c.wedges_begin + k];
    if (!std::equal(record.old_values.begin() + w.values_begin, record.old_values.begin() + w.values_begin + layout.stride,
                    attributes.begin() + size_t(w.vertex) * layout.stride))
      return false;
  }
  if (!record.influences.empty()) {
    // The old value is the kept position's current one (weightless: never chosen); the new one
    // has weight.
    const InfluenceChange& w = record.influences[i];
    const Influences current = influences.empty() ? Influences{} : influences[c.kept];
    if (!(w.old_value == current) || !has_weight(w.new_value)) return false;
  }
  // Relinks and wedge changes listed twice would not undo exactly either.
  for (uint32_t k = 0; k < c.relink_count; ++k)
    for (uint32_t j = 0; j < k; ++j) {
      const Relink &a = record.relinks[c.relinks_begin + k], &b = record.relinks[c.relinks_begin + j];
      if (a.triangle == b.triangle && a.corner == b.corner) return false;
    }
  for (uint32_t k = 0; k < c.wedge_count; ++k)
    for (uint32_t j = 0; j < k; ++j)
      if (record.wedges[c.wedges_begin + k].vertex == record.wedges[c.wedges_begin + j].vertex) return false;
  for (uint32_t k = 0; k < c.moved_count; ++k)
    for (uint32_t j = 0; j < k; ++j)
      if (record.moved_wedges[c.moved_begin + k] == record.moved_wedges[c.moved_begin + j]) return false;
  apply(record, i);
  return true;
}

void Replay::undo(const SimplifyRecord& record, size_t i) {
  check(record, i);
  const Collapse& c = record.collapses[i];
  if (!record.influences.empty()) set_influences(c, record.influences[i].old_value);
  set_values(record, c, record.old_values);
  if (!(c.new_position == c.old_position) || c.moved_count) position[c.kept] = c.old_position, --moves[c.kept];
  for (uint32_t k = 0; k < c.moved_count; ++k) position_of[record.moved_wedges[c.moved_begin + k]] = c.removed;
  for (uint32_t k = c.relink_count; k-- > 0;) {
    const Relink& r = record.relinks[c.relinks_begin + k];
    corners[3 * r.triangle + r.corner] = r.from;
  }
  for (uint32_t k = 0; k < c.removed_face_count; ++k) alive[record.removed_faces[c.faces_begin + k]] = 1;
}

void Replay::fit(const SimplifyRecord& record, bool forwards) {
  for (const FittedPosition& f : record.fitted)
    if (f.position >= position.size()) throw_usage("replay: the collapse record does not belong to this mesh");
  for (const Relink& r : record.flipped)
    if (r.triangle >= alive.size() || r.corner > 2 || r.from >= position_of.size() || r.to >= position_of.size())
      throw_usage("replay: the collapse record does not belong to this mesh");
  // Flips change corners and moves change positions: the two commute.
  if (forwards)
    for (const Relink& r : record.flipped) corners[3 * size_t(r.triangle) + r.corner] = r.to;
  else
    for (size_t i = record.flipped.size(); i-- > 0;) corners[3 * size_t(record.flipped[i].triangle) + record.flipped[i].corner] = record.flipped[i].from;
  for (const FittedPosition& f : record.fitted) {
    position[f.position] = forwards ? f.new_position : f.old_position;
    moves[f.position] += forwards ? 1 : -1;
  }
}

void Replay::set_values(const SimplifyRecord& record, const Collapse& c, const std::vector<float>& values) {
  for (uint32_t k = 0; k < c.wedge_count; ++k) {
    const WedgeChange& w = record.wedges[c.wedges_begin + k];
    std::copy_n(values.begin() + w.values_begin, layout.stride, attributes.begin() + size_t(w.vertex) * layout.stride);
  }
}

void Replay::set_influences(const Collapse& c, const Influences& value) {
  if (influences.empty()) influences.resize(position.size());  // weightless: the wedges' own
  influences[c.kept] = value;
}

}  // namespace collapse

Mesh replay(const Mesh& mesh, const SimplifyRecord& record, size_t count) {
  if (count > record.collapses.size()) throw_usage("replay: asked for more collapses than the record holds");
  collapse::Replay state(mesh);
  for (size_t i = 0; i < count; ++i) state.apply(record, i);
  if (count == record.collapses.size()) state.fit(record, true);
  return collapse::compact(mesh, state.snapshot(), nullptr, nullptr);
}

Mesh replay_and_undo(const Mesh& mesh, const SimplifyRecord& record) {
  collapse::Replay state(mesh);
  for (size_t i = 0; i < record.collapses.size(); ++i) state.apply(record, i);
  state.fit(record, true);
  state.fit(record, false);
  for (size_t i = record.collapses.size(); i-- > 0;) state.undo(record, i);
  return collapse::materialize(mesh, state.snapshot());
}

}  // namespace lod
