// lodkit: choosing LOD levels at run time. A game loop registers objects (a bounding sphere and,
// per level, an object-space error bound and a triangle count: no meshes) and calls
// LodRuntime::update once per frame; it returns, per object, the level to draw and, during a
// transition, the coarser level it morphs towards and the morph parameter t (a geomorph,
// lod::morph_positions with LodChain::morphs[level]).
//
// Selection is by screen-space error (Houle 2000, section 3.3: screen size, not plain distance):
// draw the coarsest level whose error on screen stays within a pixel threshold. Switches happen in
// transition zones just on the safe side of each switch point, with hysteresis against objects that
// hover at a threshold, and the morph parameter moves at most dt / transition_seconds per frame, so
// an object never pops; it reverses where it is when the object goes back. A global triangle budget
// coarsens where it costs the least screen-space error per triangle removed.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "lodkit/mesh.h"

namespace lod {

struct LodChain;

// ---- screen-space error ---------------------------------------------------------------------------

// The size on screen, in pixels, of an object-space error `object_error` seen at `distance` by a
// perspective camera with vertical field of view `fov` (radians) on a screen `screen_height` pixels
// high: e_px = e_obj * H / (2 d tan(fov / 2)). A distance of 0 (the camera touches or is inside the
// object) gives +infinity for any positive error, and 0 for an error of 0.
double screen_space_error(double object_error, double distance, double screen_height, double fov);

// The distance from `eye` to a sphere's surface, 0 when the eye is inside: the `distance` for
// screen_space_error, so that a camera inside an object's bounds always selects the finest level.
double sphere_distance(const float3& eye, const float3& center, double radius);

// ---- objects and options --------------------------------------------------------------------------

struct BoundingSphere {
  float3 center;  // object space
  float radius = 0;
};

// A sphere containing every vertex of `mesh` (centred on its bounding box; object space).
BoundingSphere bounding_sphere(const Mesh& mesh);

// One level of an object's chain, finest first.
struct RuntimeLevel {
  // Object-space bound on the level's distance to the finest geometry (LodLevel::error); level 0
  // usually 0. Must not decrease along the chain.
  float error = 0;
  // Triangles drawn for the level (a morph draws its finer level's triangles). Must not increase
  // along the chain.
  uint32_t triangles = 0;
};

// A chain's levels for the runtime: each level's certified bound on its Hausdorff distance to the
// input (LodLevel::error_bound, so a level never shows more than the threshold), made non-decreasing
// along the chain, and its triangle count.
std::vector<RuntimeLevel> runtime_levels(const LodChain& chain);

// Object space to world space: world = x * p.x + y * p.y + z * p.z + translation (the columns of a
// 3x4 affine matrix). Errors and the radius scale by the matrix's largest stretch (bounded above;
// exact for rotations with any axis scales).
struct Transform {
  float3 x{1, 0, 0};
  float3 y{0, 1, 0};
  float3 z{0, 0, 1};
  float3 translation{0, 0, 0};
};

struct Camera {
  float3 position;                 // world space
  double fov = 1.0471975511965976;  // vertical field of view, radians (default 60 degrees)
  double screen_height = 1080;     // pixels
};

struct RuntimeOptions {
  // The largest screen-space error to draw, pixels: each object shows the coarsest level whose
  // error on screen is at most this (the switch points).
  double error_px = 1;
  // Width of the transition zone below each switch point, as a fraction of error_px in [0, 1]:
  // while the coarser level's error on screen is in (error_px * (1 - zone), error_px], the object's
  // goal is part way through the morph between the two levels, from t = 1 (fully coarse) at the
  // lower end to t = 0 at the switch point, linearly; t follows the goal at the rate limit. Outside
  // the zones the goal is one level, unmorphed. An approaching object thus starts refining before
  // the coarser level reaches the threshold. 0: no zone; the goal jumps at the switch point and t
  // runs through the whole morph over transition_seconds.
  double transition_zone = 0.25;
  // Fraction >= 0: an object that moves away (or whose errors shrink on screen otherwise) keeps its
  // selection until its screen-space errors have shrunk by the factor 1 + hysteresis; growing errors
  // count at once. Selection only ever uses errors at least the true ones, so hysteresis never makes
  // a steady level exceed error_px.
  double hysteresis = 0.1;
  // Seconds a full morph takes: t changes by at most dt / transition_seconds per frame. 0: hard
  // switches (levels change at once, like a plain discrete LOD).
  double transition_seconds = 1;
  // Triangles drawn per frame across all objects; 0: no budget. When every object at its coarsest
  // level still exceeds it, every object draws its coarsest and DrawList::over_budget is set.
  uint64_t triangle_budget = 0;
};

// ---- the runtime ----------------------------------------------------------------------------------

struct ObjectId {
  uint32_t slot = std::numeric_limits<uint32_t>::max();
  uint32_t generation = 0;
  friend bool operator==(const ObjectId&, const ObjectId&) = default;
};

struct DrawItem {
  ObjectId object;
  uint32_t level = 0;   // the level to draw (while morphing, the finer one, whose triangles are drawn)
  uint32_t target = 0;  // level + 1 while morphing (geomorph LodChain::morphs[level]), else level
  float t = 0;          // morph parameter in [0, 1): 0 is `level` exactly; 0 when steady
  friend bool operator==(const DrawItem&, const DrawItem&) = default;
};

struct DrawList {
  std::vector<DrawItem> items;  // one per object
  uint64_t triangles = 0;       // drawn this frame: the sum of each item's `level` triangles
  // The budget cannot hold even with every object at its coarsest level (which they then draw).
  bool over_budget = false;
  uint32_t morphing = 0;  // items with target != level
  // Jumps to a coarser level without a morph this frame, made because objects were added or the
  // budget was lowered: the budget is a hard limit, and a morph draws its finer level until it
  // completes. 0 while the scene only moves.
  uint32_t pops = 0;
};

// Per-object selection, transitions and the triangle budget. update() allocates nothing once the
// object count stops growing, and its result depends only on the calls made, in order.
class LodRuntime {
 public:
  explicit LodRuntime(const RuntimeOptions& options = {});

  // `levels` finest first (at least one; errors non-decreasing, triangles non-increasing). A new
  // object appears at its selected level without a transition on its next update. Throws
  // lod::Error (usage) on invalid input.
  ObjectId add(const BoundingSphere& bounds, std::span<const RuntimeLevel> levels, const Transform& transform = {});
  void remove(ObjectId id);                               // usage error if `id` is not live
  void set_transform(ObjectId id, const Transform& transform);
  bool contains(ObjectId id) const;
  size_t size() const { return ids_.size(); }

  void set_options(const RuntimeOptions& options);
  const RuntimeOptions& options() const { return options_; }

  // Advances every object by `dt` seconds (>= 0) as seen from `camera`, and returns the draw list
  // (valid until the next call that changes the runtime).
  const DrawList& update(const Camera& camera, double dt);
  const DrawList& draw_list() const { return draw_; }

 private:
  struct Slot {
    uint32_t dense = 0;
    uint32_t generation = 0;
  };
  // A budget step for one object: hold a refinement that would start this frame, or coarsen.
  struct Candidate {
    double metric = 0;  // screen-space error added per triangle saved
    uint32_t tier = 0;  // 0: invisible (a held refinement, a new object), 1: a visible jump
    uint32_t slot = 0;  // the tie-break, stable across removals
    uint32_t dense = 0;
    uint32_t to = 0;    // the level after the step
    bool hold = false;
  };
  struct HeapOrder {
    bool operator()(const Candidate& a, const Candidate& b) const;
  };

  uint32_t dense_index(ObjectId id) const;
  void place(uint32_t dense, const BoundingSphere& bounds, const Transform& transform);
  void budget_goals(uint64_t budget);
  void budget_frame(uint64_t budget);
  uint32_t cheaper_level(uint32_t dense, uint32_t level) const;
  double step_cost(uint32_t dense, uint32_t from, uint32_t to) const;

  RuntimeOptions options_;
  // Live objects, densely (removal moves the last object into the hole).
  std::vector<ObjectId> ids_;
  std::vector<BoundingSphere> object_bounds_;  // object space, as given
  std::vector<float3> center_;                 // world space
  std::vector<float> radius_;                  // world space
  std::vector<float> stretch_;                 // object -> world error scale
  std::vector<uint32_t> level_offset_, level_count_;
  std::vector<double> pixels_per_unit_;        // with hysteresis: screen pixels per object-space unit
  std::vector<double> coordinate_;             // level + t: where each object is
  std::vector<uint8_t> fresh_;                 // added since the last update
  std::vector<RuntimeLevel> levels_;           // every object's levels, in ranges
  size_t dead_levels_ = 0;
  std::vector<Slot> slots_;
  std::vector<uint32_t> free_slots_;
  // Per-frame scratch, kept to avoid allocation.
  std::vector<double> goal_, next_;
  std::vector<uint32_t> level_;
  std::vector<Candidate> heap_;
  DrawList draw_;
};

}  // namespace lod
