// meshoptimizer 0.18 (Debian libmeshoptimizer-dev): meshopt_simplify on positions only, to the same
// triangle target, with no error limit (target_error = FLT_MAX) and no options.
//
//   peer_meshopt IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S] [--error E]
//
// --error E sets an error limit instead, E a fraction of the bounding-box diagonal as lodkit's
// --errors: meshopt_simplify's target_error is relative to meshopt_simplifyScale (the largest extent),
// so it gets E x diagonal / scale (the bench's levels by error, bench/lod/errors.py).
//
// meshopt_simplify reads the input buffers without changing them, so nothing is rebuilt between runs;
// the timed call is meshopt_simplify alone (it writes an index buffer over the original vertices, which
// is meshoptimizer's normal output; compacting the vertices for OUT is untimed).
#include <meshoptimizer.h>

#include <cfloat>
#include <cmath>

#include "harness.h"

int main(int argc, char** argv) {
  return bench::run_main("peer_meshopt", "peer_meshopt IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S]", [&] {
    const bench::Args args = bench::parse_args(argc, argv, {});
    const lod::Mesh input = bench::load_positions(args.input);
    float target_error = FLT_MAX;
    if (const std::string e = bench::option(args, "--error", ""); !e.empty()) {
      lod::float3 lo, hi;
      lod::bounding_box(input, lo, hi);
      const double dx = double(hi.x) - lo.x, dy = double(hi.y) - lo.y, dz = double(hi.z) - lo.z;
      const float scale = meshopt_simplifyScale(&input.positions[0].x, input.vertex_count(), sizeof(lod::float3));
      target_error = float(std::stod(e) * std::sqrt(dx * dx + dy * dy + dz * dz) / scale);
    }
    struct State {
      std::vector<uint32_t> destination;
      size_t index_count = 0;
      float result_error = 0;
    };
    const double rss = bench::peak_rss_mib();
    std::vector<double> seconds;
    State s = bench::timed_runs(args, seconds, [&] { return State{std::vector<uint32_t>(input.indices.size()), 0, 0.0f}; },
        [&](State& state) {
          state.index_count = meshopt_simplify(state.destination.data(), input.indices.data(), input.indices.size(),
                                               &input.positions[0].x, input.vertex_count(), sizeof(lod::float3),
                                               size_t(args.target_triangles) * 3, target_error, 0, &state.result_error);
        });
    s.destination.resize(s.index_count);
    const lod::Mesh result = bench::compact(input.positions, s.destination);
    bench::finish("meshopt", args, input, result, seconds, rss, {{"result_error_relative", s.result_error}});
    return 0;
  });
}
