// lodkit's side of the simplification benchmark, timed exactly like the peers (bench/peers/harness.h).
//
//   lodkit_bench_simplify METRIC IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S] [--threads N] [--search 0|1]
//       METRIC: edge, qem, cqem, memoryless, cmemoryless. The timed call is lod::simplify with
//       record = false (no collapse record: the peers keep none either) and threads N (0: all).
//       --search 0 turns SimplifyOptions' search off (the metric-family table times the metrics
//       themselves); by default it is on, as a user gets it.
//       lod::simplify takes the mesh by const reference, so nothing is rebuilt between runs.
//   lodkit_bench_simplify make-inputs MESH OUT_DIR LEVEL...
//       for each LEVEL, MESH subdivided 1->4 LEVEL times (lod::subdivide_midpoint), positions only,
//       written to OUT_DIR/STEM-sLEVEL.ply (binary); a file newer than MESH is kept.
#include <cstdio>
#include <filesystem>
#include <thread>

#include "harness.h"
#include "lodkit/simplify.h"

namespace {

int make_inputs(const std::filesystem::path& source, const std::filesystem::path& out_dir, const std::vector<int>& levels) {
  std::filesystem::create_directories(out_dir);
  lod::Mesh mesh;
  int level = 0;
  for (const int wanted : levels) {
    const std::filesystem::path out = out_dir / (source.stem().string() + "-s" + std::to_string(wanted) + ".ply");
    if (std::filesystem::is_regular_file(out) && std::filesystem::last_write_time(out) >= std::filesystem::last_write_time(source)) {
      std::printf("up to date: %s\n", out.c_str());
      continue;
    }
    if (mesh.positions.empty() || level > wanted) mesh = bench::load_positions(source), level = 0;
    while (level < wanted) mesh = lod::subdivide_midpoint(mesh), ++level;
    lod::write_mesh(mesh, out, {.binary = true});
    std::printf("wrote %s: %zu triangles, %zu vertices\n", out.c_str(), mesh.triangle_count(), mesh.vertex_count());
  }
  return 0;
}

lod::Metric parse_metric(const std::string& name) {
  for (const lod::Metric m : {lod::Metric::edge_length, lod::Metric::qem, lod::Metric::constrained_qem, lod::Metric::memoryless,
                              lod::Metric::constrained_memoryless})
    if (name == lod::metric_name(m)) return m;
  throw std::invalid_argument("unknown metric " + name);
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage =
      "lodkit_bench_simplify edge|qem|cqem|memoryless|cmemoryless IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S] [--threads N]\n"
      "       lodkit_bench_simplify make-inputs MESH OUT_DIR LEVEL...";
  return bench::run_main("lodkit_bench_simplify", usage, [&] {
    if (argc >= 5 && std::string(argv[1]) == "make-inputs") {
      std::vector<int> levels;
      for (int i = 4; i < argc; ++i) levels.push_back(std::stoi(argv[i]));
      std::sort(levels.begin(), levels.end());
      return make_inputs(argv[2], argv[3], levels);
    }
    const bench::Args args = bench::parse_args(argc, argv, {"edge", "qem", "cqem", "memoryless", "cmemoryless"});
    const unsigned threads = unsigned(std::stoul(bench::option(args, "--threads", "0")));
    const bool search = bench::option(args, "--search", "1") != "0";
    const lod::Mesh input = bench::load_positions(args.input);
    const lod::SimplifyOptions options{
        .target_ratio = 0.0f,
        .target_triangles = args.target_triangles,
        .metric = parse_metric(args.mode),
        .search_input_triangles = search ? lod::SimplifyOptions{}.search_input_triangles : 0,
        .record = false,
        .threads = threads,
    };
    const double rss = bench::peak_rss_mib();
    std::vector<double> seconds;
    lod::SimplifyResult result;
    // The previous run's result is freed before the next, untimed, so no run holds two results.
    bench::timed_runs(args, seconds, [&] { return result = lod::SimplifyResult{}, 0; }, [&](int&) { result = lod::simplify(input, options); });
    nlohmann::json steps;  // the last run's collapse time by step (SimplifyResult::seconds_steps)
    for (const auto& [name, value] : result.seconds_steps.named()) steps[name] = value;
    bench::finish("lodkit", args, input, result.mesh, seconds, rss,
                  {{"threads", threads},
                   {"hardware_threads", std::thread::hardware_concurrency()},
                   {"relative_error", result.relative_error},
                   {"passes", result.passes},
                   {"seconds_setup", result.seconds_setup},
                   {"seconds_collapse", result.seconds_collapse},
                   {"seconds_fit", result.seconds_fit},
                   {"seconds_steps", steps}});
    return 0;
  });
}
