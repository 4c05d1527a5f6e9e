// lodkit: the edge-collapse simplifier (Garland–Heckbert quadrics and its family of metrics).
//
//   lod::SimplifyResult r = lod::simplify(mesh, {.target_ratio = 0.1f});
//
// Topology is that of position ids (lod::position_ids): vertices that share a position but differ in
// attributes (a UV seam, a hard normal, a material border) are "wedges" of one position and move
// together; seams only collapse along themselves. Every collapse is recorded, so the result can be
// replayed from the input or undone back to it (progressive meshes are built from this record).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "lodkit/mesh.h"

namespace lod {

// The cost of contracting a pair, pluggable; all share one engine and one set of safety checks.
enum class Metric : uint8_t {
  // edge_length and qem have no border term: borders then only collapse along themselves, and an
  // interior position collapsing into a border one leaves it in place (as seams).
  edge_length,  // squared edge length, midpoint placement ("SEM"): fastest, loses thin parts first
  qem,          // Garland–Heckbert quadrics, area-weighted face planes
  // qem plus planes perpendicular to the face through each border edge: the default, since plain
  // face planes let border corners slide on flat parts (a half cylinder lost 4% of its diagonal).
  constrained_qem,
  memoryless,       // Lindstrom–Turk: quadrics rebuilt from the current faces, volume and border kept
  constrained_memoryless,  // memoryless plus the border planes of constrained_qem
};
const char* metric_name(Metric metric);  // "edge", "qem", "cqem", "memoryless", "cmemoryless"

struct SimplifyOptions {
  // Stop at whichever is reached first. A target of 0 triangles with no error limit simplifies as far
  // as the safety checks allow.
  float target_ratio = 1.0f;         // fraction of the input triangles to keep, in [0, 1]
  uint64_t target_triangles = 0;     // used instead of target_ratio when non-zero
  float max_error = -1.0f;           // object-space distance; < 0 means no limit
  float max_relative_error = -1.0f;  // fraction of the bounding-box diagonal; < 0 means no limit

  Metric metric = Metric::constrained_qem;
  // Subset placement: the result uses only input vertices (LODs can share one vertex buffer).
  bool keep_vertices = false;

  // Attribute quadrics (Hoppe 1999). Weights are relative to positions scaled so that the bounding
  // box's largest extent is 1; normals are unit, UVs and colours are taken as they are. 0 ignores the
  // attribute (it is then interpolated along with the collapse, never optimised).
  float normal_weight = 0.0f;
  float uv_weight = 0.0f;     // applies to every UV set
  float color_weight = 0.0f;  // RGBA

  // Constrained metrics: border-plane weight, times the border edge's squared length. 3 keeps a
  // hole's border vertices from drifting apart at 1%: corpus, Hausdorff distance over the best peer
  // 0.843 -> 0.809 in geometric mean at 1% (worst 1.59x -> 1.33x), RMS 0.706 -> 0.714; weights
  // of 1 to 16 are compared in bench/README (fifteenth session).
  float border_weight = 3.0f;

  // Safety. A collapse is rejected if any face around it would turn by more than the angle whose
  // cosine is min_normal_dot, would become degenerate, or (when max_aspect_ratio > 0) would have a
  // longest-edge / shortest-altitude ratio above it.
  float min_normal_dot = 0.2f;
  float max_aspect_ratio = 0.0f;
  // Distance guard (qem and cqem): a collapse waits while the input point of either end of its
  // edge would end farther from the faces around it than sqrt(distance_guard * level), level being
  // the quadric cost the current pass's collapses reach (a mean squared distance). Quadrics average
  // over their planes, so a thin part (a spike, an antler) can cost almost nothing to remove; the
  // guard holds such collapses back until the rest of the mesh has reached that error. Chosen on the
  // corpus among 2 to 64: lodkit's Hausdorff distance at most the better of CGAL's and
  // meshoptimizer's on 81% instead of 71% of the cases at 10%, 71% instead of 59% at 1%
  // (scripts/bench.sh simplify --requality, with the measure's sliver fixes), for about 7% more
  // time. 0 turns it off.
  float distance_guard = 6.0f;
  bool lock_border = false;                // border positions never move
  std::vector<uint8_t> locked;             // per input vertex: non-zero means its position never moves
  std::vector<float> importance;           // per input vertex: multiplies the cost of moving it (>= 0)

  // Aggregation (Garland–Heckbert "virtual pairs"): positions closer than this object-space distance
  // that share no edge may also be contracted, which merges separate parts (foliage, debris). The
  // parts then meet at one non-manifold position, which later edge collapses leave in place. Pairs
  // are found with a uniform grid, up to `aggregate_neighbours` nearest per position. 0 disables.
  float aggregate_distance = 0.0f;
  uint32_t aggregate_neighbours = 8;
  // Drop connected components whose bounding-box diagonal is below the error reached. Done after
  // the collapses: the record (and replay) describe the mesh before pruning.
  bool prune = false;

  // After the collapses, fit the surviving positions to the input surface by at most this many
  // least-squares iterations (Hoppe et al. 1993's vertex step; see src/simplify/fit.h). The fit
  // stops earlier once an iteration moves no position by more than 0.1% of the mean edge length.
  // 0 keeps the collapse placements. Not done with keep_vertices (positions are input vertices
  // there), on locked positions, or when the collapses' error is below 1e-6 of the bounding-box
  // diagonal (the result then lies on the input already).
  uint32_t fit_iterations = 12;
  // Before the fit's first step, flip edges whose other diagonal lies nearer the input (Hoppe et
  // al.'s flip step; the triangles keep their ids, each changes one corner). Part of the fit.
  bool fit_flips = true;
  // The weight of the fit's edge term, which pulls the midpoints of the result's edges towards the
  // input, most strongly the farthest (src/simplify/fit.h): it trades a little RMS distance for
  // Hausdorff distance. 0: a plain least-squares fit of the input's samples.
  float fit_edge_weight = 0.1f;

  // Search, for coarse results of small inputs (qem and cqem with a triangle target of at most
  // search_output_triangles, an input of at most search_input_triangles, no error limit and no
  // aggregation): the distance guard's best strength depends on the mesh, and far down the
  // memoryless form of the metric sometimes keeps the shape better, and the fit's edge term and
  // flips, which help most meshes, cost some. So the input is simplified up to five ways: as set,
  // with distance_guard 0, with 2, with the memoryless metric of the same family, and (when the fit
  // runs) with a plain fit: no flips, fit_edge_weight 0. The result nearest the input by symmetric
  // Hausdorff distance (lod::compare with its own sample seed) is kept, provided it has no more
  // triangles than the first way's or the target; ties go to the earlier way. With several threads
  // the ways run side by side. About 8x the time on one thread; on the corpus at 1%, Hausdorff at
  // most the better peer's on 92% of the cases instead of 80% (bench/README, nineteenth and
  // twenty-third sessions). Either limit 0: off, the options exactly as set.
  uint64_t search_input_triangles = uint64_t(1) << 15;
  uint64_t search_output_triangles = uint64_t(1) << 10;

  // Record every collapse in SimplifyResult::record (needed for replay, undo and progressive meshes).
  bool record = true;

  unsigned threads = 0;  // 0: one per hardware thread. The result never depends on it.
  std::function<void(double fraction)> progress;  // fraction of the planned collapses done
};

// One contraction of position `removed` into position `kept`. Face and wedge details live in the
// SimplifyRecord arrays, in the ranges given here. Indices refer to the input mesh.
struct Collapse {
  uint32_t kept = 0, removed = 0;  // position ids (lod::position_ids of the input)
  float3 old_position, new_position;
  float error = 0;                   // object-space error of this collapse (sqrt of the quadric cost)
  uint32_t faces_begin = 0;          // into SimplifyRecord::removed_faces
  uint32_t removed_face_count = 0;
  uint32_t relinks_begin = 0;        // into SimplifyRecord::relinks
  uint32_t relink_count = 0;
  uint32_t wedges_begin = 0;         // into SimplifyRecord::wedges
  uint32_t wedge_count = 0;
  uint32_t moved_begin = 0;          // into SimplifyRecord::moved_wedges
  uint32_t moved_count = 0;          // non-zero only for virtual pairs (no shared faces)
};

// A triangle corner that pointed at a wedge of `removed` and now points at one of `kept`.
struct Relink {
  uint32_t triangle = 0;
  uint32_t corner = 0;  // 0..2
  uint32_t from = 0, to = 0;  // input vertex indices
};

// A wedge of `kept` whose attributes were recomputed. Values are packed per SimplifyRecord::stride
// (normals 3, then each UV set 2, then colour 4, for the attributes the mesh has).
struct WedgeChange {
  uint32_t vertex = 0;        // input vertex index
  uint32_t values_begin = 0;  // into SimplifyRecord::old_values / new_values
};

// A position moved by the final fit (SimplifyOptions::fit_iterations), after every collapse.
struct FittedPosition {
  uint32_t position = 0;  // position id (lod::position_ids of the input)
  float3 old_position, new_position;
};

// Joints and weights of one position, as lod::simplify_skinned's multi-pose mode chooses them:
// slots 0-3 are JOINTS_0 / WEIGHTS_0, slots 4-7 JOINTS_1 / WEIGHTS_1 (a mesh with a second set);
// heaviest first, unused slots weight 0 on joint 0.
inline constexpr int max_influences = 8;
struct Influences {
  uint16_t joint[max_influences] = {};
  float weight[max_influences] = {};
  friend bool operator==(const Influences&, const Influences&) = default;
};

// A collapse's change to the influences of its kept position (every wedge of it takes `new_value`).
// `old_value` with all weights 0: the wedges still had their own, the input's.
struct InfluenceChange {
  Influences old_value, new_value;
};

struct SimplifyRecord {
  std::vector<Collapse> collapses;  // in the order they were applied
  // One per collapse when the simplification chose the survivors' joints and weights (multi-pose
  // skinned simplification), else empty.
  std::vector<InfluenceChange> influences;
  // Applied after the last collapse (replay of all collapses ends with them; undo starts with them).
  // Progressive meshes play collapses only: their coarsest level is the mesh before the fit.
  std::vector<FittedPosition> fitted;
  // The fit's edge flips, applied before its moves: two corner relinks per flip (one per face).
  std::vector<Relink> flipped;
  std::vector<uint32_t> removed_faces;
  std::vector<Relink> relinks;
  std::vector<WedgeChange> wedges;
  // Virtual pairs keep every corner's wedge: the wedges (input vertices) of `removed` move to `kept`.
  std::vector<uint32_t> moved_wedges;
  std::vector<float> old_values, new_values;
  uint32_t stride = 0;  // floats per wedge change
};

struct SimplifyResult {
  Mesh mesh;  // compacted: only live triangles and the vertices they use, in order of first use
  std::vector<uint32_t> vertex_origin;  // per output vertex: the input vertex it continues
  std::vector<uint32_t> triangle_origin;  // per output triangle: its input triangle
  // Per input vertex: the output vertex it continues as or was merged into (a wedge of the position
  // its own collapsed into, the one its triangles' corners were moved to); ~0u when it left with its
  // triangles. The input triangles around an output vertex's successors are where it came from
  // (lod::vertex_blends).
  std::vector<uint32_t> vertex_successor;

  float error = 0;           // largest collapse error, object space (a distance)
  float relative_error = 0;  // error / bounding-box diagonal of the input
  float diagonal = 0;        // bounding-box diagonal of the input

  SimplifyRecord record;

  uint64_t input_triangles = 0, output_triangles = 0;
  uint64_t input_vertices = 0, output_vertices = 0;
  uint64_t collapses = 0;
  uint64_t virtual_pairs = 0;  // collapses that joined two positions without a shared face (aggregation)
  uint64_t rejected_topology = 0, rejected_flip = 0, rejected_seam = 0, rejected_shape = 0;
  uint64_t deferred_distance = 0;  // collapses the distance guard held back (each time it did)
  uint64_t pruned_triangles = 0;
  uint64_t fitted_positions = 0;  // positions the final fit moved
  uint64_t flipped_edges = 0;     // edges the final fit flipped
  uint32_t fit_iterations = 0;    // iterations the final fit ran (at most SimplifyOptions::fit_iterations)
  uint32_t passes = 0;
  // The way this result was made (the search, SimplifyOptions::search_input_triangles): out of how
  // many tried (1 without a search), with which metric, distance guard and fit options, and its
  // measured Hausdorff distance over the diagonal (0 when there was no search).
  uint32_t search_ways = 1;
  Metric metric = Metric::constrained_qem;
  float distance_guard = 0;
  bool fit_flips = true;
  float fit_edge_weight = 0;
  double search_hausdorff = 0;
  // Wall-clock time: setting up, the collapses, the final fit (0 without one), and the whole call
  // (these, building the output mesh and, with a search, the other ways and the measures).
  double seconds_setup = 0, seconds_collapse = 0, seconds_fit = 0, seconds_total = 0;
  // seconds_collapse by step, summed over the passes (they add up to it, less a few loop ends):
  //   stars     building the per-position stars of the live triangles;
  //   ranking   the quadrics (first pass; memoryless metrics every pass) and each position's
  //             cheapest edge, where a collapse changed it;
  //   ordering  picking and sorting the pass's candidates;
  //   checks    choosing the candidates to check together and checking them, on all threads;
  //   applying  the collapses, in cost order on one thread (with the checks of candidates held
  //             back from the parallel ones).
  struct CollapseSteps {
    double stars = 0, ranking = 0, ordering = 0, checks = 0, applying = 0;
    // The steps by name, in order (for reports).
    std::array<std::pair<const char*, double>, 5> named() const {
      return {{{"stars", stars}, {"ranking", ranking}, {"ordering", ordering}, {"checks", checks}, {"applying", applying}}};
    }
    CollapseSteps& operator+=(const CollapseSteps& o) {
      stars += o.stars, ranking += o.ranking, ordering += o.ordering, checks += o.checks, applying += o.applying;
      return *this;
    }
  } seconds_steps;
};

// Simplifies `mesh` (which must pass lod::validate). Throws lod::Error (usage) on invalid options.
// Input triangles with two corners on one position (zero area, such as the pole rows of a UV
// sphere) leave with the first collapse, among its removed faces; with no collapse they stay.
SimplifyResult simplify(const Mesh& mesh, const SimplifyOptions& options = {});

// Several meshes at once (a scene's), each result exactly simplify(*meshes[i], options[i]) (so on
// any thread count): small meshes (under 32,768 triangles) side by side, one thread each, larger
// ones one at a time on `threads` (0: all; each options' threads is ignored). `progress` (may be
// empty) covers the whole batch, by triangles; each options' progress is ignored. Pointers, so that
// meshes held elsewhere need not be copied.
std::vector<SimplifyResult> simplify_batch(std::span<const Mesh* const> meshes, std::span<const SimplifyOptions> options,
                                           unsigned threads = 0, const std::function<void(double)>& progress = {});

// Applies the first `count` collapses of `record` to `mesh` (the input of the simplify call that made
// it) and returns the compacted result, identical to SimplifyResult::mesh when count is all of them.
Mesh replay(const Mesh& mesh, const SimplifyRecord& record, size_t count);
// Applies all collapses, then undoes them as vertex splits in reverse order: gives back `mesh`
// exactly (bit for bit, including triangle order and winding). For tests and progressive meshes.
Mesh replay_and_undo(const Mesh& mesh, const SimplifyRecord& record);

// ---- data the simplifier does not carry -----------------------------------------------------------
// A result vertex as a point of an input triangle: its three vertices and barycentric weights (summing
// to 1). Per-vertex data the simplifier does not model (glTF morph targets, extra attributes) can be
// interpolated there.
struct VertexBlend {
  std::array<uint32_t, 3> vertex{};  // input vertices
  std::array<float, 3> weight{};
};
// Per output vertex: the point nearest its position among the input triangles that have a corner
// whose SimplifyResult::vertex_successor is that vertex, that is, the patch of the input it replaces
// (not the nearest point of the whole input: across a thin part, such as lips or an eyelid, that
// would lie on the other side). Within a thousandth of the diagonal of that point, a triangle with a
// corner that became this very vertex (its side of a seam) is preferred, else one facing the output
// vertex's normal (the side of a double-sided surface it is on, after restore_form). Ties go to the
// lower triangle id. Results of chained calls compose by following each call's vertex_successor in
// turn.
std::vector<VertexBlend> vertex_blends(const Mesh& input, std::span<const uint32_t> vertex_successor, const Mesh& output);

// ---- inputs in a form no collapse can touch -------------------------------------------------------
// Three kinds of input leave an edge collapse nothing to do as they come; `lodkit simplify` and
// `lodkit lod` prepare them this way, and so can a caller of simplify or build_lod_chain:
// - A triangle soup (a non-indexed glTF, an OBJ or PLY without shared vertices): the simplifier takes
//   copies of one position for a seam, which moves only as a whole. Weld it first, exactly:
//   lod::weld(mesh) (optimize.h), as gltfpack does.
// - Double-sided by duplication (foliage, cloth, paper): every triangle has a twin on the same
//   positions with the opposite winding, so every edge has four triangles, which no collapse may
//   touch. The fronts (the first of each pair) are simplified, and each result triangle gets its
//   twin again, normals negated and tangents' w flipped.
// - Flat shading: every triangle's corners share its one normal and some position has several (a
//   seam of copies everywhere). Those normals only say which way each face points: the mesh is
//   simplified without them, copies merged, and each result triangle gets its face normal again.
// Neither form applies to a result that must use input vertices (keep_vertices, a chain sharing one
// vertex buffer, geomorphs): the backs and face normals are new vertices.
struct SurfaceForm {
  bool double_sided = false;  // `mesh` holds the fronts
  bool flat_shaded = false;   // `mesh` holds no normals, its copies merged
  Mesh mesh;                  // what to simplify when either is set; else empty (simplify the input)
  // Per input vertex when either is set, for restore_form to map a result's vertex_successor: its
  // vertex in `mesh` (a back's: the vertex at the same corner of its front), whether only backs use
  // it, and when flat-shaded the face normal of its front side and the material of its first
  // triangle (if the input has materials).
  std::vector<uint32_t> source;
  std::vector<bool> back;
  std::vector<float3> facet;
  std::vector<uint32_t> material;

  bool changed() const { return double_sided || flat_shaded; }
  const Mesh& to_simplify(const Mesh& input) const { return changed() ? mesh : input; }
};
// Detects both forms (double-sided first; the fronts may then be flat-shaded). Linear time but for
// a sort-free hash check that rules out most meshes that are not double-sided.
SurfaceForm surface_form(const Mesh& mesh);
// Gives a simplified result its form back: face normals, then the backs. Does nothing when
// !form.changed(). `vertex_successor`, unless empty, goes in as the SimplifyResult's (per vertex of
// form.mesh) and comes out per input vertex: a front's successor, or the back copy of it for a back,
// and of a successor's faceted copies the one whose face normal is nearest the vertex's own, on a
// triangle of the vertex's material where there is one. So
// vertex_blends can carry per-vertex data the simplifier does not model (glTF morph targets) through
// a form too.
void restore_form(const SurfaceForm& form, Mesh& result, std::vector<uint32_t>& vertex_successor);

}  // namespace lod
