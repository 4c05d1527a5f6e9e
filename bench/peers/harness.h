// The simplification benchmark's common harness, shared by every peer program and by lodkit's driver,
// so that all tools are loaded, timed and reported the same way:
//
//   PROG [MODE] IN OUT TARGET_TRIANGLES RUNS [--json] [--budget SECONDS] [tool options]
//
// - IN is read with lodkit's reader and reduced to positions and triangles (every tool gets the same
//   floats and indices; attributes would be extra work for some tools only).
// - Converting to the tool's own structure is untimed and is redone before every run (simplification
//   mutates it). Only the simplification call is timed, with steady_clock.
// - --budget S: no further run starts once the timed runs add up to S seconds (at least one run is
//   always done); "runs" in the JSON is the number done. It bounds the bench on slow cases.
// - The last run's result is written to OUT with lodkit's writer (".ply" binary); "-" writes nothing.
// - One JSON line: tool, mode, input, triangles in/out, the times, median/min/max, and the process's
//   peak RSS before the first run (getrusage), so the report can tell loading from simplifying.
//   scripts/bench.sh adds the whole process's peak RSS from /usr/bin/time -v.
#pragma once

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "lodkit/io.h"
#include "median.h"
#include "lodkit/mesh.h"

namespace bench {

struct Args {
  std::string mode, input, output;
  uint64_t target_triangles = 0;
  int runs = 1;
  double budget_seconds = 0;  // 0: no budget
  bool json = false;
  std::vector<std::string> options;  // whatever follows, for the tool to read
};

// `modes` empty: the tool takes no MODE argument.
inline Args parse_args(int argc, char** argv, const std::vector<std::string>& modes) {
  std::vector<std::string> a(argv + 1, argv + argc);
  Args args;
  size_t i = 0;
  if (!modes.empty()) {
    if (a.empty() || std::find(modes.begin(), modes.end(), a[0]) == modes.end()) throw std::invalid_argument("unknown or missing MODE");
    args.mode = a[i++];
  }
  if (a.size() < i + 4) throw std::invalid_argument("expected IN OUT TARGET_TRIANGLES RUNS");
  args.input = a[i], args.output = a[i + 1];
  args.target_triangles = std::stoull(a[i + 2]);
  args.runs = std::stoi(a[i + 3]);
  if (args.runs < 1) throw std::invalid_argument("RUNS must be at least 1");
  for (i += 4; i < a.size(); ++i) {
    if (a[i] == "--json") args.json = true;
    else if (a[i] == "--budget" && i + 1 < a.size()) args.budget_seconds = std::stod(a[++i]);
    else args.options.push_back(a[i]);
  }
  return args;
}

// The value after `name` in the options, or `fallback`.
inline std::string option(const Args& args, const std::string& name, const std::string& fallback) {
  for (size_t i = 0; i + 1 < args.options.size(); ++i)
    if (args.options[i] == name) return args.options[i + 1];
  return fallback;
}

// Positions and triangles only.
inline lod::Mesh load_positions(const std::string& path) {
  lod::Mesh full = lod::read_mesh(path);
  lod::validate(full, path);
  lod::Mesh mesh;
  mesh.positions = std::move(full.positions);
  mesh.indices = std::move(full.indices);
  return mesh;
}

// Triangles over unique positions (lod::position_ids), dropping triangles that then repeat a corner:
// what a halfedge structure (CGAL, OpenMesh) is built from, so an attribute seam is not a cut.
struct Welded {
  std::vector<lod::float3> positions;
  std::vector<uint32_t> indices;
};
inline Welded weld(const lod::Mesh& mesh) {
  const lod::PositionIds ids = lod::position_ids(mesh);
  Welded w;
  w.positions.resize(ids.count);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) w.positions[ids.id[v]] = mesh.positions[v];
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t a = ids.id[mesh.indices[3 * t]], b = ids.id[mesh.indices[3 * t + 1]], c = ids.id[mesh.indices[3 * t + 2]];
    if (a == b || b == c || a == c) continue;
    w.indices.insert(w.indices.end(), {a, b, c});
  }
  return w;
}

// A mesh of the referenced positions only, in order of first use (untimed; for writing the result).
inline lod::Mesh compact(const std::vector<lod::float3>& positions, const std::vector<uint32_t>& indices) {
  lod::Mesh out;
  std::vector<uint32_t> remap(positions.size(), UINT32_MAX);
  out.indices.reserve(indices.size());
  for (const uint32_t v : indices) {
    if (remap[v] == UINT32_MAX) remap[v] = uint32_t(out.positions.size()), out.positions.push_back(positions[v]);
    out.indices.push_back(remap[v]);
  }
  return out;
}

inline double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

// args.runs times (or until the budget is spent): state = setup() untimed, then simplify(state)
// timed. Returns the last state.
template <class Setup, class Simplify>
auto timed_runs(const Args& args, std::vector<double>& seconds, Setup setup, Simplify simplify) {
  auto state = setup();
  double total = 0;
  for (int r = 0; r < args.runs; ++r) {
    if (r > 0) {
      if (args.budget_seconds > 0 && total >= args.budget_seconds) break;
      state = setup();
    }
    const auto start = std::chrono::steady_clock::now();
    simplify(state);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    total += seconds.back();
  }
  return state;
}

// Writes the result (unless OUT is "-") and prints the report line. `extra` adds tool-specific keys.
inline void finish(const std::string& tool, const Args& args, const lod::Mesh& input, const lod::Mesh& result,
                   const std::vector<double>& seconds, double rss_before_runs_mib, nlohmann::json extra = nlohmann::json::object()) {
  if (args.output != "-") lod::write_mesh(result, args.output, {.binary = true});
  nlohmann::json j = {{"tool", tool},
                      {"mode", args.mode},
                      {"input", args.input},
                      {"output", args.output},
                      {"target_triangles", args.target_triangles},
                      {"triangles_in", input.triangle_count()},
                      {"vertices_in", input.vertex_count()},
                      {"triangles_out", result.triangle_count()},
                      {"vertices_out", result.vertex_count()},
                      {"runs", seconds.size()},
                      {"runs_asked", args.runs},
                      {"times", seconds},
                      {"median_s", median(seconds)},
                      {"min_s", *std::min_element(seconds.begin(), seconds.end())},
                      {"max_s", *std::max_element(seconds.begin(), seconds.end())},
                      {"rss_before_runs_mib", rss_before_runs_mib}};
  j.update(extra);
  if (args.json) {
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s %s %s: %zu -> %zu triangles, median %.4f s (min %.4f, max %.4f) over %zu runs\n", tool.c_str(),
                args.mode.c_str(), args.input.c_str(), input.triangle_count(), result.triangle_count(), j["median_s"].get<double>(),
                j["min_s"].get<double>(), j["max_s"].get<double>(), seconds.size());
  }
}

// main() of every tool: usage errors exit 1, failures 2, with one line on stderr.
template <class Body>
int run_main(const char* program, const char* usage, Body body) {
  try {
    return body();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: %s\nusage: %s\n", program, e.what(), usage);
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return 2;
  }
}

}  // namespace bench
