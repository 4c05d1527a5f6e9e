// Run-time LOD selection (Houle 2000, sections 3.3 and 6.2.3): screen-space error, transition zones,
// hysteresis, time-limited reversible morphs, and a greedy global triangle budget.
//
// Each object has a level coordinate c in [0, levels - 1]: at an integer k it draws level k; in
// between it draws floor(c) morphing towards floor(c) + 1 with t = c - floor(c). Every frame:
//   1. the goal coordinate from the screen-space errors (zones make it fractional inside a zone);
//   2. with a budget, goals coarsened greedily by error per triangle saved until the goals fit;
//   3. c moves towards its goal by at most dt / transition_seconds, stopping at each integer, so
//      the drawn pair of levels only changes at t = 0 or 1;
//   4. with a budget, the frame itself made to fit: refinements that would start drawing a finer
//      level wait, and only if that is not enough (objects were added, the budget lowered) objects
//      jump coarser at once.
// Step 4 is what keeps the budget hard: a morph draws its finer level, so coarsening frees
// triangles only once it completes, and a refinement costs its finer level from its first frame.
// Since c only moves within a pair or onto a coarser integer otherwise, holding the refinements
// that start always gets back to the previous frame's count.
#include "lodkit/runtime.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lodkit/error.h"
#include "lodkit/lod.h"

namespace lod {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr double kInfinity = std::numeric_limits<double>::infinity();

bool finite(const float3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
double dot(const float3& a, const float3& b) { return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z; }

// An upper bound on the largest singular value of [x y z]: the square root of a Gershgorin bound
// on the largest eigenvalue of M^T M. Exact when the columns are orthogonal.
double stretch(const Transform& m) {
  const float3 c[3] = {m.x, m.y, m.z};
  double bound = 0;
  for (int i = 0; i < 3; ++i) {
    double row = 0;
    for (int j = 0; j < 3; ++j) row += std::abs(dot(c[i], c[j]));
    bound = std::max(bound, row);
  }
  return std::sqrt(bound);
}

// Pixels covered by an error `error` at `pixels_per_unit` (which may be +infinity).
double error_px(double error, double pixels_per_unit) { return error > 0 ? error * pixels_per_unit : 0.0; }

// Moves c towards goal by at most `rate`, stopping at the next integer.
double advance(double c, double goal, double rate) {
  if (c < goal) return std::min({c + rate, goal, std::floor(c) + 1});
  if (c > goal) return std::max({c - rate, goal, std::ceil(c) - 1});
  return c;
}

void validate(const RuntimeOptions& o) {
  if (!(std::isfinite(o.error_px) && o.error_px >= 0)) throw_usage("LOD runtime: error_px must be a finite number >= 0");
  if (!(o.transition_zone >= 0 && o.transition_zone <= 1)) throw_usage("LOD runtime: transition_zone must be in [0, 1]");
  if (!(std::isfinite(o.hysteresis) && o.hysteresis >= 0)) throw_usage("LOD runtime: hysteresis must be a finite number >= 0");
  if (!(std::isfinite(o.transition_seconds) && o.transition_seconds >= 0))
    throw_usage("LOD runtime: transition_seconds must be a finite number >= 0");
}

}  // namespace

double screen_space_error(double object_error, double distance, double screen_height, double fov) {
  if (object_error <= 0) return 0;
  if (distance <= 0) return kInfinity;
  return object_error * screen_height / (2 * distance * std::tan(fov / 2));
}

double sphere_distance(const float3& eye, const float3& center, double radius) {
  const double dx = double(eye.x) - center.x, dy = double(eye.y) - center.y, dz = double(eye.z) - center.z;
  return std::max(std::sqrt(dx * dx + dy * dy + dz * dz) - radius, 0.0);
}

BoundingSphere bounding_sphere(const Mesh& mesh) {
  float3 lo, hi;
  bounding_box(mesh, lo, hi);
  BoundingSphere s{{(lo.x + hi.x) / 2, (lo.y + hi.y) / 2, (lo.z + hi.z) / 2}, 0};
  double r2 = 0;
  for (const float3& p : mesh.positions) {
    const double dx = double(p.x) - s.center.x, dy = double(p.y) - s.center.y, dz = double(p.z) - s.center.z;
    r2 = std::max(r2, dx * dx + dy * dy + dz * dz);
  }
  // Rounded up so that every vertex is inside in float too.
  s.radius = std::nextafter(float(std::sqrt(r2)), std::numeric_limits<float>::infinity());
  return s;
}

std::vector<RuntimeLevel> runtime_levels(const LodChain& chain) {
  std::vector<RuntimeLevel> out;
  float error = 0;
  for (const LodLevel& level : chain.levels) {
    error = std::max(error, level.error_bound);
    out.push_back({error, uint32_t(std::min<uint64_t>(level.mesh.triangle_count(), kNone))});
  }
  return out;
}

// ---- LodRuntime -----------------------------------------------------------------------------------

// std heaps keep the largest first; ours keeps the cheapest step first (invisible steps before
// visible ones, then the least error per triangle, then the lowest slot, for determinism).
inline bool LodRuntime::HeapOrder::operator()(const Candidate& a, const Candidate& b) const {
  if (a.tier != b.tier) return a.tier > b.tier;
  if (a.metric != b.metric) return a.metric > b.metric;
  return a.slot > b.slot;
}

LodRuntime::LodRuntime(const RuntimeOptions& options) : options_(options) { validate(options_); }

void LodRuntime::set_options(const RuntimeOptions& options) {
  validate(options);
  options_ = options;
}

uint32_t LodRuntime::dense_index(ObjectId id) const {
  if (id.slot >= slots_.size() || slots_[id.slot].generation != id.generation || slots_[id.slot].dense == kNone)
    throw_usage("LOD runtime: unknown object id");
  return slots_[id.slot].dense;
}

bool LodRuntime::contains(ObjectId id) const {
  return id.slot < slots_.size() && slots_[id.slot].generation == id.generation && slots_[id.slot].dense != kNone;
}

void LodRuntime::place(uint32_t dense, const BoundingSphere& b, const Transform& m) {
  if (!finite(b.center) || !(std::isfinite(b.radius) && b.radius >= 0))
    throw_usage("LOD runtime: the bounding sphere needs a finite centre and radius >= 0");
  if (!finite(m.x) || !finite(m.y) || !finite(m.z) || !finite(m.translation)) throw_usage("LOD runtime: non-finite transform");
  const float3& c = b.center;
  center_[dense] = {m.x.x * c.x + m.y.x * c.y + m.z.x * c.z + m.translation.x,
                    m.x.y * c.x + m.y.y * c.y + m.z.y * c.z + m.translation.y,
                    m.x.z * c.x + m.y.z * c.y + m.z.z * c.z + m.translation.z};
  const double s = stretch(m);
  stretch_[dense] = float(s);
  radius_[dense] = float(double(b.radius) * s);
}

ObjectId LodRuntime::add(const BoundingSphere& bounds, std::span<const RuntimeLevel> levels, const Transform& transform) {
  if (levels.empty()) throw_usage("LOD runtime: an object needs at least one level");
  for (size_t i = 0; i < levels.size(); ++i) {
    if (!(std::isfinite(levels[i].error) && levels[i].error >= 0))
      throw_usage("LOD runtime: level " + std::to_string(i) + ": the error must be a finite number >= 0");
    if (i && levels[i].error < levels[i - 1].error)
      throw_usage("LOD runtime: level " + std::to_string(i) + ": the error is smaller than the finer level's");
    if (i && levels[i].triangles > levels[i - 1].triangles)
      throw_usage("LOD runtime: level " + std::to_string(i) + ": more triangles than the finer level");
  }
  if (ids_.size() >= kNone - 1) throw_usage("LOD runtime: too many objects");

  const uint32_t dense = uint32_t(ids_.size());
  uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = uint32_t(slots_.size());
    slots_.push_back({kNone, 0});
  }
  const ObjectId id{slot, slots_[slot].generation};
  object_bounds_.push_back(bounds);
  center_.emplace_back();
  radius_.push_back(0);
  stretch_.push_back(1);
  try {
    place(dense, bounds, transform);
  } catch (...) {
    object_bounds_.pop_back(), center_.pop_back(), radius_.pop_back(), stretch_.pop_back();
    free_slots_.push_back(slot);
    throw;
  }
  slots_[slot].dense = dense;
  ids_.push_back(id);
  level_offset_.push_back(uint32_t(levels_.size()));
  level_count_.push_back(uint32_t(levels.size()));
  levels_.insert(levels_.end(), levels.begin(), levels.end());
  pixels_per_unit_.push_back(0);
  coordinate_.push_back(0);
  fresh_.push_back(1);
  return id;
}

void LodRuntime::set_transform(ObjectId id, const Transform& transform) {
  const uint32_t dense = dense_index(id);
  place(dense, object_bounds_[dense], transform);
}

void LodRuntime::remove(ObjectId id) {
  const uint32_t hole = dense_index(id);
  const uint32_t last = uint32_t(ids_.size() - 1);
  dead_levels_ += level_count_[hole];
  if (hole != last) {
    ids_[hole] = ids_[last];
    object_bounds_[hole] = object_bounds_[last];
    center_[hole] = center_[last];
    radius_[hole] = radius_[last];
    stretch_[hole] = stretch_[last];
    level_offset_[hole] = level_offset_[last];
    level_count_[hole] = level_count_[last];
    pixels_per_unit_[hole] = pixels_per_unit_[last];
    coordinate_[hole] = coordinate_[last];
    fresh_[hole] = fresh_[last];
    slots_[ids_[hole].slot].dense = hole;
  }
  ids_.pop_back(), object_bounds_.pop_back(), center_.pop_back(), radius_.pop_back(), stretch_.pop_back();
  level_offset_.pop_back(), level_count_.pop_back(), pixels_per_unit_.pop_back(), coordinate_.pop_back(), fresh_.pop_back();
  slots_[id.slot].dense = kNone;
  ++slots_[id.slot].generation;
  free_slots_.push_back(id.slot);

  // Removed objects leave their levels behind; compact once they are the larger part.
  if (dead_levels_ > 64 && 2 * dead_levels_ > levels_.size()) {
    std::vector<RuntimeLevel> packed;
    packed.reserve(levels_.size() - dead_levels_);
    for (size_t i = 0; i < ids_.size(); ++i) {
      const uint32_t offset = uint32_t(packed.size());
      packed.insert(packed.end(), levels_.begin() + level_offset_[i], levels_.begin() + level_offset_[i] + level_count_[i]);
      level_offset_[i] = offset;
    }
    levels_ = std::move(packed);
    dead_levels_ = 0;
  }
}

// The first level after `level` with fewer triangles (kNone if none): coarsening to a level of the
// same size saves nothing.
uint32_t LodRuntime::cheaper_level(uint32_t dense, uint32_t level) const {
  const RuntimeLevel* l = &levels_[level_offset_[dense]];
  for (uint32_t k = level + 1; k < level_count_[dense]; ++k)
    if (l[k].triangles < l[level].triangles) return k;
  return kNone;
}

// Screen-space error added per triangle saved by drawing level `to` instead of the finer `from`.
double LodRuntime::step_cost(uint32_t dense, uint32_t from, uint32_t to) const {
  const RuntimeLevel* l = &levels_[level_offset_[dense]];
  const double added = error_px(double(l[to].error) - double(l[from].error), pixels_per_unit_[dense]);
  return added / double(l[from].triangles - l[to].triangles);
}

// Greedy coarsening of the goals (level_ holds each goal's drawn level) until they fit the budget.
void LodRuntime::budget_goals(uint64_t budget) {
  const uint32_t n = uint32_t(ids_.size());
  uint64_t total = 0;
  for (uint32_t i = 0; i < n; ++i) {
    level_[i] = uint32_t(goal_[i]);
    total += levels_[level_offset_[i] + level_[i]].triangles;
  }
  if (total <= budget) return;
  heap_.clear();
  for (uint32_t i = 0; i < n; ++i)
    if (const uint32_t k = cheaper_level(i, level_[i]); k != kNone)
      heap_.push_back({step_cost(i, level_[i], k), 0, ids_[i].slot, i, k, false});
  std::make_heap(heap_.begin(), heap_.end(), HeapOrder{});
  while (total > budget && !heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), HeapOrder{});
    const Candidate c = heap_.back();
    heap_.pop_back();
    const RuntimeLevel* l = &levels_[level_offset_[c.dense]];
    total -= l[level_[c.dense]].triangles - l[c.to].triangles;
    level_[c.dense] = c.to;
    goal_[c.dense] = c.to;
    if (const uint32_t k = cheaper_level(c.dense, c.to); k != kNone) {
      heap_.push_back({step_cost(c.dense, c.to, k), 0, c.slot, c.dense, k, false});
      std::push_heap(heap_.begin(), heap_.end(), HeapOrder{});
    }
  }
}

// Makes this frame's positions (next_) fit the budget: first hold refinements that would start
// drawing a finer level (and coarsen new objects, which nobody has seen yet), then make objects jump
// coarser. Both in order of least screen-space error per triangle saved. The two tiers run one after
// the other (a single heap ordered by tier would pop the same steps), so the usual frame, where a few
// held refinements suffice, never builds a heap over every object.
void LodRuntime::budget_frame(uint64_t budget) {
  const uint32_t n = uint32_t(ids_.size());
  uint64_t total = 0;
  for (uint32_t i = 0; i < n; ++i) total += levels_[level_offset_[i] + uint32_t(next_[i])].triangles;
  draw_.over_budget = false;
  if (total <= budget) return;

  auto run = [&] {
    std::make_heap(heap_.begin(), heap_.end(), HeapOrder{});
    while (total > budget && !heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), HeapOrder{});
      const Candidate c = heap_.back();
      heap_.pop_back();
      const RuntimeLevel* l = &levels_[level_offset_[c.dense]];
      total -= l[uint32_t(next_[c.dense])].triangles - l[c.to].triangles;
      next_[c.dense] = c.to;
      if (c.tier) ++draw_.pops;
      if (c.hold) continue;  // a held object may still have to jump, but in tier 1
      if (const uint32_t k = cheaper_level(c.dense, c.to); k != kNone) {
        heap_.push_back({step_cost(c.dense, c.to, k), c.tier, c.slot, c.dense, k, false});
        std::push_heap(heap_.begin(), heap_.end(), HeapOrder{});
      }
    }
  };

  // Tier 0: refinements starting this frame (coordinate_ is then an integer), and new objects.
  heap_.clear();
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t drawn = uint32_t(next_[i]);
    const uint32_t from = uint32_t(coordinate_[i]);
    const RuntimeLevel* l = &levels_[level_offset_[i]];
    if (fresh_[i]) {
      if (const uint32_t k = cheaper_level(i, drawn); k != kNone) heap_.push_back({step_cost(i, drawn, k), 0, ids_[i].slot, i, k, false});
    } else if (drawn < from && l[drawn].triangles > l[from].triangles) {
      heap_.push_back({step_cost(i, drawn, from), 0, ids_[i].slot, i, from, true});
    }
  }
  run();
  if (total > budget) {
    // Tier 1: jumps of objects already on screen.
    heap_.clear();
    for (uint32_t i = 0; i < n; ++i)
      if (!fresh_[i])
        if (const uint32_t k = cheaper_level(i, uint32_t(next_[i])); k != kNone)
          heap_.push_back({step_cost(i, uint32_t(next_[i]), k), 1, ids_[i].slot, i, k, false});
    run();
  }
  draw_.over_budget = total > budget;
}

const DrawList& LodRuntime::update(const Camera& camera, double dt) {
  if (!(std::isfinite(dt) && dt >= 0)) throw_usage("LOD runtime: dt must be a finite number of seconds >= 0");
  if (!finite(camera.position) || !(camera.fov > 0 && camera.fov < std::numbers::pi) || !(std::isfinite(camera.screen_height) && camera.screen_height > 0))
    throw_usage("LOD runtime: the camera needs a finite position, a fov in (0, pi) radians and a screen height > 0 pixels");

  const uint32_t n = uint32_t(ids_.size());
  goal_.resize(n), next_.resize(n), level_.resize(n), draw_.items.resize(n);
  if (heap_.capacity() < n) heap_.reserve(n);
  draw_.triangles = 0, draw_.morphing = 0, draw_.pops = 0, draw_.over_budget = false;

  const double pixels_per_radian = camera.screen_height / (2 * std::tan(camera.fov / 2));
  const double threshold = options_.error_px;
  const double zone_low = threshold * (1 - options_.transition_zone);
  const double hysteresis = 1 + options_.hysteresis;

  // 1. Goals from the screen-space errors.
  for (uint32_t i = 0; i < n; ++i) {
    const double d = sphere_distance(camera.position, center_[i], radius_[i]);
    const double p = d > 0 ? pixels_per_radian * stretch_[i] / d : kInfinity;
    // Hysteresis keeps the largest recent scale, within a factor: errors are never underestimated.
    double& kept = pixels_per_unit_[i];
    kept = fresh_[i] ? p : std::min(std::max(kept, p), p * hysteresis);
    const RuntimeLevel* l = &levels_[level_offset_[i]];
    double goal = 0;
    for (uint32_t b = 0; b + 1 < level_count_[i]; ++b) {
      // How far the coarser level of the pair (b, b + 1) is shown: 1 below the zone, 0 above the
      // switch point, linear in the zone.
      const double x = error_px(l[b + 1].error, kept);
      const double shown = x <= zone_low ? 1.0 : x > threshold ? 0.0 : (threshold - x) / (threshold - zone_low);
      if (shown <= 0) break;
      goal += shown;
    }
    goal_[i] = goal;
  }
  // 2. Goals within the budget.
  if (options_.triangle_budget) budget_goals(options_.triangle_budget);

  // 3. Move towards the goals; new objects start there.
  const double rate = options_.transition_seconds > 0 ? dt / options_.transition_seconds : kInfinity;
  for (uint32_t i = 0; i < n; ++i)
    next_[i] = fresh_[i] || rate == kInfinity ? goal_[i] : advance(coordinate_[i], goal_[i], rate);

  // 4. This frame within the budget.
  if (options_.triangle_budget) budget_frame(options_.triangle_budget);

  for (uint32_t i = 0; i < n; ++i) {
    const double c = next_[i];
    coordinate_[i] = c;
    fresh_[i] = 0;
    const uint32_t level = uint32_t(c);
    DrawItem& item = draw_.items[i];
    item.object = ids_[i];
    item.level = level;
    if (double(level) == c) {
      item.target = level, item.t = 0;
    } else {
      item.target = level + 1;
      item.t = std::min(float(c - level), std::nextafter(1.0f, 0.0f));
      ++draw_.morphing;
    }
    draw_.triangles += levels_[level_offset_[i] + level].triangles;
  }
  return draw_;
}

}  // namespace lod
