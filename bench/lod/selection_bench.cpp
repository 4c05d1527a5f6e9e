// Selection cost (issue 6): one LodRuntime::update for 10,000 objects, as a game loop calls it once
// per frame, with the camera flying through the scene.
//
//   lodkit_bench_selection [--benchmark_...]     Google Benchmark flags (--benchmark_format=json ...)
//
// The scene: a 100 x 100 grid of objects 10 units apart, bounding radii 1 to 3, five levels each
// (10k to 50k triangles, halving; errors 0.1% of the radius times 4^level). The camera flies along
// the grid's diagonal at 40 units per second, 1080 pixels high, 60 degree vertical field of view, one
// pixel threshold, dt = 1/60 s. Deterministic: the same frames in every run.
//
// Variants: `plain` (zones, hysteresis, 1 s morphs), `budget` (the same plus a triangle budget half
// way between all-coarsest and what the threshold wants, so the greedy runs over all objects twice a
// frame) and `hard` (no morphs).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "lodkit/runtime.h"

namespace {

constexpr int kSide = 100;  // kSide^2 objects
constexpr float kSpacing = 10;

struct Scene {
  lod::LodRuntime runtime;
  uint64_t finest = 0, coarsest = 0;
  double time = 0;
};

void fill(Scene& scene) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < kSide; ++i)
    for (int j = 0; j < kSide; ++j) {
      const float radius = 1 + 2 * u(rng);
      std::vector<lod::RuntimeLevel> levels;
      uint32_t triangles = 10000 + uint32_t(40000 * u(rng));
      for (int k = 0; k < 5; ++k) {
        levels.push_back({k ? 0.001f * radius * float(1 << (2 * k)) : 0.0f, triangles});
        triangles /= 2;
      }
      scene.finest += levels.front().triangles;
      scene.coarsest += levels.back().triangles;
      scene.runtime.add({{i * kSpacing, 0, j * kSpacing}, radius}, levels);
    }
}

// Along the diagonal and back, 2 units above the objects.
lod::Camera camera(double time) {
  const double extent = (kSide - 1) * kSpacing;
  const double s = std::fmod(40 * time, 2 * extent * std::sqrt(2.0)) / std::sqrt(2.0);
  const double x = s < extent ? s : 2 * extent - s;
  return {.position = {float(x), 2, float(x)}, .fov = 1.0471975511965976, .screen_height = 1080};
}

void run(benchmark::State& state, lod::RuntimeOptions options, bool budget) {
  Scene scene{lod::LodRuntime(options)};
  fill(scene);
  if (budget) {
    // Half way from every object's coarsest level to what the threshold alone draws on the first
    // frame: it binds everywhere, and objects still move between levels.
    const uint64_t wanted = scene.runtime.update(camera(0), 0).triangles;
    options.triangle_budget = scene.coarsest + (wanted - scene.coarsest) / 2;
    scene.runtime.set_options(options);
  }
  // Warm up: one second of flight, so morphs are under way and the scratch is sized.
  for (int frame = 0; frame < 60; ++frame) scene.runtime.update(camera(scene.time += 1.0 / 60), 1.0 / 60);

  uint64_t morphing = 0, triangles = 0, frames = 0;
  for (auto _ : state) {
    const lod::DrawList& list = scene.runtime.update(camera(scene.time += 1.0 / 60), 1.0 / 60);
    benchmark::DoNotOptimize(list.items.data());
    morphing += list.morphing, triangles += list.triangles, ++frames;
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kSide * kSide);
  state.counters["objects"] = kSide * kSide;
  state.counters["morphing"] = double(morphing) / double(frames);
  state.counters["triangles"] = double(triangles) / double(frames);
  if (budget) state.counters["budget"] = double(scene.runtime.options().triangle_budget);
}

void BM_Selection_plain(benchmark::State& state) { run(state, {}, false); }
void BM_Selection_budget(benchmark::State& state) { run(state, {}, true); }
void BM_Selection_hard(benchmark::State& state) {
  run(state, {.transition_zone = 0, .hysteresis = 0, .transition_seconds = 0}, false);
}

BENCHMARK(BM_Selection_plain)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Selection_budget)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Selection_hard)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
