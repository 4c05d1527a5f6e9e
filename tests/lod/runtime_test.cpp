// LOD runtime: the screen-space error by hand, selection against a brute-force rule, transition
// zones, hysteresis, morphs that never pop (rate limit, reversal, swaps only at t = 0 or 1), the
// greedy triangle budget (hand-derived choices, never exceeded over a random scene), determinism
// and no allocation per frame.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <map>
#include <new>
#include <numbers>
#include <random>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"
#include "lodkit/runtime.h"

// Counts allocations made by the current thread while `counting` is set (the no-allocation test).
// This replaces the global operator new of the whole test binary; it only forwards to malloc.
namespace {
thread_local bool counting = false;
thread_local size_t allocations = 0;
}  // namespace
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(size_t size) {
  if (counting) ++allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
// Every other form too: AddressSanitizer supplies its own nothrow and array forms, and memory from
// its allocator must not reach the free() above (std::stable_sort's nothrow buffers did).
void* operator new(size_t size, const std::nothrow_t&) noexcept {
  if (counting) ++allocations;
  return std::malloc(size ? size : 1);
}
void* operator new[](size_t size) { return ::operator new(size); }
void* operator new[](size_t size, const std::nothrow_t& tag) noexcept { return ::operator new(size, tag); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace lod {
namespace {

constexpr double kPi = std::numbers::pi;

}  // namespace

void PrintTo(const DrawItem& item, std::ostream* os) {
  *os << "{object " << item.object.slot << "/" << item.object.generation << ", level " << item.level << " -> " << item.target
      << ", t " << item.t << "}";
}

namespace {

// fov 90 degrees on 1000 pixels: H / (2 tan(fov / 2)) = 500 pixels per unit at distance 1.
Camera camera_at(float3 p) { return {.position = p, .fov = kPi / 2, .screen_height = 1000}; }

// Errors 0, 0.002, 0.008, 0.032 (times `scale`): at 500 px per unit and error_px = 1, level k is
// good enough from distance 500 e_k on: 1, 4 and 16 (times `scale`).
std::vector<RuntimeLevel> four_levels(float scale = 1) {
  return {{0, 1000}, {0.002f * scale, 500}, {0.008f * scale, 250}, {0.032f * scale, 125}};
}

double coordinate(const DrawItem& item) { return item.level + double(item.t); }
bool steady(const DrawItem& item) { return item.level == item.target && item.t == 0; }

// The draw item of `id` (items are one per object, in no promised order).
const DrawItem& item_of(const DrawList& list, ObjectId id) {
  for (const DrawItem& item : list.items)
    if (item.object == id) return item;
  throw std::runtime_error("object missing from the draw list");
}

// Checks one object's step between frames: t in [0, 1), target = level or level + 1, the level
// coordinate moves by at most `rate`, and the pair of levels drawn changes only through a steady
// frame (t = 0, or the other frame's t = 1 which is the coarser level drawn steadily).
void expect_smooth(const DrawItem& before, const DrawItem& now, double rate, const std::string& where) {
  EXPECT_GE(now.t, 0.0f) << where;
  EXPECT_LT(now.t, 1.0f) << where;
  EXPECT_TRUE(now.target == now.level || now.target == now.level + 1) << where;
  EXPECT_EQ(now.t == 0, now.target == now.level) << where;
  EXPECT_LE(std::abs(coordinate(now) - coordinate(before)), rate + 1e-6) << where;
  if (now.level != before.level || now.target != before.target) {
    const bool from_steady = steady(before) && (now.level == before.level || now.target == before.level);
    const bool to_steady = steady(now) && (before.level == now.level || before.target == now.level);
    EXPECT_TRUE(from_steady || to_steady) << where << ": swapped from (" << before.level << " -> " << before.target << ", t "
                                          << before.t << ") to (" << now.level << " -> " << now.target << ", t " << now.t << ")";
  }
}

TEST(RuntimeScreenSpaceError, ByHand) {
  // 0.01 * 1000 / (2 * 5 * tan(45 deg)) = 1.
  EXPECT_NEAR(screen_space_error(0.01, 5, 1000, kPi / 2), 1.0, 1e-12);
  // 0.02 * 1080 / (2 * 10 * tan(30 deg)) = 1.08 * sqrt(3).
  EXPECT_NEAR(screen_space_error(0.02, 10, 1080, kPi / 3), 1.08 * std::sqrt(3.0), 1e-12);
  // Halving the distance doubles it.
  EXPECT_NEAR(screen_space_error(0.01, 2.5, 1000, kPi / 2), 2.0, 1e-12);
  EXPECT_EQ(screen_space_error(0.01, 0, 1000, kPi / 2), std::numeric_limits<double>::infinity());
  EXPECT_EQ(screen_space_error(0, 0, 1000, kPi / 2), 0.0);
  // The distance is to the sphere's surface: |(3, 4, 0)| - 2 = 3; inside is 0.
  EXPECT_DOUBLE_EQ(sphere_distance({3, 4, 0}, {0, 0, 0}, 2), 3.0);
  EXPECT_DOUBLE_EQ(sphere_distance({1, 1, 0}, {0, 0, 0}, 2), 0.0);
}

TEST(RuntimeScreenSpaceError, CameraInsideTheSphereDrawsTheFinestLevel) {
  LodRuntime runtime({.error_px = 1000});  // everything would be coarsest outside
  const auto levels = four_levels();
  const ObjectId id = runtime.add({{0, 0, 0}, 10}, levels);
  EXPECT_EQ(item_of(runtime.update(camera_at({5, 0, 0}), 0), id).level, 0u);
  // Just outside: 0.032 * 500 / 0.5 = 32 px <= 1000, the coarsest.
  LodRuntime outside({.error_px = 1000});
  const ObjectId id2 = outside.add({{0, 0, 0}, 10}, levels);
  EXPECT_EQ(item_of(outside.update(camera_at({10.5f, 0, 0}), 0), id2).level, 3u);
}

TEST(RuntimeSelection, CoarsestLevelWithinThreshold) {
  // Hand table (radius 0.5 at the origin, camera on +x at that distance from the surface): switch
  // distances 1, 4, 16.
  const std::pair<float, uint32_t> table[] = {{0.5f, 0}, {0.99f, 0}, {1.01f, 1}, {3.99f, 1}, {4.01f, 2}, {15.9f, 2}, {16.1f, 3}, {100, 3}};
  for (auto [d, expected] : table) {
    LodRuntime runtime({.error_px = 1, .transition_zone = 0, .hysteresis = 0.1});
    const ObjectId id = runtime.add({{0, 0, 0}, 0.5f}, four_levels());
    const DrawItem& item = item_of(runtime.update(camera_at({0.5f + d, 0, 0}), 1.0 / 60), id);
    EXPECT_EQ(item.level, expected) << "distance " << d;
    EXPECT_TRUE(steady(item));
  }

  // Brute force over random objects and cameras, after the transitions have settled.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  for (int round = 0; round < 20; ++round) {
    const double threshold = 0.5 + 2 * u(rng);
    LodRuntime runtime({.error_px = threshold, .transition_zone = 0, .hysteresis = 0, .transition_seconds = 0.25});
    std::vector<std::vector<RuntimeLevel>> chains;
    std::vector<BoundingSphere> spheres;
    std::vector<ObjectId> ids;
    for (int i = 0; i < 30; ++i) {
      std::vector<RuntimeLevel> levels{{0, 4000}};
      const int count = 1 + int(u(rng) * 5);
      for (int k = 1; k < count; ++k) levels.push_back({levels.back().error + 0.05f * u(rng), levels.back().triangles / 2});
      chains.push_back(levels);
      spheres.push_back({{40 * u(rng) - 20, 40 * u(rng) - 20, 40 * u(rng) - 20}, 2 * u(rng)});
      ids.push_back(runtime.add(spheres.back(), levels));
    }
    // Fly somewhere, then stay until every transition is over (4 levels at 0.25 s each).
    float3 eye{};
    for (int frame = 0; frame < 30; ++frame) {
      eye = {eye.x + 4 * u(rng) - 2, eye.y + 4 * u(rng) - 2, eye.z + 4 * u(rng) - 2};
      runtime.update(camera_at(eye), 1.0 / 60);
    }
    for (int frame = 0; frame < 61; ++frame) runtime.update(camera_at(eye), 1.0 / 60);
    const DrawList& list = runtime.draw_list();
    for (size_t i = 0; i < ids.size(); ++i) {
      const float3 c = spheres[i].center;
      const double d = std::max(0.0, std::sqrt(double(eye.x - c.x) * (eye.x - c.x) + double(eye.y - c.y) * (eye.y - c.y) +
                                               double(eye.z - c.z) * (eye.z - c.z)) - spheres[i].radius);
      uint32_t expected = 0;
      for (uint32_t k = 0; k < chains[i].size(); ++k)
        if (chains[i][k].error == 0 || (d > 0 && chains[i][k].error * 1000 / (2 * d) <= threshold)) expected = k;
      const DrawItem& item = item_of(list, ids[i]);
      EXPECT_TRUE(steady(item));
      EXPECT_EQ(item.level, expected) << "round " << round << " object " << i << " distance " << d;
    }
  }
}

TEST(RuntimeSelection, TransformScalesErrorsAndBounds) {
  // Uniform scale 2 and a translation: the sphere (1, 0, 0) r 1 becomes (12, 0, 0) r 2, and the
  // level-1 error 0.002 becomes 0.004, good enough from distance 2 on.
  const Transform scale2{{2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {10, 0, 0}};
  for (auto [d, expected] : {std::pair{1.9f, 0u}, {2.1f, 1u}}) {
    LodRuntime runtime({.transition_zone = 0, .transition_seconds = 0});
    const ObjectId id = runtime.add({{1, 0, 0}, 1}, four_levels(), scale2);
    EXPECT_EQ(item_of(runtime.update(camera_at({14 + d, 0, 0}), 0), id).level, expected) << d;
    // Back to object space = world space: the sphere is (1, 0, 0) r 1, switch at distance 1, so
    // 0.9 from its surface (2.9 on x) is level 0.
    runtime.set_transform(id, {});
    EXPECT_EQ(item_of(runtime.update(camera_at({2 + 0.9f, 0, 0}), 0), id), (DrawItem{id, 0, 0, 0}));
  }
  // A rotation with scale 3 along one axis: errors scale by 3, so level 1 is good enough from 3 on.
  const Transform rotated{{0, 3, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, 0}};
  for (auto [d, expected] : {std::pair{2.9f, 0u}, {3.1f, 1u}}) {
    LodRuntime runtime({.transition_zone = 0});
    const ObjectId id = runtime.add({{0, 0, 0}, 0}, four_levels(), rotated);
    EXPECT_EQ(item_of(runtime.update(camera_at({0, 0, d}), 0), id).level, expected) << d;
  }
}

TEST(RuntimeTransitions, NoMorphOutsideTheZones) {
  // error_px 1, zones of 0.25 and hysteresis 0.1. An object with errors scaled by s has zones at
  // effective distances [s, 4s/3), [4s, 16s/3), [16s, 64s/3); the effective distance is between
  // d / 1.1 and d. With the camera 1.8 to 3.6 from the objects, s = 5, 1, 0.3 and 0.075 stay in the
  // gaps of levels 0, 1, 2 and 3.
  const float scales[] = {5, 1, 0.3f, 0.075f};
  auto run = [&](float near, float far) {
    LodRuntime runtime({.error_px = 1, .transition_zone = 0.25, .hysteresis = 0.1, .transition_seconds = 0.5});
    std::vector<ObjectId> ids;
    for (float s : scales) ids.push_back(runtime.add({{0, 0, 0}, 0}, four_levels(s)));
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, 1);
    float d = near;
    uint32_t morphing = 0;
    for (int frame = 0; frame < 1200; ++frame) {
      d = std::clamp(d + (u(rng) - 0.5f) * 0.3f, near, far);
      const float a = u(rng) * 6.2831853f;
      const DrawList& list = runtime.update(camera_at({d * std::cos(a), d * std::sin(a), 0}), 1.0 / 60);
      morphing += list.morphing;
      for (uint32_t i = 0; i < 4; ++i)
        if (near >= 1.8f && far <= 3.6f) {
          EXPECT_EQ(item_of(list, ids[i]), (DrawItem{ids[i], i, i, 0})) << frame;
        }
    }
    return morphing;
  };
  EXPECT_EQ(run(1.8f, 3.6f), 0u);
  // The control: wandering into the zones of s = 1 (4 to 5.33) does morph.
  EXPECT_GT(run(1.8f, 5), 0u);
}

TEST(RuntimeTransitions, ZonePositionAndHysteresisByHand) {
  LodRuntime runtime({.error_px = 1, .transition_zone = 0.25, .hysteresis = 0.1, .transition_seconds = 1});
  const ObjectId id = runtime.add({{0, 0, 0}, 0}, four_levels());
  // Approach slowly from 6 to 32/7 = 4.571: level 2's error there is 4 / d = 0.875 px, half way
  // through the zone (0.75, 1]: t = (1 - 0.875) / 0.25 = 0.5 towards level 2.
  const float stop = 32.0f / 7;
  for (float d = 6; d > stop; d -= 0.001f) runtime.update(camera_at({d, 0, 0}), 1.0 / 60);
  for (int frame = 0; frame < 120; ++frame) runtime.update(camera_at({stop, 0, 0}), 1.0 / 60);
  DrawItem item = item_of(runtime.draw_list(), id);
  EXPECT_EQ(item.level, 1u);
  EXPECT_EQ(item.target, 2u);
  EXPECT_NEAR(item.t, 0.5, 1e-5);
  // Backing off to 4.8 is within the hysteresis (500 / 4.8 * 1.1 > 500 / stop): nothing moves.
  for (int frame = 0; frame < 120; ++frame) runtime.update(camera_at({4.8f, 0, 0}), 1.0 / 60);
  EXPECT_NEAR(item_of(runtime.draw_list(), id).t, 0.5, 1e-5);
  // At 5.2 the error taken is 4.4 / 5.2 = 0.84615 px: t = (1 - 0.84615) / 0.25 = 0.61538.
  for (int frame = 0; frame < 120; ++frame) runtime.update(camera_at({5.2f, 0, 0}), 1.0 / 60);
  item = item_of(runtime.draw_list(), id);
  EXPECT_EQ(item.level, 1u);
  EXPECT_NEAR(item.t, (1 - 4.4 / 5.2) / 0.25, 1e-5);
}

TEST(RuntimeTransitions, OscillatingObjectNeverPops) {
  // No zone and no hysteresis: the worst case, every crossing of distance 4 flips the goal. The
  // camera first oscillates faster than a transition (t must reverse mid-way), then slower (full
  // swaps happen).
  for (const auto& [zone, hysteresis, random_dt] : {std::tuple{0.0, 0.0, false}, {0.25, 0.05, true}}) {
    LodRuntime runtime({.error_px = 1, .transition_zone = zone, .hysteresis = hysteresis, .transition_seconds = 1});
    const ObjectId id = runtime.add({{0, 0, 0}, 0}, four_levels());
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.5 / 60, 2.0 / 60);
    double time = 0, phase = 0;
    DrawItem before = item_of(runtime.update(camera_at({4.2f, 0, 0}), 0), id);
    int reversals = 0, swaps = 0, last_direction = 0;
    for (int frame = 0; frame < 900; ++frame) {
      const double dt = random_dt ? u(rng) : 1.0 / 60;
      time += dt;
      phase += 2 * kPi * (time < 5 ? 0.8 : 0.15) * dt;
      const float d = float(4 + 0.6 * std::sin(phase));
      const DrawItem now = item_of(runtime.update(camera_at({d, 0, 0}), dt), id);
      expect_smooth(before, now, dt / 1.0, "frame " + std::to_string(frame));
      const double move = coordinate(now) - coordinate(before);
      const int direction = move > 0 ? 1 : move < 0 ? -1 : 0;
      if (direction && last_direction && direction != last_direction && before.t > 0 && before.level == now.level) ++reversals;
      if (direction) last_direction = direction;
      if (steady(now) && steady(before) && now.level != before.level) ADD_FAILURE() << "jump between steady levels at frame " << frame;
      if (steady(now) && !steady(before)) ++swaps;
      before = now;
    }
    EXPECT_GE(reversals, 3) << "zone " << zone;
    EXPECT_GE(swaps, 2) << "zone " << zone;
  }
}

TEST(RuntimeTransitions, HardSwitchesWithoutDuration) {
  LodRuntime runtime({.transition_zone = 0, .hysteresis = 0, .transition_seconds = 0});
  const ObjectId id = runtime.add({{0, 0, 0}, 0}, four_levels());
  EXPECT_EQ(item_of(runtime.update(camera_at({0.5f, 0, 0}), 1.0 / 60), id).level, 0u);
  // Straight from 0 to 3 in one frame.
  const DrawItem item = item_of(runtime.update(camera_at({20, 0, 0}), 1.0 / 60), id);
  EXPECT_TRUE(steady(item));
  EXPECT_EQ(item.level, 3u);
}

TEST(RuntimeTransitions, MultiLevelTransitionGoesLevelByLevel) {
  LodRuntime runtime({.transition_zone = 0, .hysteresis = 0, .transition_seconds = 1});
  const ObjectId id = runtime.add({{0, 0, 0}, 0}, four_levels());
  DrawItem before = item_of(runtime.update(camera_at({0.5f, 0, 0}), 0), id);
  // dt = 0.3 s: t = 0.3, 0.6, 0.9, then it stops at 1 (steady at the next level) before the next
  // pair: 4 frames per level.
  int frames = 0;
  while (!(steady(before) && before.level == 3) && frames < 100) {
    const DrawItem now = item_of(runtime.update(camera_at({20, 0, 0}), 0.3), id);
    expect_smooth(before, now, 0.3, "frame " + std::to_string(frames));
    before = now;
    ++frames;
  }
  EXPECT_EQ(frames, 12);
}

// ---- budget ---------------------------------------------------------------------------------------

TEST(RuntimeBudget, GreedyByErrorPerTriangleByHand) {
  // Both at 500 px per unit (distance 500, 500 px per unit at distance 1 / 500... = 1 px per unit).
  // A: level 1 adds 0.5 px and saves 500 triangles (0.001 px per triangle); B: adds 0.2 px and saves
  // 100 (0.002). A threshold of 0.01 px wants level 0 for both: 2000 triangles.
  const RuntimeLevel a[] = {{0, 1000}, {0.5f, 500}};
  const RuntimeLevel b[] = {{0, 1000}, {0.2f, 900}};
  struct Case {
    uint64_t budget;
    uint32_t a_level, b_level;
    uint64_t triangles;
    bool over;
  };
  // 1950: coarsening either would do; A costs more error (0.5 px) but less per triangle: A goes.
  for (const Case& c : {Case{2000, 0, 0, 2000, false}, Case{1950, 1, 0, 1500, false}, Case{1400, 1, 1, 1400, false}, Case{1399, 1, 1, 1400, true}}) {
    LodRuntime runtime({.error_px = 0.01, .triangle_budget = c.budget});
    const ObjectId ia = runtime.add({{500, 0, 0}, 0}, a), ib = runtime.add({{-500, 0, 0}, 0}, b);
    for (int frame = 0; frame < 3; ++frame) {
      const DrawList& list = runtime.update(camera_at({0, 0, 0}), 1.0 / 60);
      EXPECT_EQ(item_of(list, ia).level, c.a_level) << c.budget;
      EXPECT_EQ(item_of(list, ib).level, c.b_level) << c.budget;
      EXPECT_EQ(list.triangles, c.triangles) << c.budget;
      EXPECT_EQ(list.over_budget, c.over) << c.budget;
      EXPECT_EQ(list.pops, 0u);  // new objects appear where the budget puts them
      EXPECT_EQ(list.morphing, 0u);
    }
  }
}

TEST(RuntimeBudget, RefinementWaitsForCoarseningToFinish) {
  // Budget 1500 for two objects of 1000 / 500 triangles. The camera moves from A to B: A coarsens
  // (drawing 1000 until its morph ends) and B's refinement must wait for that, without any pop.
  const RuntimeLevel levels[] = {{0, 1000}, {1, 500}};
  LodRuntime runtime({.error_px = 1, .transition_zone = 0, .hysteresis = 0, .transition_seconds = 1, .triangle_budget = 1500});
  const ObjectId a = runtime.add({{0, 0, 0}, 0}, levels), b = runtime.add({{10000, 0, 0}, 0}, levels);
  const DrawList& first = runtime.update(camera_at({-10, 0, 0}), 0.125);
  EXPECT_EQ(item_of(first, a).level, 0u);
  EXPECT_EQ(item_of(first, b).level, 1u);
  int a_done = -1, b_started = -1;
  for (int frame = 0; frame < 40; ++frame) {
    const DrawList& list = runtime.update(camera_at({10010, 0, 0}), 0.125);
    EXPECT_LE(list.triangles, 1500u);
    EXPECT_EQ(list.pops, 0u);
    if (a_done < 0 && steady(item_of(list, a)) && item_of(list, a).level == 1) a_done = frame;
    if (b_started < 0 && item_of(list, b).level == 0) b_started = frame;
  }
  // A morphs for 8 frames of 1/8 s and is steady at level 1 on frame 7; B starts on that frame.
  EXPECT_EQ(a_done, 7);
  EXPECT_EQ(b_started, 7);
  EXPECT_EQ(item_of(runtime.draw_list(), b), (DrawItem{b, 0, 0, 0}));
}

// A random scene: chains, spheres, a camera path, objects added and removed as it goes.
struct Scene {
  std::mt19937 rng;
  std::uniform_real_distribution<float> u{0, 1};
  std::map<uint64_t, std::vector<RuntimeLevel>> chains;  // by id
  std::vector<ObjectId> ids;

  explicit Scene(uint32_t seed) : rng(seed) {}
  static uint64_t key(ObjectId id) { return uint64_t(id.slot) << 32 | id.generation; }
  // `twin`, if any, gets the same calls (and so the same ids).
  void add(LodRuntime& runtime, LodRuntime* twin = nullptr) {
    std::vector<RuntimeLevel> levels{{0, 1000 + uint32_t(u(rng) * 20000)}};
    const int count = 1 + int(u(rng) * 6);
    for (int k = 1; k < count; ++k)
      levels.push_back({levels.back().error + 0.05f * u(rng), uint32_t(levels.back().triangles * (0.3 + 0.7 * u(rng)))});
    const BoundingSphere sphere{{200 * u(rng) - 100, 200 * u(rng) - 100, 200 * u(rng) - 100}, 5 * u(rng)};
    const ObjectId id = runtime.add(sphere, levels);
    if (twin && !(twin->add(sphere, levels) == id)) throw std::runtime_error("twin ids differ");
    chains[key(id)] = levels;
    ids.push_back(id);
  }
  void remove_one(LodRuntime& runtime, LodRuntime* twin = nullptr) {
    const size_t i = size_t(u(rng) * float(ids.size())) % ids.size();
    runtime.remove(ids[i]);
    if (twin) twin->remove(ids[i]);
    chains.erase(key(ids[i]));
    ids.erase(ids.begin() + long(i));
  }
  uint64_t coarsest() const {
    uint64_t sum = 0;
    for (const auto& [id, levels] : chains) sum += levels.back().triangles;
    return sum;
  }
  uint64_t finest() const {
    uint64_t sum = 0;
    for (const auto& [id, levels] : chains) sum += levels.front().triangles;
    return sum;
  }
};

TEST(RuntimeBudget, NeverExceededOverARandomScene) {
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    Scene scene(seed);
    const double seconds = seed % 2 ? 0.5 : 0;
    const RuntimeOptions unlimited{.error_px = 0.5, .transition_zone = seed % 3 ? 0.25 : 0, .hysteresis = 0.1, .transition_seconds = seconds};
    // `twin` runs without the budget, to show that it binds.
    LodRuntime runtime(unlimited), twin(unlimited);
    for (int i = 0; i < 300; ++i) scene.add(runtime, &twin);
    // An eighth of the way from all-coarsest to what the threshold alone wants at the start.
    const uint64_t wanted = runtime.update(camera_at({0, 0, 0}), 0).triangles;
    twin.update(camera_at({0, 0, 0}), 0);
    ASSERT_GT(wanted, scene.coarsest());
    const uint64_t budget = scene.coarsest() + (wanted - scene.coarsest()) / 8;
    RuntimeOptions options = runtime.options();
    options.triangle_budget = budget;
    runtime.set_options(options);

    std::map<uint64_t, DrawItem> before;
    float3 eye{0, 0, 0}, velocity{0, 0, 0};
    uint64_t pops = 0, morphs = 0, binding = 0;
    for (int frame = 0; frame < 400; ++frame) {
      bool added = frame == 0;  // the budget was just set: objects on screen may have to jump
      if (frame % 50 == 25) {
        for (int i = 0; i < 5; ++i) scene.remove_one(runtime, &twin);
        for (int i = 0; i < 5; ++i) scene.add(runtime, &twin);
        added = true;
      }
      // A damped random walk through the objects (up to about 10 units per frame).
      velocity = {0.9f * velocity.x + 2 * scene.u(scene.rng) - 1, 0.9f * velocity.y + 2 * scene.u(scene.rng) - 1, 0.9f * velocity.z + 2 * scene.u(scene.rng) - 1};
      eye = {std::clamp(eye.x + velocity.x, -80.f, 80.f), std::clamp(eye.y + velocity.y, -80.f, 80.f), std::clamp(eye.z + velocity.z, -80.f, 80.f)};
      const double dt = scene.u(scene.rng) / 30;
      const DrawList& list = runtime.update(camera_at(eye), dt);
      binding += twin.update(camera_at(eye), dt).triangles > budget;

      ASSERT_EQ(list.items.size(), scene.ids.size());
      uint64_t triangles = 0;
      std::map<uint64_t, DrawItem> now;
      for (const DrawItem& item : list.items) {
        const auto& levels = scene.chains.at(Scene::key(item.object));
        ASSERT_LT(item.level, levels.size());
        ASSERT_LT(item.target, levels.size());
        triangles += levels[item.level].triangles;
        now[Scene::key(item.object)] = item;
        if (seconds > 0 && !list.pops && before.count(Scene::key(item.object)))
          expect_smooth(before[Scene::key(item.object)], item, dt / seconds, "seed " + std::to_string(seed) + " frame " + std::to_string(frame));
      }
      EXPECT_EQ(list.triangles, triangles);
      if (scene.coarsest() <= budget) {
        EXPECT_LE(triangles, budget) << "seed " << seed << " frame " << frame;
        EXPECT_FALSE(list.over_budget);
      } else {  // added objects made it unachievable: everything at its coarsest, reported
        EXPECT_TRUE(list.over_budget);
        EXPECT_EQ(triangles, scene.coarsest());
      }
      // Jumps only make room for added objects.
      if (!added) {
        EXPECT_EQ(list.pops, 0u) << "seed " << seed << " frame " << frame;
      }
      pops += list.pops;
      morphs += list.morphing;
      before = std::move(now);
    }
    if (seconds > 0) {
      EXPECT_GT(morphs, 0u);
    }
    EXPECT_GT(binding, 200u) << "without the budget, most frames should exceed it";
    RecordProperty("pops_seed_" + std::to_string(seed), int(pops));
  }
}

TEST(RuntimeBudget, UnachievableBudgetIsReported) {
  Scene scene(9);
  LodRuntime runtime({.error_px = 0.5});
  for (int i = 0; i < 50; ++i) scene.add(runtime);
  runtime.set_options({.error_px = 0.5, .triangle_budget = scene.coarsest() - 1});
  const DrawList& list = runtime.update(camera_at({0, 0, 0}), 1.0 / 60);
  EXPECT_TRUE(list.over_budget);
  EXPECT_EQ(list.triangles, scene.coarsest());
  for (const DrawItem& item : list.items) EXPECT_EQ(item.level, scene.chains.at(Scene::key(item.object)).size() - 1);
  runtime.set_options({.error_px = 0.5, .triangle_budget = scene.coarsest()});
  EXPECT_FALSE(runtime.update(camera_at({0, 0, 0}), 1.0 / 60).over_budget);
}

// ---- the API --------------------------------------------------------------------------------------

TEST(RuntimeApi, DeterministicAcrossRuns) {
  auto run = [] {
    Scene scene(5);
    LodRuntime runtime({.error_px = 0.5, .triangle_budget = 400000});
    for (int i = 0; i < 200; ++i) scene.add(runtime);
    std::vector<DrawItem> all;
    for (int frame = 0; frame < 200; ++frame) {
      if (frame % 40 == 10) scene.remove_one(runtime), scene.add(runtime);
      const DrawList& list = runtime.update(camera_at({float(frame) - 100, 0, 0}), 1.0 / 60);
      all.insert(all.end(), list.items.begin(), list.items.end());
    }
    return all;
  };
  const std::vector<DrawItem> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << i;
}

TEST(RuntimeApi, NoAllocationPerFrame) {
  Scene scene(2);
  LodRuntime runtime({.error_px = 0.5, .transition_seconds = 0.5});
  for (int i = 0; i < 500; ++i) scene.add(runtime);
  runtime.set_options({.error_px = 0.5, .transition_seconds = 0.5, .triangle_budget = scene.coarsest() + 100000});
  runtime.update(camera_at({0, 0, 0}), 0);  // the first frame sizes the scratch
  allocations = 0;
  counting = true;
  for (int frame = 0; frame < 200; ++frame) runtime.update(camera_at({float(frame) - 100, 0, 0}), 1.0 / 60);
  counting = false;
  EXPECT_EQ(allocations, 0u);
}

TEST(RuntimeApi, IdsAndValidation) {
  LodRuntime runtime;
  const auto levels = four_levels();
  const ObjectId a = runtime.add({{0, 0, 0}, 1}, levels), b = runtime.add({{5, 0, 0}, 1}, levels);
  EXPECT_EQ(runtime.size(), 2u);
  runtime.remove(a);
  EXPECT_FALSE(runtime.contains(a));
  EXPECT_TRUE(runtime.contains(b));
  const ObjectId c = runtime.add({{0, 0, 0}, 1}, levels);  // reuses a's slot with a new generation
  EXPECT_NE(c, a);
  auto usage = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return e.category() == ErrorCategory::usage;
    }
    return false;
  };
  EXPECT_TRUE(usage([&] { runtime.remove(a); }));
  EXPECT_TRUE(usage([&] { runtime.set_transform(a, {}); }));
  EXPECT_TRUE(usage([&] { runtime.add({{0, 0, 0}, 1}, {}); }));
  const RuntimeLevel growing[] = {{0, 100}, {0.1f, 200}};
  EXPECT_TRUE(usage([&] { runtime.add({{0, 0, 0}, 1}, growing); }));
  const RuntimeLevel shrinking_error[] = {{0.2f, 100}, {0.1f, 50}};
  EXPECT_TRUE(usage([&] { runtime.add({{0, 0, 0}, 1}, shrinking_error); }));
  EXPECT_TRUE(usage([&] { runtime.add({{0, 0, 0}, -1}, levels); }));
  EXPECT_TRUE(usage([&] { runtime.update(camera_at({0, 0, 0}), -1); }));
  EXPECT_TRUE(usage([&] { runtime.update({.position = {0, 0, 0}, .fov = 0}, 0); }));
  EXPECT_TRUE(usage([&] { LodRuntime bad({.transition_zone = 2}); }));
  EXPECT_EQ(runtime.size(), 2u);
  const DrawList& list = runtime.update(camera_at({0, 0, 20}), 0);
  ASSERT_EQ(list.items.size(), 2u);
  EXPECT_NO_THROW(item_of(list, b));
  EXPECT_NO_THROW(item_of(list, c));
}

TEST(RuntimeApi, LevelsFromAChain) {
  const LodChain chain = build_lod_chain(shapes::icosphere(3), {.levels = 3});
  const std::vector<RuntimeLevel> levels = runtime_levels(chain);
  // The certified bound, not the sampled error.
  ASSERT_EQ(levels.size(), 3u);
  float error = 0;
  for (size_t i = 0; i < levels.size(); ++i) {
    EXPECT_EQ(levels[i].triangles, chain.levels[i].mesh.triangle_count());
    error = std::max(error, chain.levels[i].error_bound);
    EXPECT_EQ(levels[i].error, error);
  }
  EXPECT_EQ(levels[0].triangles, 1280u);
  LodRuntime runtime;
  EXPECT_NO_THROW(runtime.add(bounding_sphere(chain.levels[0].mesh), levels));
}

TEST(RuntimeApi, BoundingSphereContainsTheMesh) {
  const Mesh mesh = shapes::icosphere(2);
  const BoundingSphere s = bounding_sphere(mesh);
  for (const float3& p : mesh.positions) {
    const float dx = p.x - s.center.x, dy = p.y - s.center.y, dz = p.z - s.center.z;
    EXPECT_LE(std::sqrt(dx * dx + dy * dy + dz * dz), s.radius);
  }
  EXPECT_NEAR(s.radius, 1.0f, 1e-5f);  // the unit icosphere
}

}  // namespace
}  // namespace lod
