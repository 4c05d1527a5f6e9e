// Inputs in a form no collapse can touch (double-sided by duplication, flat-shaded): the form to
// simplify instead, and the result's form given back. See simplify.h.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>

#include "core/buckets.h"
#include "core/vec3d.h"
#include "lodkit/error.h"
#include "lodkit/optimize.h"
#include "lodkit/simplify.h"

namespace lod {

namespace {

// A position's bits mixed into 64 (+0 and -0 alike, as position ids have them).
uint64_t position_hash(const float3& p) {
  uint64_t h = 0;
  for (const float f : {p.x, p.y, p.z}) {
    uint32_t bits = 0;
    const float g = f == 0.0f ? 0.0f : f;
    std::memcpy(&bits, &g, 4);
    h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
    h ^= h >> 29;
  }
  return h;
}

// A quick filter before the exact pairing (a map over every triangle, a second on an 832k-triangle
// mesh): each triangle adds the hash of its corners' positions in sorted order, with the sign of
// the sort's permutation. A twin has the same sorted corners and the other sign, so a double-sided
// mesh sums to zero; anything else almost surely does not.
bool may_be_double_sided(const Mesh& mesh) {
  if (mesh.triangle_count() == 0 || mesh.triangle_count() % 2) return false;
  uint64_t sum = 0;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    uint64_t h[3];
    for (int k = 0; k < 3; ++k) h[k] = position_hash(mesh.positions[mesh.indices[3 * t + k]]);
    bool odd = false;
    const auto order = [&](int i, int j) {
      if (h[i] > h[j]) std::swap(h[i], h[j]), odd = !odd;
    };
    order(0, 1), order(1, 2), order(0, 1);
    const uint64_t key = (h[0] * 0x9E3779B97F4A7C15ull) ^ (h[1] * 0xC2B2AE3D27D4EB4Full + (h[1] >> 29)) ^
                         (h[2] * 0x165667B19E3779F9ull + (h[2] >> 31));
    sum += odd ? key : 0 - key;
  }
  return sum == 0;
}

// Per triangle: the index of its reversed twin among the triangles (each twin paired once, the
// earlier of a pair first), or -1. Position ids decide: the twin's corners are separate vertices.
std::vector<int64_t> twins(const Mesh& mesh, const PositionIds& ids) {
  std::map<std::array<uint32_t, 3>, std::vector<uint32_t>> open;  // a rotation of the corners -> unpaired triangles
  const auto rotated = [](std::array<uint32_t, 3> c) {  // the rotation starting at the smallest id
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    return c;
  };
  std::vector<int64_t> twin(mesh.triangle_count(), -1);
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t a = ids.id[mesh.indices[3 * t]], b = ids.id[mesh.indices[3 * t + 1]], c = ids.id[mesh.indices[3 * t + 2]];
    const auto reversed = open.find(rotated({a, c, b}));
    if (reversed != open.end() && !reversed->second.empty()) {
      twin[t] = reversed->second.back(), twin[reversed->second.back()] = t;
      reversed->second.pop_back();
    } else {
      open[rotated({a, b, c})].push_back(t);
    }
  }
  return twin;
}

// The first of each twin pair on the vertices they use (in input order), or nothing when some
// triangle has no twin. The backs' vertices go: left in, their reversed normals would make every
// position look flat-shaded. Fills `form.source` and `form.back` for the input's vertices.
std::optional<Mesh> double_sided_fronts(const Mesh& mesh, SurfaceForm& form) {
  if (!may_be_double_sided(mesh)) return std::nullopt;
  const PositionIds ids = position_ids(mesh);
  const std::vector<int64_t> twin = twins(mesh, ids);
  if (std::any_of(twin.begin(), twin.end(), [](int64_t t) { return t < 0; })) return std::nullopt;
  std::vector<uint32_t> kept(mesh.vertex_count(), UINT32_MAX);
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    if (size_t(twin[t]) > t)
      for (int k = 0; k < 3; ++k) kept[mesh.indices[3 * t + k]] = 0;
  Mesh front;
  copy_id_tables(front, mesh);
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    if (kept[v] == 0) kept[v] = uint32_t(front.vertex_count()), append_vertex(front, mesh, v);
  form.source = kept, form.back.assign(mesh.vertex_count(), false);
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (size_t(twin[t]) < t) {
      // The back of an earlier front: its own vertices stand for the front's at the same positions.
      const uint32_t* f = &mesh.indices[3 * size_t(twin[t])];
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = mesh.indices[3 * t + k];
        if (kept[u] != UINT32_MAX) continue;  // a front's vertex too (no normals to tell the sides apart)
        for (int j = 0; j < 3; ++j)
          if (ids.id[f[j]] == ids.id[u]) form.source[u] = kept[f[j]], form.back[u] = true;
      }
      continue;
    }
    for (int k = 0; k < 3; ++k) front.indices.push_back(kept[mesh.indices[3 * t + k]]);
    if (!mesh.materials.empty()) front.materials.push_back(mesh.materials[t]);
    if (!mesh.groups.empty()) front.groups.push_back(mesh.groups[t]);
  }
  return front;
}

bool flat_shaded(const Mesh& mesh) {
  if (mesh.normals.empty() || !mesh.tangents.empty()) return false;  // (tangents would need the same care)
  if (mesh.triangle_count() == 0) return false;  // no face to facet
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float3& n = mesh.normals[mesh.indices[3 * t]];
    if (!(mesh.normals[mesh.indices[3 * t + 1]] == n) || !(mesh.normals[mesh.indices[3 * t + 2]] == n)) return false;
  }
  // Some position with two normals: else the normals cost the simplifier nothing.
  return position_ids(mesh).count < weld(mesh).output_vertices;
}

// Each triangle's corners get its face normal (double precision), corners alike shared again.
// Returns each corner's vertex.
std::vector<uint32_t> refacet(Mesh& mesh) {
  Mesh split;
  copy_id_tables(split, mesh);
  split.materials = mesh.materials, split.groups = mesh.groups;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float3 n = core::unit_float3(core::triangle_cross(mesh, t), {0, 0, 1});
    for (int k = 0; k < 3; ++k) {
      split.indices.push_back(uint32_t(split.positions.size()));
      append_vertex(split, mesh, mesh.indices[3 * t + k]);
      split.normals.push_back(n);
    }
  }
  WeldResult welded = weld(split);
  mesh = std::move(welded.mesh);
  return std::move(welded.remap);
}

// Each triangle gets its reversed twin on copies of its vertices, normals negated. Returns, per
// vertex and then per back copy of it, its vertex (the front's own when they weld).
std::vector<uint32_t> add_back_faces(Mesh& mesh) {
  const size_t triangles = mesh.triangle_count(), vertices = mesh.vertex_count();
  for (uint32_t v = 0; v < vertices; ++v) {
    append_vertex(mesh, mesh, v);
    if (!mesh.normals.empty()) {
      float3& n = mesh.normals.back();
      n = {-n.x, -n.y, -n.z};
    }
    if (!mesh.tangents.empty()) {
      float4& t = mesh.tangents.back();
      t.w = -t.w;  // u runs the same way on the back, whose normal is turned: the bitangent's sign flips
    }
  }
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
    mesh.indices.insert(mesh.indices.end(), {uint32_t(vertices) + a, uint32_t(vertices) + c, uint32_t(vertices) + b});
    if (!mesh.materials.empty()) mesh.materials.push_back(mesh.materials[t]);
    if (!mesh.groups.empty()) mesh.groups.push_back(mesh.groups[t]);
  }
  std::vector<uint32_t> vertex(mesh.vertex_count());
  for (uint32_t v = 0; v < vertex.size(); ++v) vertex[v] = v;
  if (mesh.normals.empty()) {  // without normals the twins' vertices are the fronts'
    WeldResult welded = weld(mesh);
    mesh = std::move(welded.mesh), vertex = std::move(welded.remap);
  }
  return vertex;
}

}  // namespace

SurfaceForm surface_form(const Mesh& mesh) {
  SurfaceForm form;
  if (std::optional<Mesh> front = double_sided_fronts(mesh, form)) form.double_sided = true, form.mesh = std::move(*front);
  const Mesh& sided = form.double_sided ? form.mesh : mesh;
  if (flat_shaded(sided)) {
    Mesh smooth = sided;
    smooth.normals.clear();
    WeldResult welded = weld(smooth);
    if (!form.double_sided) {
      form.source.resize(mesh.vertex_count());
      for (uint32_t v = 0; v < mesh.vertex_count(); ++v) form.source[v] = v;
      form.back.assign(mesh.vertex_count(), false);
    }
    form.facet.resize(mesh.vertex_count());
    for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
      if (form.source[v] != UINT32_MAX)  // (a vertex no triangle uses has no front)
        form.facet[v] = sided.normals[form.source[v]], form.source[v] = welded.remap[form.source[v]];
    if (!mesh.materials.empty()) {
      form.material.assign(mesh.vertex_count(), 0);
      for (size_t c = mesh.indices.size(); c-- > 0;) form.material[mesh.indices[c]] = mesh.materials[c / 3];
    }
    form.flat_shaded = true, form.mesh = std::move(welded.mesh);  // (`sided` may be form.mesh: last)
  }
  return form;
}

void restore_form(const SurfaceForm& form, Mesh& result, std::vector<uint32_t>& vertex_successor) {
  if (!form.changed()) return;
  if (vertex_successor.empty()) {  // nothing to map
    if (form.flat_shaded) refacet(result);
    if (form.double_sided) add_back_faces(result);
    return;
  }
  if (vertex_successor.size() != form.mesh.vertex_count() || form.source.size() != form.back.size())
    throw_usage("restore_form: " + std::to_string(vertex_successor.size()) + " successors for a form of " +
                std::to_string(form.mesh.vertex_count()) + " vertices");
  // Each input vertex's successor in the simplified form (UINT32_MAX: none).
  std::vector<uint32_t> successor(form.source.size(), UINT32_MAX);
  for (size_t u = 0; u < successor.size(); ++u)
    if (form.source[u] < vertex_successor.size()) successor[u] = vertex_successor[form.source[u]];
  if (form.flat_shaded) {
    // A successor's faceted copies are at its corners: the corner whose face normal is nearest.
    // (refacet keeps the corners in order: corner c of the result is corner c of the smooth mesh.)
    const size_t smooth = result.vertex_count();
    const core::Buckets<uint32_t> corners = core::bucket<uint32_t>(smooth, [&](auto&& emit) {
      for (uint32_t c = 0; c < result.indices.size(); ++c) emit(result.indices[c], c);
    });
    const std::vector<uint32_t> corner_vertex = refacet(result);
    for (size_t u = 0; u < successor.size(); ++u) {
      const uint32_t r = successor[u];
      if (r >= smooth) continue;
      const float3& n = form.facet[u];
      // Its own material's copies, when it has some: a joined group's member keeps its vertices.
      const auto own = [&](uint32_t c) {
        return form.material.empty() || result.materials.empty() || result.materials[c / 3] == form.material[u];
      };
      const bool any_own = std::any_of(corners[r].begin(), corners[r].end(), own);
      double best_dot = -INFINITY;
      successor[u] = UINT32_MAX;  // (a vertex no triangle uses has no copy)
      for (const uint32_t c : corners[r]) {
        if (any_own && !own(c)) continue;
        const double dot = core::dot(core::to_double(result.normals[corner_vertex[c]]), core::to_double(n));
        if (dot > best_dot) best_dot = dot, successor[u] = corner_vertex[c];  // ties: the first corner
      }
    }
  }
  if (form.double_sided) {
    const size_t fronts = result.vertex_count();
    const std::vector<uint32_t> vertex = add_back_faces(result);
    for (size_t u = 0; u < successor.size(); ++u)
      if (successor[u] < fronts) successor[u] = vertex[successor[u] + (form.back[u] ? fronts : 0)];
  }
  vertex_successor = std::move(successor);
}

}  // namespace lod
