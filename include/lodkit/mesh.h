// lodkit: the indexed triangle mesh (structure of arrays) and what can be asked of it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lod {

struct float2 {
  float x = 0, y = 0;
  friend bool operator==(const float2&, const float2&) = default;
};
struct float3 {
  float x = 0, y = 0, z = 0;
  friend bool operator==(const float3&, const float3&) = default;
};
struct float4 {
  float x = 0, y = 0, z = 0, w = 0;
  friend bool operator==(const float4&, const float4&) = default;
};
using ushort4 = std::array<uint16_t, 4>;

inline constexpr size_t max_uv_sets = 4;

// How a material looks, where the input says so (an OBJ's MTL library, a PLY's TextureFile lines, a
// glTF's materials), in glTF's metallic-roughness terms: what a glTF written from the mesh gets.
// Textures are file paths (UTF-8), as resolved against the library's folder; empty for none.
struct MaterialLook {
  float4 base_color{1, 1, 1, 1};      // RGB (MTL Kd) and alpha (d, or 1 - Tr)
  float3 emissive{0, 0, 0};           // MTL Ke
  float metallic = 0, roughness = 1;  // MTL Pm and Pr, or roughness from the Phong exponent Ns
  std::string base_color_texture;     // map_Kd
  std::string normal_texture;         // norm, map_Bump or bump
  std::string emissive_texture;       // map_Ke
  // A texture embedded in a glTF (its binary chunk or a data: URI) has no file to name: its encoded
  // image (PNG or JPEG) instead, by slot in textures()' order, the path then empty; shared by the
  // looks that use it. An OBJ or PLY written from the mesh gets it as a file beside it (write_mesh).
  std::array<std::shared_ptr<const std::vector<uint8_t>>, 3> images;
  // The three texture paths, in that order (base colour, normal, emissive).
  std::array<const std::string*, 3> textures() const { return {&base_color_texture, &normal_texture, &emissive_texture}; }
  std::array<std::string*, 3> textures() { return {&base_color_texture, &normal_texture, &emissive_texture}; }
  friend bool operator==(const MaterialLook& a, const MaterialLook& b);  // (images by their bytes)
};

// An indexed triangle mesh in structure-of-arrays form.
// Every non-empty vertex stream has exactly vertex_count() entries; an empty stream is absent.
// Triangles are counter-clockwise seen from outside (glTF / OpenGL convention).
struct Mesh {
  std::vector<float3> positions;                     // object space
  std::vector<float3> normals;                       // unit length
  std::vector<float4> tangents;                      // xyz unit, w = handedness (+1 or -1)
  std::array<std::vector<float2>, max_uv_sets> uvs;  // texture coordinate sets, used in order 0, 1, ...
  std::vector<float4> colors;                        // linear RGBA in [0, 1]
  // Skin influences: four (joint index, weight) pairs per vertex in joints/weights (glTF JOINTS_0 /
  // WEIGHTS_0), and four more in joints1/weights1 (JOINTS_1 / WEIGHTS_1) for inputs with up to eight.
  // joints1/weights1 are empty unless the input has a second set, and present only with the first.
  // The weights of a vertex sum to 1 over all its sets; a slot of weight 0 is unused (its joint may be
  // any index).
  std::vector<ushort4> joints;
  std::vector<float4> weights;
  std::vector<ushort4> joints1;
  std::vector<float4> weights1;

  std::vector<uint32_t> indices;    // 3 per triangle
  std::vector<uint32_t> materials;  // per triangle material id; empty means every triangle uses material 0
  std::vector<std::string> material_names;  // indexed by material id; may be empty or shorter
  // Indexed by material id, as material_names, when the input described the materials (an OBJ's
  // MTL library); empty otherwise.
  std::vector<MaterialLook> material_looks;
  std::vector<uint32_t> groups;             // per triangle group id (OBJ g/o); empty means no groups
  std::vector<std::string> group_names;     // indexed by group id

  size_t vertex_count() const { return positions.size(); }
  size_t triangle_count() const { return indices.size() / 3; }
  size_t uv_set_count() const;  // number of leading non-empty uv sets
  uint32_t material(size_t triangle) const { return materials.empty() ? 0 : materials[triangle]; }
  // Influence slots per vertex: 0 (no skin), 4 (joints/weights) or 8 (with joints1/weights1).
  size_t influence_slots() const { return joints.empty() ? 0 : joints1.empty() ? 4 : 8; }

  friend bool operator==(const Mesh&, const Mesh&) = default;
};

// Gives `to` the tables `from` keeps by material and group id (material names and looks, group
// names), not the per-triangle ids: for a mesh made of another's triangles.
void copy_id_tables(Mesh& to, const Mesh& from);

// Which of the material ids below `count` some triangle uses (with no per-triangle ids, every
// triangle uses material 0).
std::vector<bool> used_materials(const Mesh& mesh, size_t count);

// Copies vertex `from` of `src` (all streams present in `dst`) to the end of `dst`.
void append_vertex(Mesh& dst, const Mesh& src, uint32_t from);

// Which vertex streams a mesh has, as bits in this order: normals, tangents, the UV sets, colours,
// then the influences (influence_streams: joints, weights, joints1, weights1). Meshes with the same
// layout join without dropping or inventing values (see flatten).
uint32_t stream_layout(const Mesh& mesh);
inline constexpr uint32_t stream_normals = 1u << 0, stream_tangents = 1u << 1;
inline constexpr uint32_t stream_uv0 = 1u << 2;  // UV set k: stream_uv0 << k
inline constexpr uint32_t stream_colors = 1u << 6, stream_joints = 1u << 7, stream_weights = 1u << 8;
inline constexpr uint32_t stream_joints1 = 1u << 9, stream_weights1 = 1u << 10;
inline constexpr uint32_t influence_streams = stream_joints | stream_weights | stream_joints1 | stream_weights1;
// Gives `mesh` the streams of `layout` it lacks, with neutral values: smooth normals, tangents along
// +x, UVs of 0, white, no second influences (weights 0). For a join whose result is split again:
// constant values cost nothing in the simplifier, and keep_streams drops them again.
void fill_streams(Mesh& mesh, uint32_t layout);
// Drops the streams `layout` does not have.
void keep_streams(Mesh& mesh, uint32_t layout);

// Throws lod::Error (bad_input) naming `source` if streams have mismatched sizes, indices are out of
// range, values are not finite, weights are negative or do not sum to 1 over both influence sets
// (within weight_tolerance), a second influence set comes without the first, or per-triangle streams
// do not match the triangle count.
struct ValidateOptions {
  float weight_tolerance = 1e-3f;  // |sum(weights) + sum(weights1) - 1| allowed per vertex
};
void validate(const Mesh& mesh, const std::string& source = "mesh", const ValidateOptions& options = {});

// Position ids (the wedge / seam table): vertices with bit-identical positions share one id,
// so attributes (wedges) and topology can be told apart. Ids are dense, in order of first appearance.
// +0.0 and -0.0 are treated as equal.
struct PositionIds {
  std::vector<uint32_t> id;  // per vertex
  uint32_t count = 0;        // number of unique positions
};
PositionIds position_ids(const Mesh& mesh);

// Per vertex: the unit sum of the area-weighted normals of the triangles at its position (position
// ids, so a UV seam does not crease it; in double). (0, 0, 0) where they cancel or there are none.
std::vector<float3> smooth_normals(const Mesh& mesh);

// Gives every normal and tangent unit length, as Mesh promises (glTF requires it): a normal off it
// is scaled to it, a zero one takes its smooth normal (smooth_normals), or +z where that is zero
// too. A tangent's xyz likewise; a zero one takes a direction perpendicular to the normal, and its
// w becomes the sign of w (+1 for 0). A direction within 1e-6 of unit length is kept bit for bit.
// No reader asks unit directions of its file (an OBJ corner without `vn` reads as zero); they all
// call this.
void make_unit_directions(Mesh& mesh);

// Topological and geometric statistics. Topology is computed on position ids, so seams do not cut.
struct ComponentStats {
  uint32_t vertices = 0;   // unique positions
  uint32_t edges = 0;      // undirected edges
  uint32_t triangles = 0;  // non-degenerate triangles
  uint32_t boundary_loops = 0;
  int64_t euler_characteristic = 0;  // V - E + F
  bool closed = false;      // no boundary edge
  bool manifold = false;    // no non-manifold edge or vertex
  bool orientable = false;  // triangles can be wound consistently (manifold components only)
  // (2 - chi - b) / 2 for an orientable manifold with b boundary loops; -1 otherwise.
  int64_t genus = -1;
};

struct MeshStats {
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  uint64_t unique_positions = 0;
  uint64_t edges = 0;
  uint64_t connected_components = 0;
  uint64_t boundary_edges = 0;
  uint64_t boundary_loops = 0;
  uint64_t non_manifold_edges = 0;     // edges with more than two incident triangles
  uint64_t non_manifold_vertices = 0;  // vertices whose incident triangles form more than one fan
  uint64_t degenerate_triangles = 0;   // two corners share a position id
  uint64_t zero_area_triangles = 0;    // distinct corners but zero area (collinear)
  uint64_t duplicate_triangles = 0;    // same position-id set as an earlier triangle (any winding)
  uint64_t seam_edges = 0;             // edges whose two sides use different vertices (attribute seams)
  uint64_t materials = 0;
  uint64_t unreferenced_positions = 0;  // unique positions used by no triangle
  // V - E + F over the referenced unique positions, non-degenerate triangles and their edges;
  // equals the sum over components.
  int64_t euler_characteristic = 0;
  float3 bbox_min, bbox_max;
  double diagonal = 0;                 // length of the bounding-box diagonal
  std::vector<ComponentStats> components;  // in order of their first triangle
};
MeshStats compute_stats(const Mesh& mesh);

// 1 -> 4 midpoint subdivision; every vertex stream is interpolated (normals renormalised).
// Edge midpoints are shared between triangles that share the two vertex indices.
Mesh subdivide_midpoint(const Mesh& mesh);

// Axis-aligned bounds of the positions ({0,0,0} for an empty mesh).
void bounding_box(const Mesh& mesh, float3& min, float3& max);

}  // namespace lod
