// The optimize benchmark's program: lodkit and meshoptimizer on the same index buffer, one tool and
// one operation per process (so /usr/bin/time -v gives each its own peak memory).
//
//   lodkit_bench_optimize TOOL OP IN RUNS [--min-seconds S] [--json]
//     TOOL lodkit | meshopt | meshopt-fifo
//     OP   vcache16 | vcache32: vertex-cache order for a FIFO cache of 16 or 32 entries.
//              lodkit: lod::optimize_vertex_cache with that cache size (FIFO);
//              meshopt: meshopt_optimizeVertexCache (it takes no cache size);
//              meshopt-fifo: meshopt_optimizeVertexCacheFifo with that cache size (Tipsify).
//          strip | strip-restart: strips joined by degenerate triangles or by a restart index.
//              lodkit: lod::stripify, method best (its own vertex-cache order inside, FIFO 16);
//              meshopt: meshopt_optimizeVertexCacheStrip then meshopt_stripify (both timed).
//          sgi | sgi-restart: lodkit only, lod::stripify with the SGI method (the baseline).
//          overdraw: vertex-cache order (FIFO 16) then the overdraw order (threshold 1.05), both timed.
//              lodkit: lod::optimize_vertex_cache then lod::optimize_overdraw;
//              meshopt: meshopt_optimizeVertexCache then meshopt_optimizeOverdraw.
//          The overdraw op and vcache16 also report overdraw (lodkit's analyzer and
//          meshopt_analyzeOverdraw).
//   lodkit_bench_optimize make-input MESH OUT LEVEL: MESH subdivided 1->4 LEVEL times, binary PLY.
//
// IN is read with lodkit's reader; every tool gets the same index buffer (positions and triangles,
// attributes dropped). Only the library calls are timed (steady_clock), RUNS times or, with
// --min-seconds, until the runs add up to S seconds (at most 1000 runs: small meshes take
// microseconds, and a median over many runs is steadier); the median is reported.
// Every result is checked before it is reported: a reordered list must hold the same triangles with
// the same winding, a strip must decode to them (lod::unstripify); a failed check exits 3. ACMR and
// ATVR are measured with lodkit's analyzer (FIFO 16 and 32, LRU 16) for every tool, and with
// meshopt_analyzeVertexCache for comparison.
#include <meshoptimizer.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "lodkit/io.h"
#include "lodkit/optimize.h"
#include "median.h"

namespace {

using Clock = std::chrono::steady_clock;

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

// Triangles as rotation-normalised triples (smallest index first, winding kept), sorted.
std::vector<std::array<uint32_t, 3>> triangle_multiset(const std::vector<uint32_t>& indices) {
  std::vector<std::array<uint32_t, 3>> t;
  t.reserve(indices.size() / 3);
  for (size_t k = 0; k + 2 < indices.size(); k += 3) {
    std::array<uint32_t, 3> a = {indices[k], indices[k + 1], indices[k + 2]};
    while (a[0] > a[1] || a[0] > a[2]) a = {a[1], a[2], a[0]};
    t.push_back(a);
  }
  std::sort(t.begin(), t.end());
  return t;
}

// The input's non-degenerate triangles (strips leave the degenerate ones out, for every tool).
std::vector<uint32_t> without_degenerate(const std::vector<uint32_t>& indices) {
  std::vector<uint32_t> out;
  for (size_t k = 0; k + 2 < indices.size(); k += 3)
    if (indices[k] != indices[k + 1] && indices[k + 1] != indices[k + 2] && indices[k] != indices[k + 2])
      out.insert(out.end(), {indices[k], indices[k + 1], indices[k + 2]});
  return out;
}

int make_input(const std::string& source, const std::string& out, int level) {
  if (std::filesystem::is_regular_file(out) && std::filesystem::last_write_time(out) >= std::filesystem::last_write_time(source)) {
    std::printf("up to date: %s\n", out.c_str());
    return 0;
  }
  lod::Mesh full = lod::read_mesh(source), mesh;
  mesh.positions = std::move(full.positions);
  mesh.indices = std::move(full.indices);
  for (int l = 0; l < level; ++l) mesh = lod::subdivide_midpoint(mesh);
  std::filesystem::create_directories(std::filesystem::path(out).parent_path());
  lod::write_mesh(mesh, out, {.binary = true});
  std::printf("wrote %s: %zu triangles\n", out.c_str(), mesh.triangle_count());
  return 0;
}

int run(const std::string& tool, const std::string& op, const std::string& input, int runs, double min_seconds, bool json) {
  lod::Mesh mesh;
  {
    lod::Mesh full = lod::read_mesh(input);
    lod::validate(full, input);
    mesh.positions = std::move(full.positions);
    mesh.indices = std::move(full.indices);
  }
  const size_t V = mesh.vertex_count();
  const std::vector<uint32_t>& in = mesh.indices;
  const bool is_strip = op.rfind("strip", 0) == 0 || op.rfind("sgi", 0) == 0;
  const bool restart = op.size() > 8 && op.compare(op.size() - 8, 8, "-restart") == 0;
  const uint32_t cache = op == "vcache32" ? 32 : 16;
  const bool is_overdraw = op == "overdraw";
  if (!is_strip && !is_overdraw && op != "vcache16" && op != "vcache32") throw std::invalid_argument("unknown OP " + op);
  if (is_overdraw && tool == "meshopt-fifo") throw std::invalid_argument("overdraw is lodkit's or meshopt's");
  if (tool != "lodkit" && tool != "meshopt" && tool != "meshopt-fifo") throw std::invalid_argument("unknown TOOL " + tool);
  if (op.rfind("sgi", 0) == 0 && tool != "lodkit") throw std::invalid_argument("sgi is lodkit's only");
  if (is_strip && tool == "meshopt-fifo") throw std::invalid_argument("meshopt-fifo only orders for the cache");

  // The operation: returns the output buffer (a triangle list, or a strip buffer).
  std::function<std::vector<uint32_t>()> operation;
  const std::vector<lod::float3>& positions = mesh.positions;
  if (is_overdraw) {
    if (tool == "lodkit")
      operation = [&] {
        const std::vector<uint32_t> ordered = lod::optimize_vertex_cache(in, V, {.cache_size = 16, .policy = lod::CachePolicy::fifo});
        return lod::optimize_overdraw(ordered, positions, {.cache_size = 16, .threshold = 1.05f});
      };
    else
      operation = [&] {
        std::vector<uint32_t> ordered(in.size()), out(in.size());
        meshopt_optimizeVertexCache(ordered.data(), in.data(), in.size(), V);
        meshopt_optimizeOverdraw(out.data(), ordered.data(), in.size(), &positions[0].x, V, sizeof(lod::float3), 1.05f);
        return out;
      };
  } else if (!is_strip) {
    if (tool == "lodkit")
      operation = [&] { return lod::optimize_vertex_cache(in, V, {.cache_size = cache, .policy = lod::CachePolicy::fifo}); };
    else if (tool == "meshopt")
      operation = [&] {
        std::vector<uint32_t> out(in.size());
        meshopt_optimizeVertexCache(out.data(), in.data(), in.size(), V);
        return out;
      };
    else
      operation = [&] {
        std::vector<uint32_t> out(in.size());
        meshopt_optimizeVertexCacheFifo(out.data(), in.data(), in.size(), V, cache);
        return out;
      };
  } else if (tool == "lodkit") {
    const lod::StripMethod method = op.rfind("sgi", 0) == 0 ? lod::StripMethod::sgi : lod::StripMethod::best;
    operation = [&, method] {
      return lod::stripify(in, V, {.method = method, .use_restart = restart, .restart_index = 0xFFFFFFFFu, .cache_size = 16}).indices;
    };
  } else {
    operation = [&] {
      std::vector<uint32_t> ordered(in.size());
      meshopt_optimizeVertexCacheStrip(ordered.data(), in.data(), in.size(), V);
      std::vector<uint32_t> out(meshopt_stripifyBound(in.size()));
      out.resize(meshopt_stripify(out.data(), ordered.data(), in.size(), V, restart ? 0xFFFFFFFFu : 0u));
      return out;
    };
  }

  const double rss_before = peak_rss_mib();
  std::vector<double> seconds;
  std::vector<uint32_t> out;
  double total = 0;
  for (int r = 0; r < runs || (total < min_seconds && r < 1000); ++r) {
    const auto start = Clock::now();
    out = operation();
    seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    total += seconds.back();
  }

  // Check, then measure the triangle list the GPU would draw.
  const std::vector<uint32_t> list = is_strip ? lod::unstripify(out, restart, 0xFFFFFFFFu) : out;
  if (triangle_multiset(list) != triangle_multiset(is_strip ? without_degenerate(in) : in)) {
    std::fprintf(stderr, "%s %s %s: the output does not hold the input's triangles\n", tool.c_str(), op.c_str(), input.c_str());
    return 3;
  }
  nlohmann::json j = {{"tool", tool}, {"op", op}, {"input", input}, {"triangles", mesh.triangle_count()}, {"vertices", V},
                      {"runs", seconds.size()}, {"median_s", bench::median(seconds)},
                      {"min_s", *std::min_element(seconds.begin(), seconds.end())}, {"rss_before_runs_mib", rss_before}};
  for (const uint32_t k : {16u, 32u}) {
    const lod::VertexCacheStats s = lod::analyze_vertex_cache(list, V, {.cache_size = k, .policy = lod::CachePolicy::fifo});
    j["acmr_fifo" + std::to_string(k)] = s.acmr;
    j["atvr_fifo" + std::to_string(k)] = s.atvr;
    j["acmr_meshopt_analyzer" + std::to_string(k)] = meshopt_analyzeVertexCache(list.data(), list.size(), V, k, 0, 0).acmr;
  }
  j["acmr_lru16"] = lod::analyze_vertex_cache(list, V, {.cache_size = 16, .policy = lod::CachePolicy::lru}).acmr;
  j["acmr_input_fifo16"] = lod::analyze_vertex_cache(in, V, {.cache_size = 16}).acmr;
  if (is_overdraw || op == "vcache16") {
    j["overdraw"] = lod::analyze_overdraw(list, positions).overdraw;
    j["overdraw_meshopt_analyzer"] = meshopt_analyzeOverdraw(list.data(), list.size(), &positions[0].x, V, sizeof(lod::float3)).overdraw;
  }
  if (is_strip) {
    const lod::StripStats s = lod::analyze_strips(out, restart, 0xFFFFFFFFu);
    j["strip_indices"] = s.indices;
    j["strips"] = s.strips;
    j["strip_triangles"] = s.triangles;
    j["indices_per_triangle"] = s.indices_per_triangle;
  }
  if (json) std::printf("%s\n", j.dump().c_str());
  else std::printf("%s\n", j.dump(2).c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> a(argv + 1, argv + argc);
  try {
    if (a.size() == 4 && a[0] == "make-input") return make_input(a[1], a[2], std::stoi(a[3]));
    if (a.size() < 4) throw std::invalid_argument("usage");
    const bool json = std::find(a.begin(), a.end(), "--json") != a.end();
    double min_seconds = 0;
    for (size_t i = 4; i + 1 < a.size(); ++i)
      if (a[i] == "--min-seconds") min_seconds = std::stod(a[i + 1]);
    return run(a[0], a[1], a[2], std::stoi(a[3]), min_seconds, json);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr,
                 "lodkit_bench_optimize: %s\nusage: lodkit_bench_optimize lodkit|meshopt|meshopt-fifo "
                 "vcache16|vcache32|strip|strip-restart|sgi|sgi-restart|overdraw IN RUNS [--min-seconds S] [--json]\n"
                 "       lodkit_bench_optimize make-input MESH OUT LEVEL\n",
                 e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodkit_bench_optimize: %s\n", e.what());
    return 2;
  }
}
