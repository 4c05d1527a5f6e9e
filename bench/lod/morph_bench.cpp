// Geomorph throughput: lod::morph_positions (P' = (1 - t) P + t P_target for every vertex of the
// finer level) against a plain memcpy of the same position bytes, in the same process, one core.
// Houle measured 1.5 M interpolations/s on a 600 MHz CPU; the target is morph <= 3x memcpy.
//
//   lodkit_bench_morph MESH [RUNS=15] [--json]
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "median.h"

namespace {
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    fmt::print(stderr, "usage: lodkit_bench_morph MESH [RUNS=15] [--json]\n");
    return 2;
  }
  const int runs = argc > 2 && argv[2][0] != '-' ? std::max(1, std::atoi(argv[2])) : 15;
  const bool json = std::string(argv[argc - 1]) == "--json";
  lod::Mesh mesh = lod::read_mesh(argv[1]);
  // Enough vertices that the arrays leave the caches, as a real character or scan would.
  while (mesh.vertex_count() < 1'000'000) mesh = lod::subdivide_midpoint(mesh);
  const lod::LodChain chain = lod::build_lod_chain(mesh, {.ratios = {1.0f, 0.5f}, .morph = true, .measure = false});
  const lod::Mesh &fine = chain.levels[0].mesh, &coarse = chain.levels[1].mesh;
  const lod::Geomorph& table = chain.morphs[0];
  const size_t n = fine.vertex_count();

  std::vector<lod::float3> out(n), copy(n);
  std::vector<double> morph_s, copy_s;
  double checksum = 0;
  for (int r = 0; r < runs; ++r) {
    const float t = float(r + 1) / float(runs + 1);
    auto a = std::chrono::steady_clock::now();
    lod::morph_positions(fine.positions, coarse.positions, table, t, out);
    auto b = std::chrono::steady_clock::now();
    std::memcpy(copy.data(), fine.positions.data(), n * sizeof(lod::float3));
    auto c = std::chrono::steady_clock::now();
    morph_s.push_back(std::chrono::duration<double>(b - a).count());
    copy_s.push_back(std::chrono::duration<double>(c - b).count());
    checksum += out[size_t(r) % n].x + copy[size_t(r) % n].y;  // keep both results alive
  }
  const double m = bench::median(morph_s), c = bench::median(copy_s);
  if (json) {
    fmt::print("{}\n", nlohmann::json{{"vertices", n}, {"runs", runs}, {"morph_s", m}, {"memcpy_s", c}, {"ratio", m / c},
                                      {"morph_vertices_per_s", double(n) / m}, {"checksum", checksum}}
                           .dump());
  } else {
    fmt::print("{:<28}{:>14}{:>18}\n", "", "median time", "vertices / s");
    fmt::print("{:<28}{:>13.3f}ms{:>18.3g}\n", "morph_positions", 1e3 * m, double(n) / m);
    fmt::print("{:<28}{:>13.3f}ms{:>18.3g}\n", "memcpy (same bytes)", 1e3 * c, double(n) / c);
    fmt::print("{} vertices, {} runs; morph / memcpy = {:.2f} (target <= 3)\n", n, runs, m / c);
  }
  return 0;
}
