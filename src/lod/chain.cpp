// Discrete LOD chains: levels by ratio or error, simplified from the previous level or the input,
// with certified error bounds, geomorph tables and an optional shared vertex buffer.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

#include "core/parallel.h"
#include "lod/internal.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"
#include "lodkit/measure.h"
#include "lodkit/optimize.h"

namespace lod {

namespace {

void check_options(const LodOptions& o) {
  if (!o.errors.empty() && !o.ratios.empty()) throw_usage("lod: give ratios or errors, not both");
  for (size_t i = 0; i < o.ratios.size(); ++i) {
    if (!(o.ratios[i] > 0 && o.ratios[i] <= 1)) throw_usage("lod: ratios must be in (0, 1]");
    if (i && !(o.ratios[i] < o.ratios[i - 1])) throw_usage("lod: ratios must decrease, finest first");
  }
  for (size_t i = 0; i < o.errors.size(); ++i) {
    if (!(o.errors[i] >= 0) || !std::isfinite(o.errors[i])) throw_usage("lod: errors must be finite and >= 0");
    if (i && !(o.errors[i] > o.errors[i - 1])) throw_usage("lod: errors must increase, finest first");
  }
  if (o.ratios.empty() && o.errors.empty() && (o.levels < 1 || o.levels > 32))
    throw_usage("lod: levels must be in [1, 32]");
  if (o.morph && !o.from_previous) throw_usage("lod: geomorphs need each level simplified from the previous one");
}

// Level i's vertices as indices into the input's, for the shared buffer.
SharedVertices share_vertices(const Mesh& input, const std::vector<LodLevel>& levels,
                              const std::vector<std::vector<uint32_t>>& origin) {
  // Coarsest level that uses each input vertex: the buffer lists the coarsest level's vertices
  // first, then those the next finer level adds, and so on.
  std::vector<int> coarsest(input.vertex_count(), -1);
  for (size_t i = 0; i < levels.size(); ++i)
    for (const uint32_t v : origin[i]) coarsest[v] = std::max(coarsest[v], int(i));
  std::vector<uint32_t> order;
  for (uint32_t v = 0; v < input.vertex_count(); ++v)
    if (coarsest[v] >= 0) order.push_back(v);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return coarsest[a] > coarsest[b]; });
  std::vector<uint32_t> slot(input.vertex_count(), ~0u);
  SharedVertices shared;
  for (uint32_t i = 0; i < order.size(); ++i) {
    slot[order[i]] = i;
    append_vertex(shared.vertices, input, order[i]);
  }
  shared.vertex_origin = std::move(order);
  for (size_t i = 0; i < levels.size(); ++i) {
    std::vector<uint32_t> indices;
    indices.reserve(levels[i].mesh.indices.size());
    for (const uint32_t v : levels[i].mesh.indices) indices.push_back(slot[origin[i][v]]);
    shared.indices.push_back(std::move(indices));
    shared.prefix.push_back(uint32_t(std::count_if(shared.vertex_origin.begin(), shared.vertex_origin.end(),
                                                   [&](uint32_t v) { return coarsest[v] >= int(i); })));
  }
  return shared;
}

uint64_t level_samples(const Mesh& input) { return std::clamp<uint64_t>(2 * input.triangle_count(), 2'000, 1'000'000); }

// Each level's measurement: the symmetric Hausdorff distance to the input with a certified bound.
Deviation measure_level(const Mesh& input, const Mesh& level, unsigned threads) {
  // Two samples per input triangle find the maximum well on meshes of that density; the
  // refinement then certifies a bound (it stops within its tolerance or at its budget). The
  // budget is eight times the samples: the default (as many) ran out on bunny00's levels,
  // leaving bounds 2-4x the error; four times closed them within the tolerance, for 1.2x the
  // build time. Where even this runs out, the bound is still certified, only looser.
  // A small mesh takes fewer samples but keeps the budget of 160,000 queries (8 x 20,000): the
  // refinement then finds what the samples miss, and its queries go where the bound is open (a
  // 288-triangle chain: 0.84x the build time, the same errors and bounds to 0.4%). Budget and
  // samples cut together left a cube-meshed level's bound 537x looser.
  const uint64_t samples = level_samples(input);
  const uint64_t budget = 8 * std::max<uint64_t>(samples, 20'000);
  return compare(input, level,
                 {.samples = samples, .refine = true, .refine_tolerance = 1e-5f, .refine_budget = budget,
                  .attributes = false, .threads = threads});
}

struct Attempt {
  SimplifyResult result;
  double distance = 0;  // sampled Hausdorff distance to the input (a lower bound)
};

// A level by error: simplified from `source` (at `source_distance` from the input: the previous
// level's bound, or 0) and as coarse as a few tries find, with its certified
// bound to the input within `limit` (object space); `deviation` gets that measurement. The
// simplifier's own error (the square root of a quadric cost) is only the first try's stop: the
// distance measured runs up to 3x past it (bunny00's --errors 0.001 gave 0.27% of the diagonal).
// Later tries ask for a triangle count, from the power law H ~ c / T^0.7 (measured on bunny00's
// levels: 0.6-0.8) through the nearest results on each side of the limit, inside that bracket, or
// halfway in the logarithm after two tries on the same side (a feature that fewer triangles do not
// change breaks the law). The search ends when the bracket is within 10% (the distance is noisy in
// the count below that) or after max_tries. Tries are judged by the sampled distance, a quarter of
// the refined measurement's cost; the coarsest within the limit is then certified (refined). If its
// bound is past the limit, the samples fell short: every try is judged again by its distance times
// that shortfall, and the search goes on (two more tries, at most twice). With no try left within
// the limit the source is kept (simplified to its own triangle count: no collapses).
SimplifyResult level_within(const Mesh& input, const Mesh& source, double source_distance, const SimplifyOptions& base, double limit,
                            const std::function<SimplifyResult(const Mesh&, const SimplifyOptions&)>& simplifier,
                            Deviation& deviation, const std::function<void(double)>& progress) {
  constexpr int max_tries = 6;
  constexpr double exponent = 0.7;
  // The source simplified to `target` triangles (0: none) or `max_error` (< 0: none).
  const auto simplified = [&](uint64_t target, float max_error) {
    SimplifyOptions so = base;
    so.target_ratio = 0, so.target_triangles = target, so.max_error = max_error, so.max_relative_error = -1;
    return simplifier ? simplifier(source, so) : simplify(source, so);
  };
  const auto attempt = [&](uint64_t target, float max_error) {
    Attempt a;
    a.result = simplified(target, max_error);
    a.distance = a.result.mesh.triangle_count()
                     ? compare(input, a.result.mesh, {.samples = level_samples(input), .attributes = false, .threads = base.threads})
                           .hausdorff
                     : std::numeric_limits<double>::infinity();  // nothing left: past any limit
    return a;
  };
  std::vector<Attempt> within;                           // tries within the limit
  uint64_t fine = source.triangle_count(), coarse = 0;  // the bracket: triangles within / past the limit
  double fine_h = source_distance, coarse_h = 0;         // their distances (0: the input itself)
  bool past = false;                                     // whether `coarse` is known
  // How far the sampled distance fell short of a certified bound that failed (from then on, tries
  // are judged by their distance times this).
  double shortfall = 1;
  int streak = 0;  // consecutive tries on the same side of the limit
  bool last_within = false;
  const auto set_past = [&](uint64_t t, double h) {
    if (!past || t > coarse) coarse = t, coarse_h = h, past = true;
  };
  const auto coarsest_within = [&] {
    return std::min_element(within.begin(), within.end(), [](const Attempt& x, const Attempt& y) {
      return x.result.mesh.triangle_count() < y.result.mesh.triangle_count();
    });
  };
  const auto take = [&](Attempt&& a) {
    const uint64_t t = a.result.mesh.triangle_count();
    const bool is_within = a.distance * shortfall <= limit;
    streak = is_within == last_within ? streak + 1 : 1, last_within = is_within;
    if (is_within) {
      if (within.empty() || t < fine) fine = t, fine_h = a.distance * shortfall;
      within.push_back(std::move(a));
    } else {
      set_past(t, a.distance * shortfall);
    }
  };
  // The next triangle count to try, or 0 when the bracket is closed.
  const auto next_target = [&]() -> uint64_t {
    // The power law needs a measured point past the limit (not an empty result).
    const bool scaled = past && coarse > 0 && std::isfinite(coarse_h);
    double t;
    if (past) {  // finer than `coarse`, coarser than `fine` (a try within the limit, or the source)
      if (double(fine) <= double(coarse) * 1.1 + 1) return 0;
      if (scaled && fine_h > 0 && coarse_h > fine_h)  // the law through both ends
        t = std::exp(std::log(double(coarse)) + (std::log(limit) - std::log(coarse_h)) *
                                                    (std::log(double(fine)) - std::log(double(coarse))) /
                                                    (std::log(fine_h) - std::log(coarse_h)));
      else if (scaled && streak < 2)  // the law from the coarse end
        t = double(coarse) * std::pow(coarse_h / limit, 1 / exponent);
      else  // twice past in a row, the law is off (a feature fewer triangles do not change): halfway
        t = std::sqrt(double(std::max<uint64_t>(coarse, 1)) * double(fine));
      // Kept off both ends by a sixth of the bracket, in the logarithm: a bracket up to the source
      // can span thousands of times (a first try past the limit at 86 triangles, the source at 75,408).
      const double step = std::pow(double(fine) / double(std::max<uint64_t>(coarse, 1)), 1.0 / 6);
      t = std::clamp(t, std::max<double>(coarse, 1) * step, double(fine) / step);
    } else {  // every try so far is within the limit: coarser
      if (fine <= 1) return 0;
      t = fine_h > 0 && streak < 2 ? double(fine) * std::pow(fine_h / limit, 1 / exponent) : double(fine) / 4;
      t = std::clamp(t, 1.0, double(fine) * 0.95);
    }
    const uint64_t target = uint64_t(std::llround(t));
    return target >= fine || (past && target <= coarse) ? 0 : target;
  };
  take(attempt(0, float(limit)));
  // Tries end at max_tries, plus two more after each certification that fails (at most two).
  for (int tries = 1, failed = 0;;) {
    const uint64_t target = tries < max_tries + 2 * failed ? next_target() : 0;
    if (target) {
      take(attempt(target, -1));
      ++tries;
      if (progress) progress(std::min(1.0, double(tries) / max_tries));
      continue;
    }
    if (within.empty()) break;
    const auto best = coarsest_within();
    deviation = measure_level(input, best->result.mesh, base.threads);
    if (deviation.hausdorff_bound <= limit) return std::move(best->result);
    // Its samples missed the maximum: past the limit after all. The other tries are judged again
    // with that shortfall, and the search goes on finer.
    shortfall = std::max(shortfall, deviation.hausdorff_bound / best->distance);
    std::vector<Attempt> tried = std::move(within);
    within.clear();
    fine = source.triangle_count(), fine_h = source_distance;
    for (Attempt& a : tried) take(std::move(a));
    streak = 1, last_within = false;  // the last verdict: the failed one, past
    failed = std::min(failed + 1, 2);
  }
  SimplifyResult kept = simplified(source.triangle_count(), -1);
  deviation = measure_level(input, kept.mesh, base.threads);
  return kept;
}

}  // namespace

LodChain build_lod_chain(const Mesh& input, const LodOptions& o) {
  check_options(o);
  validate(input, "lod input");
  LodChain chain;
  float3 lo, hi;
  bounding_box(input, lo, hi);
  chain.diagonal = std::sqrt(double(hi.x - lo.x) * (hi.x - lo.x) + double(hi.y - lo.y) * (hi.y - lo.y) +
                             double(hi.z - lo.z) * (hi.z - lo.z));

  // One entry per level: a ratio, or an error limit (then ratio 0).
  std::vector<float> ratios = o.ratios, errors;
  if (!o.errors.empty()) errors = o.errors, ratios.assign(o.errors.size(), 0.0f);
  if (ratios.empty())
    for (uint32_t i = 0; i < o.levels; ++i) ratios.push_back(std::ldexp(1.0f, -int(i)));

  const uint64_t input_triangles = input.triangle_count();
  std::vector<std::vector<uint32_t>> origin;  // per level: input vertex of each vertex
  std::vector<std::vector<uint32_t>> successor;  // per level: each input vertex's vertex (~0u: none)
  std::vector<bool> identity;                 // per level: the input itself (no error to measure)
  // Per level: its distance and bound when the search by error measured them (the Deviation's
  // per-vertex arrays are not kept).
  struct Measured {
    double error, bound;
  };
  std::vector<std::optional<Measured>> measured;
  const size_t count = ratios.size();
  // The build's progress after `levels` levels (the measurements, if any, are the second half).
  const auto built = [&](double levels) {
    if (o.progress) o.progress(levels / double(count) * (o.measure ? 0.5 : 1.0));
  };
  for (size_t i = 0; i < count; ++i) {
    const bool by_error = !errors.empty();
    const uint64_t target = by_error ? 0 : uint64_t(std::llround(double(ratios[i]) * double(input_triangles)));
    const bool previous = o.from_previous && i > 0;
    const Mesh& source = previous ? chain.levels.back().mesh : input;
    LodLevel level;
    std::vector<uint32_t> level_origin, level_successor;
    std::optional<Measured> found;
    if ((!by_error && target >= source.triangle_count() && !previous) || (by_error && errors[i] == 0 && !previous)) {
      // Everything kept: the input itself, vertex order and all.
      level.mesh = input;
      level_origin.resize(input.vertex_count());
      std::iota(level_origin.begin(), level_origin.end(), 0u);
      level_successor = level_origin;
    } else {
      SimplifyOptions so = o.simplify;
      so.target_ratio = 0;
      so.target_triangles = by_error ? 0 : std::max<uint64_t>(target, 1);
      if (by_error) so.max_error = errors[i] * chain.diagonal, so.max_relative_error = -1;
      so.record = o.morph;
      // A geomorph moves a level's vertices onto the next level's: that level's triangles must be
      // this one's after collapses alone.
      if (o.morph) so.fit_flips = false;
      if (o.shared_vertices) {
        so.keep_vertices = true;
        so.normal_weight = so.uv_weight = so.color_weight = 0;
      }
      SimplifyResult r;
      if (by_error && errors[i] > 0) {
        // Within the limit as measured (a limit of 0 keeps the engine's exact collapses only).
        // The source's own distance: the previous level's bound (0 for the input).
        const double source_distance = previous && measured.back() ? measured.back()->bound : 0.0;
        Deviation d;
        r = level_within(input, source, source_distance, so, double(errors[i]) * chain.diagonal, o.simplifier, d,
                         [&](double f) { built(double(i) + f); });
        found = Measured{d.hausdorff, d.hausdorff_bound};
      } else {
        r = o.simplifier ? o.simplifier(source, so) : simplify(source, so);
      }
      if (o.morph && previous) chain.morphs.push_back(geomorph_from_record(source, r));
      level.engine_error = (previous ? chain.levels.back().engine_error : 0.0f) + r.error;
      level_origin.resize(r.vertex_origin.size());
      for (size_t v = 0; v < r.vertex_origin.size(); ++v)
        level_origin[v] = previous ? origin.back()[r.vertex_origin[v]] : r.vertex_origin[v];
      if (previous) {  // through the previous level's vertices
        level_successor = successor.back();
        for (uint32_t& s : level_successor)
          if (s != ~0u) s = r.vertex_successor[s];
      } else {
        level_successor = std::move(r.vertex_successor);
      }
      level.mesh = std::move(r.mesh);
    }
    level.ratio = input_triangles ? float(double(level.mesh.triangle_count()) / double(input_triangles)) : 1.0f;
    level.error = level.error_bound = level.engine_error;
    identity.push_back(level.mesh.triangle_count() == input_triangles && level.engine_error == 0 && !previous &&
                       level_origin.size() == input.vertex_count());
    chain.levels.push_back(std::move(level));
    measured.push_back(found);
    origin.push_back(std::move(level_origin));
    successor.push_back(std::move(level_successor));
    built(double(i + 1));
  }

  if (o.optimize) {
    // new_index[i][v]: where vertex v of level i went.
    std::vector<std::vector<uint32_t>> new_index(count);
    for (size_t i = 0; i < count; ++i) {
      Mesh& m = chain.levels[i].mesh;
      m = reorder_triangles(m, vertex_cache_order(m.indices, m.vertex_count(), o.cache));
      new_index[i] = vertex_fetch_remap(m.indices, m.vertex_count());
      m = remap_vertices(m, new_index[i], m.vertex_count());
      std::vector<uint32_t> moved(origin[i].size());
      for (size_t v = 0; v < origin[i].size(); ++v) moved[new_index[i][v]] = origin[i][v];
      origin[i] = std::move(moved);
      for (uint32_t& s : successor[i])
        if (s != ~0u) s = new_index[i][s];
    }
    for (size_t i = 0; i < chain.morphs.size(); ++i) {
      std::vector<uint32_t> target(chain.morphs[i].target.size());
      for (size_t v = 0; v < target.size(); ++v) target[new_index[i][v]] = new_index[i + 1][chain.morphs[i].target[v]];
      chain.morphs[i].target = std::move(target);
    }
  }

  for (size_t i = 0; i < count; ++i) {
    LodLevel& level = chain.levels[i];
    if (measured[i]) {
      // The search measured this geometry already (the optimisation above only reorders it).
      level.error = float(measured[i]->error);
      level.error_bound = float(measured[i]->bound);
    } else if (o.measure && level.mesh.triangle_count() && !identity[i]) {
      const Deviation d = measure_level(input, level.mesh, o.simplify.threads);
      level.error = float(d.hausdorff);
      level.error_bound = float(d.hausdorff_bound);
    } else if (o.measure && !level.mesh.triangle_count()) {
      level.error = level.error_bound = chain.diagonal;  // nothing left
    }
    if (o.measure && o.progress) o.progress(0.5 + 0.5 * double(i + 1) / double(count));
  }
  for (LodLevel& level : chain.levels) level.relative_error = chain.diagonal > 0 ? level.error / chain.diagonal : 0;
  if (o.shared_vertices) chain.shared = share_vertices(input, chain.levels, origin);
  for (size_t i = 0; i < count; ++i)
    chain.levels[i].vertex_origin = std::move(origin[i]), chain.levels[i].vertex_successor = std::move(successor[i]);
  return chain;
}

std::vector<LodChain> build_lod_chains(std::span<const Mesh* const> meshes, const LodOptions& o) {
  check_options(o);
  std::vector<LodChain> chains(meshes.size());
  core::parallel_meshes(meshes, "lod: build_lod_chains", o.simplify.threads, o.progress,
                        [&](size_t i, unsigned threads, const std::function<void(double)>& progress) {
                          LodOptions one = o;
                          one.simplify.threads = threads;
                          one.progress = progress;
                          chains[i] = build_lod_chain(*meshes[i], one);
                        });
  return chains;
}

double switch_distance(double object_error, double pixels, double screen_height, double fov) {
  if (!(pixels > 0) || !(screen_height > 0) || !(fov > 0 && fov < M_PI)) throw_usage("switch_distance: bad camera");
  return object_error * screen_height / (2.0 * pixels * std::tan(fov / 2));
}

}  // namespace lod
