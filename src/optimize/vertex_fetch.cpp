// Vertex-fetch order: renumber vertices by first use, so the vertex shader's reads walk memory
// forward. Also the mesh-level permutations the optimiser uses.
#include "lodkit/error.h"
#include "lodkit/optimize.h"

namespace lod {

namespace {
constexpr uint32_t none = 0xFFFFFFFFu;

template <class T>
void remap_stream(std::vector<T>& stream, std::span<const uint32_t> remap, size_t new_count) {
  if (stream.empty()) return;
  std::vector<T> out(new_count);
  std::vector<uint8_t> filled(new_count, 0);
  for (size_t v = 0; v < remap.size(); ++v)
    if (remap[v] != none && !filled[remap[v]]) out[remap[v]] = stream[v], filled[remap[v]] = 1;
  stream = std::move(out);
}
}  // namespace

std::vector<uint32_t> vertex_fetch_remap(std::span<const uint32_t> indices, size_t vertex_count) {
  std::vector<uint32_t> remap(vertex_count, none);
  uint32_t next = 0;
  for (const uint32_t i : indices) {
    if (i >= vertex_count) throw_usage("vertex_fetch_remap: index " + std::to_string(i) + " out of range");
    if (remap[i] == none) remap[i] = next++;
  }
  for (uint32_t& r : remap)
    if (r == none) r = next++;
  return remap;
}

Mesh reorder_triangles(const Mesh& mesh, std::span<const uint32_t> order) {
  if (order.size() != mesh.triangle_count()) throw_usage("reorder_triangles: the order must list every triangle once");
  Mesh out = mesh;
  for (size_t k = 0; k < order.size(); ++k) {
    const size_t t = order[k];
    if (t >= mesh.triangle_count()) throw_usage("reorder_triangles: triangle out of range");
    for (size_t c = 0; c < 3; ++c) out.indices[3 * k + c] = mesh.indices[3 * t + c];
    if (!mesh.materials.empty()) out.materials[k] = mesh.materials[t];
    if (!mesh.groups.empty()) out.groups[k] = mesh.groups[t];
  }
  return out;
}

Mesh remap_vertices(const Mesh& mesh, std::span<const uint32_t> remap, size_t new_vertex_count) {
  if (remap.size() != mesh.vertex_count()) throw_usage("remap_vertices: the remap must have one entry per vertex");
  for (const uint32_t r : remap)
    if (r != none && r >= new_vertex_count) throw_usage("remap_vertices: target vertex out of range");
  Mesh out = mesh;
  remap_stream(out.positions, remap, new_vertex_count);
  remap_stream(out.normals, remap, new_vertex_count);
  remap_stream(out.tangents, remap, new_vertex_count);
  for (auto& uv : out.uvs) remap_stream(uv, remap, new_vertex_count);
  remap_stream(out.colors, remap, new_vertex_count);
  remap_stream(out.joints, remap, new_vertex_count);
  remap_stream(out.weights, remap, new_vertex_count);
  remap_stream(out.joints1, remap, new_vertex_count);
  remap_stream(out.weights1, remap, new_vertex_count);
  for (uint32_t& i : out.indices) {
    i = remap[i];
    if (i == none) throw_usage("remap_vertices: a triangle uses a vertex the remap drops");
  }
  return out;
}

}  // namespace lod
