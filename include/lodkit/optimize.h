// lodkit: consolidation for the GPU. Weld duplicate vertices, make the winding consistent, order
// triangles for the post-transform vertex cache and vertices for fetch locality, build triangle
// strips, and measure all of it.
//
// Index-buffer functions take and return plain `uint32_t` triangle lists (3 indices per triangle) so
// they work on any vertex layout; the `Mesh` functions carry every vertex and per-triangle stream.
// No function here changes the set of triangles: reordering keeps each triangle's corner order, and
// the strip decoder gives back exactly the encoded triangles with their winding.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "lodkit/mesh.h"

namespace lod {

// ---- weld -----------------------------------------------------------------------------------------
// Merges duplicate vertices. With every tolerance 0 the weld is exact: vertices merge when all their
// streams are bitwise equal (+0.0 and -0.0 count as equal). A positive `position_tolerance` welds
// positions closer than it (Euclidean, object space) through a spatial hash; each attribute is then
// compared with its own tolerance (largest per-component difference), so UV seams and hard normals stay
// split unless their tolerances are raised or `ignore_attributes` is set.
//
// The weld is greedy in vertex order: a vertex joins the first earlier kept vertex that matches it, so
// every vertex ends within the tolerances of the vertex it became, and the result never depends on
// anything but the input. The kept vertex keeps its own values (nothing is averaged).
struct WeldOptions {
  float position_tolerance = 0;  // object space; 0: bitwise equal positions
  float normal_tolerance = 0;    // per component of unit normals; 0: bitwise
  float tangent_tolerance = 0;   // per component, handedness (w) must be equal
  float uv_tolerance = 0;        // per component, UV units
  float color_tolerance = 0;     // per component, linear RGBA
  float weight_tolerance = 0;    // per skin weight; joints must be equal
  // Weld by position alone: the first vertex's attributes win, so seams and hard edges disappear.
  bool ignore_attributes = false;
  // Remove triangles that lost a corner to the weld (two corners became one vertex). Counted either way.
  bool remove_degenerate = false;
  // Empty, or one per input vertex: vertices merge only within one class, whatever the tolerances and
  // ignore_attributes say. For streams the Mesh does not hold, such as a glTF primitive's morph
  // targets (lod::source_vertex_classes): merging vertices whose targets differ would move them
  // together in every blend shape.
  std::span<const uint32_t> vertex_classes;
};

struct WeldResult {
  Mesh mesh;                   // the welded mesh: kept vertices in order of first appearance
  std::vector<uint32_t> remap;  // input vertex -> output vertex
  uint64_t input_vertices = 0, output_vertices = 0;
  uint64_t degenerate_triangles = 0;  // triangles with two corners on one output vertex (removed or not)
};
WeldResult weld(const Mesh& mesh, const WeldOptions& options = {});

// ---- orientation ----------------------------------------------------------------------------------
// Makes the winding consistent: a breadth-first walk per connected part, across manifold edges (two
// triangles; topology on position ids, so seams do not cut), flips every triangle that disagrees with
// the triangle it was reached from. A closed part is then turned outward (positive signed volume); an
// open part keeps the winding of the larger area of its input triangles (the fewest changes). A part
// that cannot be wound consistently (a Möbius strip) keeps its walk's winding, which leaves a seam of
// disagreeing edges, and is counted as a warning: never an error.
struct OrientOptions {
  bool outward = true;  // turn closed parts outward (false: only make the winding consistent)
};

struct OrientResult {
  Mesh mesh;
  uint64_t flipped_triangles = 0;
  uint64_t components = 0;         // parts connected across manifold edges
  uint64_t closed_components = 0;  // no boundary or non-manifold edge
  uint64_t turned_outward = 0;     // closed parts whose whole winding was reversed to face outward
  uint64_t non_orientable_components = 0;  // the warning: Möbius-like parts
  uint64_t non_manifold_edges = 0;         // edges of three or more triangles (the walk does not cross them)
};
OrientResult orient(const Mesh& mesh, const OrientOptions& options = {});

// ---- post-transform vertex cache ------------------------------------------------------------------
enum class CachePolicy {
  fifo,  // a miss pushes the vertex in, the oldest leaves; a hit changes nothing (most GPUs)
  lru,   // a hit also moves the vertex to the front
};
const char* cache_policy_name(CachePolicy policy);

struct VertexCacheOptions {
  uint32_t cache_size = 16;  // entries (vertices), 3 or more
  CachePolicy policy = CachePolicy::fifo;
  // The order also feeds EXT_meshopt_compression's index codec (lodkit -c). With an LRU cache the
  // order is then the one whose indices the codec codes in the fewer bytes, of the input's and the
  // greedy walk's under a scoring that puts the last triangle's vertices first, so that the walk
  // runs in strips (the codec codes a triangle on an edge of a recent one in a few bits): 17% fewer
  // index bytes than the walk for the cache on refined_elephant, 27% fewer than Tipsify.
  bool index_codec = false;
};

// Reorders triangles (each keeps its corner order) for fewer misses on the given cache. Three orders
// are made and the best on that cache kept (so never worse than the input): the input's own; Tipsify
// (Sander et al. 2007); and for a FIFO lodkit's fan orderer (fans around one vertex at a time, the
// next centre being the cached vertex whose fan costs fewest misses per triangle in the simulated
// FIFO), for an LRU a Forsyth-style greedy walk. For a FIFO and an input of at most 1,024 triangles,
// the fan orderer also starts from the input's first vertex, in Tipsify's place. Linear time; the
// same input gives the same order.
// Returns the new index buffer.
std::vector<uint32_t> optimize_vertex_cache(std::span<const uint32_t> indices, size_t vertex_count,
                                            const VertexCacheOptions& options = {});
// The same order as a triangle permutation: result[k] = input triangle emitted k-th.
std::vector<uint32_t> vertex_cache_order(std::span<const uint32_t> indices, size_t vertex_count,
                                         const VertexCacheOptions& options = {});

// ---- overdraw -------------------------------------------------------------------------------------
// Reorders triangles so that those likely to hide others are drawn first, for fewer shaded fragments
// that a later triangle covers. The input should already be in vertex-cache order: it is cut into
// runs of consecutive triangles (clusters: at least a given size, then ending before the next triangle
// with two or more corners missing the simulated FIFO), and the clusters are sorted by a
// view-independent occlusion potential (how far each lies out from the mesh's centroid along its mean
// normal, largest first), keeping each cluster's own order. The smallest size in 16, 32, 64, ...
// whose order needs at most `threshold` times the input order's FIFO misses is used; if none does,
// the input order is returned. Each triangle keeps its corner order; the same input gives the same
// order. Returns the new index buffer.
struct OverdrawOrderOptions {
  uint32_t cache_size = 16;  // FIFO entries the miss bound is measured on
  float threshold = 1.05f;   // allowed misses relative to the input order (1: no more misses)
};
std::vector<uint32_t> optimize_overdraw(std::span<const uint32_t> indices, std::span<const float3> positions,
                                        const OverdrawOrderOptions& options = {});
// The same order as a triangle permutation: result[k] = input triangle drawn k-th.
std::vector<uint32_t> overdraw_order(std::span<const uint32_t> indices, std::span<const float3> positions,
                                     const OverdrawOrderOptions& options = {});

// ---- vertex fetch ---------------------------------------------------------------------------------
// Renumbers vertices in order of first use by the index buffer, so the vertex shader reads memory
// nearly in sequence. Returns old vertex -> new vertex; vertices no triangle uses go last, in their
// input order.
std::vector<uint32_t> vertex_fetch_remap(std::span<const uint32_t> indices, size_t vertex_count);

// ---- strips ---------------------------------------------------------------------------------------
enum class StripMethod {
  sgi,   // the course's SGI algorithm: start at a triangle with the fewest free neighbours, grow one
         // strip through each of them, keep the longest, repeat
  best,  // lodkit's: a greedy walk that turns with a swap (one repeated index) instead of ending the
         // strip, prefers the neighbour that would otherwise be stranded, and starts new strips in a
         // vertex-cache order; the shortest of that, the same in input order, and SGI is kept
};
const char* strip_method_name(StripMethod method);

struct StripOptions {
  StripMethod method = StripMethod::best;
  // Strips are joined by a restart index (true) or by repeated indices that make degenerate
  // triangles (false).
  bool use_restart = false;
  uint32_t restart_index = 0xFFFFFFFFu;
  uint32_t cache_size = 16;  // best: the FIFO cache its triangle order is optimised for
};

struct Strips {
  std::vector<uint32_t> indices;  // one buffer: the strips with their joins
  uint64_t strips = 0;            // strips joined in the buffer
  uint64_t triangles = 0;         // encoded (non-degenerate) triangles
  uint64_t dropped_degenerate = 0;  // input triangles with a repeated index: they draw nothing and are left out
  bool use_restart = false;
  uint32_t restart_index = 0xFFFFFFFFu;
  std::vector<uint32_t> triangle_order;  // input triangles in the order the strips draw them
};
Strips stripify(std::span<const uint32_t> indices, size_t vertex_count, const StripOptions& options = {});

// Appends `more` to `into` with `into`'s join (a restart index, or repeated indices that keep the
// winding parity), so strips of several index ranges make one buffer. Both must use the same join.
// `more.triangle_order` follows its buffer (reversed when the buffer is, to save a join index); it is
// not renumbered, so renumber it first if it counts from another base.
void append_strips(Strips& into, const Strips& more);

// Decodes a strip buffer to a triangle list: every triangle with three distinct indices, with the
// strip's alternating winding undone (triangle k of a strip is (v[k], v[k+1], v[k+2]) for even k and
// (v[k+1], v[k], v[k+2]) for odd k). With `use_restart`, `restart_index` starts a new strip.
std::vector<uint32_t> unstripify(std::span<const uint32_t> strip, bool use_restart = false,
                                 uint32_t restart_index = 0xFFFFFFFFu);

// ---- analyzers ------------------------------------------------------------------------------------
struct VertexCacheStats {
  uint64_t triangles = 0;
  uint64_t misses = 0;              // vertex shader invocations
  uint64_t referenced_vertices = 0;  // distinct vertices the triangles use
  double acmr = 0;  // average cache miss ratio: misses per triangle (0.5 is the ideal for large regular meshes)
  double atvr = 0;  // average transform to vertex ratio: misses per referenced vertex (1 is ideal)
};
// Simulates the cache over a triangle list.
VertexCacheStats analyze_vertex_cache(std::span<const uint32_t> indices, size_t vertex_count,
                                      const VertexCacheOptions& options = {});

struct VertexFetchOptions {
  uint32_t vertex_size = 32;    // bytes per vertex (position, normal, uv as floats)
  uint32_t line_size = 64;      // bytes per memory cache line
  uint32_t cache_lines = 128;   // lines in the simulated (direct-mapped) fetch cache
  uint32_t vertex_cache_size = 16;  // only post-transform cache misses fetch (FIFO of this size)
};
struct VertexFetchStats {
  uint64_t bytes_fetched = 0;
  // bytes fetched / bytes of the referenced vertices: 1 when every vertex is read once, line by line.
  double overfetch = 0;
};
VertexFetchStats analyze_vertex_fetch(std::span<const uint32_t> indices, size_t vertex_count,
                                      const VertexFetchOptions& options = {});

// Overdraw measured by rasterising the triangles in order with a depth buffer (less-than test,
// counter-clockwise front faces, back faces culled) in square orthographic views of the mesh's
// bounding sphere, pixel centres sampled, and summing over the views.
struct OverdrawOptions {
  uint32_t resolution = 256;   // pixels along each side of a view
  bool diagonal_views = true;  // view along the 8 cube diagonals besides the 6 axis directions
};
struct OverdrawStats {
  uint64_t pixels_covered = 0;  // pixels some front face covers, over all views
  uint64_t pixels_shaded = 0;   // fragments that pass the depth test (each is shaded), over all views
  double overdraw = 0;          // shaded / covered: 1 when no covered pixel is shaded twice
};
OverdrawStats analyze_overdraw(std::span<const uint32_t> indices, std::span<const float3> positions,
                               const OverdrawOptions& options = {});

struct StripStats {
  uint64_t indices = 0;     // including joins and restart indices
  uint64_t strips = 0;      // runs between restart indices, or between degenerate joins
  uint64_t triangles = 0;   // non-degenerate triangles
  uint64_t degenerate_triangles = 0;
  double indices_per_triangle = 0;
};
StripStats analyze_strips(std::span<const uint32_t> strip, bool use_restart = false, uint32_t restart_index = 0xFFFFFFFFu);

// ---- the whole consolidation on a Mesh ------------------------------------------------------------
struct OptimizeOptions {
  bool weld = false;
  WeldOptions weld_options;
  bool orient = false;
  OrientOptions orient_options;
  VertexCacheOptions cache;  // triangles are always reordered for this cache
  bool strips = false;       // also build strips; the mesh's triangles then follow the strip order
  StripOptions strip_options;
  // After the cache order, the overdraw order (optimize_overdraw, per material, its miss bound on a
  // FIFO of cache.cache_size entries); not with strips.
  bool overdraw = false;
  float overdraw_threshold = 1.05f;  // allowed FIFO misses relative to the cache order (1: no more)
  bool vertex_fetch = true;  // renumber vertices by first use
};

struct OptimizeResult {
  Mesh mesh;
  // Each output vertex's input vertex (the first of those welded into it): carries streams the Mesh
  // does not hold, such as a glTF primitive's morph targets (Primitive::source_vertices).
  std::vector<uint32_t> source_vertices;
  WeldResult weld;      // when welded (its mesh is moved out, remap kept)
  OrientResult orient;  // when oriented (its mesh is moved out)
  Strips strips;        // when strips were built, over the output mesh's vertices
  VertexCacheStats cache_before, cache_after;  // on options.cache
  // Wall-clock seconds per step (0 for a step not run); `order` is the cache order or the strips.
  // `overdraw` is the overdraw pass alone (also counted in `order`).
  double weld_seconds = 0, orient_seconds = 0, order_seconds = 0, fetch_seconds = 0, overdraw_seconds = 0;
};
// Triangles of different materials are kept apart: they are sorted by material (stably) and each
// material's range is ordered on its own, since each is drawn by its own call.
OptimizeResult optimize(const Mesh& mesh, const OptimizeOptions& options = {});

// Permutes a mesh's triangles (indices, materials, groups): triangle k of the result is input triangle
// order[k]. Renumbers its vertices: vertex remap[v] of the result is input vertex v (remap must be a
// permutation or map onto fewer vertices; the first vertex mapped onto a slot supplies it).
Mesh reorder_triangles(const Mesh& mesh, std::span<const uint32_t> order);
Mesh remap_vertices(const Mesh& mesh, std::span<const uint32_t> remap, size_t new_vertex_count);

}  // namespace lod
