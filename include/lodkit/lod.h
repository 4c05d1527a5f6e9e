// lodkit: what the simplifier's output becomes in an application: a chain of discrete LODs with
// error bounds and geomorphs between them, and a progressive mesh (refine or coarsen to any size)
// with a file format that stores it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "lodkit/mesh.h"
#include "lodkit/optimize.h"
#include "lodkit/simplify.h"

namespace lod {

// ---- geomorphs ------------------------------------------------------------------------------------

// Where each vertex of a finer level goes in the next coarser one (Houle's correspondence table):
// `target[v]` is the coarser vertex that vertex v of the finer level becomes, chains of collapses
// already shortened (A -> B -> C is stored as A -> C). Attributes follow the same table, so a UV
// seam vertex moves to a vertex on its own side of the seam.
struct Geomorph {
  std::vector<uint32_t> target;  // per finer vertex: a coarser vertex index
  friend bool operator==(const Geomorph&, const Geomorph&) = default;
};

// m(a -> c) = m(b -> c) after m(a -> b).
Geomorph compose(const Geomorph& a_to_b, const Geomorph& b_to_c);

// The finer level morphed towards the coarser one: P' = (1 - t) P + t P_target, the same for UVs and
// colours, and normals renormalised. t = 0 gives `finer` bit for bit; t = 1 puts every vertex on its
// target, so the triangles of non-zero area are exactly the coarser level's and the rest have none.
Mesh morph(const Mesh& finer, const Mesh& coarser, const Geomorph& table, float t);
// Positions only, into `out` (resized): the per-frame work of a geomorph, without allocation.
void morph_positions(std::span<const float3> finer, std::span<const float3> coarser, const Geomorph& table, float t,
                     std::vector<float3>& out);

// ---- LOD chains -----------------------------------------------------------------------------------

struct LodOptions {
  // Fractions of the input's triangles, one per level, finest first (level 0 is usually 1: the
  // input). Empty: `levels` levels halving each time (1, 1/2, 1/4, ...).
  std::vector<float> ratios;
  uint32_t levels = 4;
  // Instead of ratios: each level's limit on its certified distance to the input (LodLevel::
  // error_bound), as a fraction of the bounding-box diagonal (finest first; 0 for the input itself:
  // a later 0 keeps only the simplifier's exact collapses). A level by error is searched for, each
  // try simplified to a triangle count and measured (the simplifier's own error, a quadric estimate,
  // is only the first try's stop): a few times the build time of ratios.
  std::vector<float> errors;
  // Each level simplified from the previous one (errors accumulate; needed for geomorphs) or from
  // the input.
  bool from_previous = true;
  // Subset placement, and one vertex buffer: SharedVertices orders it so each coarser level uses a
  // prefix. Attribute values then stay as they are (attribute weights are ignored).
  bool shared_vertices = false;
  // Geomorph tables between consecutive levels (needs from_previous).
  bool morph = false;
  // Measure each level against the input (lod::compare, with a certified bound from refinement).
  bool measure = true;
  // Reorder each level's triangles for the vertex cache and its vertices by first use
  // (lod::optimize_vertex_cache, lod::vertex_fetch_remap); geomorph tables follow.
  bool optimize = true;
  // The cache `optimize` orders for. An LRU order also suits meshoptimizer's codecs best
  // (EXT_meshopt_compression): `lodkit lod -c` asks for it.
  VertexCacheOptions cache;
  SimplifyOptions simplify;  // metric, attribute weights, locks, threads; the target fields are set per level
  // The simplifier each level is made with; empty: lod::simplify. Skinned chains pass
  // lod::simplify_skinned with their poses (levels are then measured in the bind pose).
  std::function<SimplifyResult(const Mesh&, const SimplifyOptions&)> simplifier;
  std::function<void(double fraction)> progress;
};

struct LodLevel {
  Mesh mesh;
  float ratio = 1;         // triangles / input triangles
  float engine_error = 0;  // the simplifier's error, accumulated along the chain (object space)
  // Symmetric Hausdorff distance to the input measured by lod::compare (Metro-style sampling).
  // With measure off, engine_error.
  float error = 0;
  // A certified upper bound on it (lod::compare's refinement to 1e-5 of the diagonal: typically a
  // few percent above `error`; looser only where the refinement budget ran out): the runtime's
  // e_obj and the switch distances. With measure off, engine_error (not certified).
  float error_bound = 0;
  float relative_error = 0;  // error / bounding-box diagonal
  // Per vertex: the input vertex it continues (for streams the Mesh does not hold, such as a glTF
  // primitive's morph targets).
  std::vector<uint32_t> vertex_origin;
  // Per input vertex: the level's vertex it became (SimplifyResult::vertex_successor along the
  // chain; ~0u for none). lod::vertex_blends(input, vertex_successor, mesh) interpolates those
  // streams at vertices that moved.
  std::vector<uint32_t> vertex_successor;
};

// With shared_vertices: one vertex buffer for all levels, and per level its indices into it; level i
// uses only the first `prefix[i]` vertices.
struct SharedVertices {
  Mesh vertices;  // streams only (no indices)
  // Per buffer vertex: the input vertex it is (for streams the Mesh does not hold, such as a glTF
  // primitive's morph targets, which subset placement leaves exact).
  std::vector<uint32_t> vertex_origin;
  std::vector<std::vector<uint32_t>> indices;
  std::vector<uint32_t> prefix;
};

struct LodChain {
  std::vector<LodLevel> levels;    // finest first
  std::vector<Geomorph> morphs;    // morphs[i]: level i -> level i + 1 (with LodOptions::morph)
  SharedVertices shared;           // with LodOptions::shared_vertices
  float diagonal = 0;              // of the input's bounding box
};

// Throws lod::Error (usage) on invalid options.
LodChain build_lod_chain(const Mesh& mesh, const LodOptions& options = {});

// One chain per mesh, each exactly build_lod_chain(*meshes[i], options): the meshes of a scene, say.
// Small meshes (under 32,768 triangles) are built side by side, one thread each, larger ones one at
// a time on options.simplify.threads; options.simplifier, if set, is then called from several
// threads at once. Pointers, so that meshes held elsewhere need not be copied; progress covers the
// whole batch.
std::vector<LodChain> build_lod_chains(std::span<const Mesh* const> meshes, const LodOptions& options = {});

// ---- popping --------------------------------------------------------------------------------------

// A camera flies past a LOD chain (with geomorph tables) along a straight line, from where the
// coarsest level shows to closer than the finest level's switch point and away on the other side,
// looking at the object; a LodRuntime picks the levels each frame. Per frame, the largest screen
// displacement of the drawn surface against the previous frame is measured, both frames seen from
// the current camera (so camera motion does not count): every vertex of the finest level is
// followed through its collapses to where it is drawn (its image in the drawn level, morphed by t),
// and its displacement across the surface (along the finest level's vertex normal: sliding along
// the surface changes nothing on screen) is projected at its distance from the eye. Visibility is
// ignored (hidden vertices count too).
struct PoppingOptions {
  double error_px = 1;             // the runtime's threshold (RuntimeOptions::error_px)
  double screen_height = 1080;     // pixels
  double fov = 1.0471975511965976; // vertical, radians
  double fps = 60;
  double transition_seconds = 1;   // geomorph duration; the hard-switch run uses 0
  double transition_zone = 0.25;
  double flight_seconds = 20;      // frames = fps * flight_seconds
};
struct PoppingRun {
  double max_px = 0;               // largest per-frame displacement, pixels
  double mean_px = 0;              // over frames that moved at all
  uint32_t frames = 0, moving_frames = 0;
  uint32_t level_changes = 0;      // drawn-level swaps
  std::vector<float> per_frame_px; // one per frame
};
struct PoppingResult {
  PoppingRun geomorph, hard;
};
// Throws usage if the chain has no geomorph tables (build it with LodOptions::morph).
PoppingResult measure_popping(const LodChain& chain, const PoppingOptions& options = {});

// The distance at which a level's error reaches `pixels` on screen: e_px = e_obj * H / (2 d tan(fov/2))
// solved for d. fov in radians (vertical), H in pixels.
double switch_distance(double object_error, double pixels, double screen_height, double fov);

// A progressive mesh (Hoppe 1996) built from a collapse record: the coarsest mesh plus, read
// backwards, one vertex split per collapse. Moving to a size applies or undoes collapses from the
// current state, so a sweep costs what it changes. At k collapses the mesh is exactly the
// simplifier's (lod::replay(input, record, k)).
//
// Sizes count unique positions, as the simplifier does (one collapse removes one position; vertices
// split at seams move with their position).
class ProgressiveMesh {
 public:
  ProgressiveMesh();
  // `record` must be the record of simplifying `input` (validated: usage error if an index is out
  // of range). Starts fully refined (the input).
  ProgressiveMesh(Mesh input, SimplifyRecord record);
  ~ProgressiveMesh();
  ProgressiveMesh(ProgressiveMesh&&) noexcept;
  ProgressiveMesh& operator=(ProgressiveMesh&&) noexcept;

  size_t collapse_count() const;     // collapses in the record
  size_t collapses_applied() const;  // 0: the input, collapse_count(): the base mesh
  uint32_t max_positions() const;    // unique positions of the input
  uint32_t min_positions() const;    // of the base mesh
  uint32_t positions() const;        // now

  // Applies or undoes collapses until `collapses_applied() == k` (clamped to the record).
  void set_collapses(size_t k);
  // To `n` unique positions, clamped to [min_positions(), max_positions()]. refine_to never
  // coarsens and coarsen_to never refines: they leave a mesh already past `n` as it is.
  void refine_to(uint32_t n);
  void coarsen_to(uint32_t n);

  // The current mesh, compacted as the simplifier's output: live triangles in input order and the
  // vertices they use in order of first use.
  Mesh mesh() const;

  const Mesh& input() const;
  const SimplifyRecord& record() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// `.lpm`: a versioned little-endian binary file holding a progressive mesh (its input mesh and
// collapse record) with a CRC-32 of the payload. The reader rejects wrong magic, unknown versions,
// truncation, counts that exceed the bytes present, bad checksums and records that do not belong to
// the mesh, with the byte offset; it never allocates more than the file's size implies.
void write_progressive_mesh(const ProgressiveMesh& pm, const std::filesystem::path& path);
std::string encode_progressive_mesh(const ProgressiveMesh& pm);
ProgressiveMesh read_progressive_mesh(const std::filesystem::path& path);
ProgressiveMesh decode_progressive_mesh(std::span<const uint8_t> bytes, const std::string& name);

}  // namespace lod
