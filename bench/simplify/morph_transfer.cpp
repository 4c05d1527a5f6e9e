// scripts/bench.sh morphs: how well a simplification carries a morph target (a glTF blend shape)
// when its vertices move, and what that costs.
//
// Each corpus mesh gets a smooth morph field: offsets of 2% of the bounding-box diagonal, a few
// waves across it. It is simplified to 10% and 1% of its triangles (the default options), and the
// result's offsets are made two ways: interpolated on the input by lod::vertex_blends (what lodkit
// simplify writes), and, for comparison, each vertex's survivor's own offset (vertex_origin: what a
// subset simplifier such as meshoptimizer keeps). The morphed result is measured against the morphed
// input with lod::compare (symmetric Hausdorff and RMS over the diagonal), next to the rest pose's
// distances. Also the time of vertex_blends against the simplify call (medians of RUNS). Prints a
// markdown table.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "lodkit/io.h"
#include "median.h"
#include "lodkit/measure.h"
#include "lodkit/simplify.h"

using namespace lod;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// The morph field: waves of a few periods across the bounding box, amplitude 2% of its diagonal.
struct Field {
  float3 lo;
  float diagonal = 1;
  float3 operator()(const float3& p) const {
    const float x = (p.x - lo.x) / diagonal, y = (p.y - lo.y) / diagonal, z = (p.z - lo.z) / diagonal, a = 0.02f * diagonal;
    return {a * std::sin(12 * y), a * std::cos(10 * z), a * std::sin(11 * x + 4 * y)};
  }
};

Mesh displaced(Mesh m, const std::vector<float3>& offsets) {
  for (size_t v = 0; v < m.vertex_count(); ++v)
    m.positions[v] = {m.positions[v].x + offsets[v].x, m.positions[v].y + offsets[v].y, m.positions[v].z + offsets[v].z};
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: lodkit_bench_morph_transfer RUNS MESH...\n");
    return 2;
  }
  const int runs = std::max(1, std::atoi(argv[1]));
  std::printf("| mesh | ratio | rest H | rest RMS | interpolated H | interpolated RMS | survivor's H | survivor's RMS | simplify (s) | vertex_blends (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  int interpolated_rms_better = 0, interpolated_h_better = 0, cases = 0;
  for (int a = 2; a < argc; ++a) {
    const Mesh input = read_mesh(argv[a]);
    Field field;
    float3 hi;
    bounding_box(input, field.lo, hi);
    field.diagonal = std::hypot(hi.x - field.lo.x, hi.y - field.lo.y, hi.z - field.lo.z);
    std::vector<float3> offsets;
    for (const float3& p : input.positions) offsets.push_back(field(p));
    const Mesh morphed_input = displaced(input, offsets);
    for (const float ratio : {0.1f, 0.01f}) {
      std::vector<double> simplify_times, blend_times;
      SimplifyResult r;
      std::vector<VertexBlend> blends;
      for (int run = 0; run < runs; ++run) {
        double t = now();
        r = simplify(input, {.target_ratio = ratio, .record = false});
        simplify_times.push_back(now() - t);
        t = now();
        blends = vertex_blends(input, r.vertex_successor, r.mesh);
        blend_times.push_back(now() - t);
      }
      std::vector<float3> interpolated(r.mesh.vertex_count()), own(r.mesh.vertex_count());
      for (size_t v = 0; v < r.mesh.vertex_count(); ++v) {
        for (int k = 0; k < 3; ++k) {
          const float3& o = offsets[blends[v].vertex[k]];
          const float w = blends[v].weight[k];
          interpolated[v] = {interpolated[v].x + w * o.x, interpolated[v].y + w * o.y, interpolated[v].z + w * o.z};
        }
        own[v] = offsets[r.vertex_origin[v]];
      }
      const Deviation rest = compare(input, r.mesh);
      const Deviation with_blends = compare(morphed_input, displaced(r.mesh, interpolated));
      const Deviation with_own = compare(morphed_input, displaced(r.mesh, own));
      const double d = field.diagonal;
      std::string name = argv[a];
      name = name.substr(name.find_last_of('/') + 1);
      std::printf("| %s | %g%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.3f | %.4f |\n", name.c_str(), 100.0 * ratio,
                  100 * rest.hausdorff / d, 100 * rest.rms / d, 100 * with_blends.hausdorff / d, 100 * with_blends.rms / d,
                  100 * with_own.hausdorff / d, 100 * with_own.rms / d, bench::median(simplify_times), bench::median(blend_times));
      ++cases;
      interpolated_rms_better += with_blends.rms < with_own.rms;
      interpolated_h_better += with_blends.hausdorff < with_own.hausdorff;
    }
  }
  std::printf("\ninterpolated offsets nearer the morphed input than the survivors' own: RMS in %d of %d cases, Hausdorff in %d of %d\n",
              interpolated_rms_better, cases, interpolated_h_better, cases);
  return 0;
}
