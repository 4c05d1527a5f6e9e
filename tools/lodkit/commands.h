// The lodkit CLI: one file per subcommand; each registers itself on the root app.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>
#include <functional>
#include <optional>
#include <span>
#include <initializer_list>
#include <string>

#include "lodkit/io.h"
#include "lodkit/simplify.h"

namespace lod::cli {

// A subcommand's body; returns the process exit code. Library errors propagate as lod::Error.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Command register_info(CLI::App& root);
Command register_convert(CLI::App& root);
Command register_simplify(CLI::App& root);
Command register_compare(CLI::App& root);
Command register_optimize(CLI::App& root);
Command register_analyze(CLI::App& root);
Command register_lod(CLI::App& root);
Command register_render(CLI::App& root);

// Shared option parsers (simplify, lod): --metric NAME and --attributes normal=W,uv=W,color=W.
Metric parse_metric(const std::string& name);
void parse_attributes(const std::string& text, SimplifyOptions& options);

// A command's input geometry: the whole glTF scene when input and output are both glTF (nodes,
// skins, animations and materials are written back as they were), else one mesh. `meshes` lists
// what to process in place. Not copyable: `meshes` points into it.
class GeometryFile {
 public:
  // Refuses (check_not_source) an output that would write over a file the input glTF reads.
  GeometryFile(const std::string& input, const std::string& output, bool force);
  GeometryFile(const GeometryFile&) = delete;
  GeometryFile& operator=(const GeometryFile&) = delete;
  WriteReport write(const std::string& output, const WriteOptions& options = {}) const;
  // lod::cli::check_not_source for another file the command writes (the constructor checks `output`).
  void check_not_source(const std::string& path, bool force) const;
  // After meshes[i] changed for each i where changed[i]: the facts `lodkit lod` wrote on the glTF
  // nodes that draw them (extras "lodkit": triangles, errors, switch distance; "LODKIT_geomorph": a
  // morph target) no longer hold, and are removed, the geomorph's target too.
  void forget_lod_facts(const std::vector<bool>& changed);
  // meshes[i]'s vertices were renumbered: its vertex v was vertex source[v]. The glTF streams lodkit
  // does not model (morph targets, other attributes) follow them (Primitive::source_vertices). An
  // empty `source`: the vertices are new, and those streams are dropped.
  void renumbered(size_t i, const std::vector<uint32_t>& source);
  // meshes[i]'s vertices moved (a simplification): its vertex v lies at blends[v] on the vertices it
  // had, and those streams are interpolated there (Primitive::source_weights).
  void renumbered(size_t i, const std::vector<VertexBlend>& blends);
  // meshes[] in groups to simplify as one: the primitives of one glTF mesh with the same vertex
  // streams, so that the borders between their materials stay closed. In order of first member.
  std::vector<std::vector<size_t>> joint_groups() const;
  // meshes[i]'s vertex classes for a weld (lod::source_vertex_classes; empty: none).
  std::vector<uint32_t> vertex_classes(size_t i) const;

  std::vector<Mesh*> meshes;

 private:
  bool as_scene_ = false;
  Scene scene_;
  Mesh mesh_;
};

// Meshes simplified as one (GeometryFile::joint_groups, a skinned node's primitives), so that the
// borders between them stay closed like seams: member k is material id k + 1 (flatten's numbering)
// and its vertices are offsets[k] to offsets[k + 1]. A stream some member lacks is given to it with
// neutral values (FlattenOptions::fill_streams), and split_members drops it again (keep_streams):
// layouts[k] is member k's own (stream_layout). Influences are not made up: the members have the
// same first set. A group of one is the mesh itself, not a copy.
struct Joined {
  const Mesh& mesh() const { return alone ? *alone : joined; }
  const Mesh* alone = nullptr;
  Mesh joined;
  std::vector<uint32_t> offsets;  // members + 1
  std::vector<uint32_t> layouts;
};
Joined join_members(std::span<const Mesh* const> members);

// A result of the joined mesh (a simplification, a LOD level) back in its members, each with its
// own streams, its vertices' input vertices among its own (origin, when given), its input vertices'
// vertices (successor, when given; ~0u for none), and the joined result's vertex each of its
// vertices is (vertices). A member whose triangles all collapsed is left empty.
struct Member {
  Mesh mesh;
  std::vector<uint32_t> origin, successor, vertices;
};
std::vector<Member> split_members(const Joined& joined, Mesh mesh, std::vector<uint32_t> origin,
                                  std::vector<uint32_t> successor);

// Removes these members from a node's extras: lodkit's facts about what it draws (extras "lodkit",
// "LODKIT_geomorph", "MSFT_screencoverage") once they no longer hold.
bool erase_extras(Node& node, std::initializer_list<const char*> members);  // whether any was there

// lod --morph's geomorphs (extras "LODKIT_geomorph") leave the meshes of the nodes `which` takes,
// the facts those nodes' extras: a geomorph moved the old vertices onto the next level's, and at
// new vertices it would morph towards nothing. The blend shapes before it stay
// (Primitive::source_target_count).
void drop_geomorphs(Scene& scene, const std::function<bool(const Node&)>& which);

// A primitive whose vertices moved: vertex v lies at blends[v] on the vertices it had, so the glTF
// streams lodkit does not model are interpolated there (Primitive::source_weights), through its
// source_vertices when it has them.
void blend_sources(Primitive& p, const std::vector<VertexBlend>& blends);

// Merges a mesh's bitwise-identical vertices (lod::weld, exact), as gltfpack does before it
// simplifies: the simplifier takes copies of one vertex for a seam, so a triangle soup (a
// non-indexed glTF, an OBJ or PLY without shared vertices) would not simplify at all. Vertices in
// different `classes` (GeometryFile::vertex_classes) stay apart. Returns each vertex's first input
// vertex, or nothing when no two vertices were the same (the mesh is then untouched).
std::vector<uint32_t> weld_duplicates(Mesh& mesh, std::span<const uint32_t> classes);

// -c/--compress, -q/--quantize and --position-bits on a command that writes glTF.
void add_gltf_output_flags(CLI::App* app, WriteOptions& options);
// Refuses those flags for an output that is not glTF (they would do nothing).
void check_gltf_output_flags(const WriteOptions& options, const std::string& output);
// What a write did, for a command's report: `output_bytes`, and under --draco the primitives by
// how they went into Draco, added to `json`; as text, a line of it (nothing without --draco). Either
// warns on stderr of a primitive left plain: the user asked for Draco and did not get it there.
void add_write_report(nlohmann::json& json, const WriteReport& report, const WriteOptions& options);
std::string draco_line(const WriteReport& report, const WriteOptions& options);

// The value of an option whose value may be left out (--weld, --weld=EPS): `fallback` when it was
// given without one. CLI11 2.1 gives such an option the next word even when that word is the input
// file (`--weld in.obj -o out.glb`), so a word that is not a number becomes `input` when no input was
// given; otherwise it is a usage error.
double optional_number(const std::string& flag, const std::string& word, double fallback, std::string& input);

// Refuses (bad input) an input without a single triangle, a point cloud or a glTF of points and
// lines only, saying `why`: simplifying, ordering or building levels of it would write an empty file.
void require_triangles(std::span<const Mesh* const> meshes, const std::string& input, const std::string& why);

// Checked before any work: refuses to write over the input (it would be lost if anything went wrong)
// or over the MTL library an OBJ input reads (an .obj output's library, obj_library_path) unless
// `force`, and an output in a folder that does not exist (check_output_folder).
void check_output(const std::string& input, const std::string& output, bool force);
// Refuses (bad input, exit 2, as the write itself would say) an output in a folder that does not
// exist: found only at the end otherwise, after the work.
void check_output_folder(const std::string& output);
// Likewise over a file an input glTF reads (lod::source_files): a .gltf output writes OUT.bin beside
// it, which may be the input's buffer (scene.gltf reading data.bin, written as data.gltf).
void check_not_source(const Scene& scene, const std::string& output, bool force);

}  // namespace lod::cli
