// The closest-point BVH alone (measure/bvh.h), which lod::compare and the simplifier's final fit
// build and query: the median build time of TriangleBvh over a mesh's triangles, and of one query
// per K-th vertex moved off the surface (closest(), each from the last answer, as a walk would).
// --coherent builds by halving the triangles' Morton order (of their centroids, 10 bits an axis, as
// the bench computes it; the time to sort is not counted) instead of by SAH, as the simplifier's fit
// does over the input.
//
//   lodkit_bench_bvh MESH [--threads T] [--runs R] [--stride K] [--coherent] [--json]
//
// "checksum" sums the answers (squared distances and triangle ids): it must not change when only the
// build does, since every tree gives a brute-force scan's answers.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "harness.h"
#include "measure/bvh.h"

int main(int argc, char** argv) {
  return bench::run_main("lodkit_bench_bvh", "lodkit_bench_bvh MESH [--threads T] [--runs R] [--stride K] [--coherent] [--json]", [&] {
    std::vector<std::string> a(argv + 1, argv + argc);
    std::string file;
    unsigned threads = 0;
    int runs = 5;
    size_t stride = 7;
    bool json = false, coherent = false;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == "--threads" && i + 1 < a.size()) threads = unsigned(std::stoul(a[++i]));
      else if (a[i] == "--runs" && i + 1 < a.size()) runs = std::max(1, std::stoi(a[++i]));
      else if (a[i] == "--stride" && i + 1 < a.size()) stride = std::max<size_t>(1, std::stoull(a[++i]));
      else if (a[i] == "--json") json = true;
      else if (a[i] == "--coherent") coherent = true;
      else if (a[i].rfind("--", 0) == 0) throw std::invalid_argument("unknown option " + a[i]);
      else file = a[i];
    }
    if (file.empty()) throw std::invalid_argument("expected a mesh");
    const lod::Mesh mesh = bench::load_positions(file);
    // Query points: vertices moved by a hundredth of the bounding box's extent.
    lod::float3 low, high;
    lod::bounding_box(mesh, low, high);
    const float lo[3] = {low.x, low.y, low.z}, hi[3] = {high.x, high.y, high.z};
    const float offset = 0.01f * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    std::vector<uint32_t> order;
    if (coherent) {
      const auto spread = [](uint32_t x) {  // 10 bits to every third of 30
        x &= 0x3ff;
        x = (x | x << 16) & 0x030000ff, x = (x | x << 8) & 0x0300f00f;
        x = (x | x << 4) & 0x030c30c3, x = (x | x << 2) & 0x09249249;
        return x;
      };
      std::vector<std::pair<uint32_t, uint32_t>> keyed(mesh.triangle_count());
      for (uint32_t t = 0; t < keyed.size(); ++t) {
        uint32_t code = 0;
        for (int k = 0; k < 3; ++k) {
          float c = 0;
          for (int j = 0; j < 3; ++j) c += (&mesh.positions[mesh.indices[3 * size_t(t) + j]].x)[k] / 3;
          const float unit = hi[k] > lo[k] ? (c - lo[k]) / (hi[k] - lo[k]) : 0;
          code |= spread(uint32_t(std::clamp(unit, 0.0f, 1.0f) * 1023)) << k;
        }
        keyed[t] = {code, t};
      }
      std::sort(keyed.begin(), keyed.end());
      for (const auto& [code, t] : keyed) order.push_back(t);
    }
    std::vector<double> build, query;
    double checksum = 0;
    size_t nodes = 0;
    const auto now = [] { return std::chrono::steady_clock::now(); };
    const auto seconds = [](auto from, auto to) { return std::chrono::duration<double>(to - from).count(); };
    for (int r = 0; r < runs; ++r) {
      const auto start = now();
      const lod::measure::TriangleBvh bvh(mesh, order, threads);
      const auto built = now();
      double sum = 0;
      uint32_t hint = 0;
      for (size_t v = 0; v < mesh.positions.size(); v += stride) {
        const lod::float3& p = mesh.positions[v];
        const lod::measure::ClosestHit hit = bvh.closest(lod::measure::vec3f(p.x + offset, p.y - offset, p.z + offset), hint);
        hint = hit.triangle;
        sum += double(hit.distance_squared) + double(hit.triangle);
      }
      build.push_back(seconds(start, built)), query.push_back(seconds(built, now()));
      checksum = sum, nodes = bvh.node_count();
    }
    const auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    const nlohmann::json j = {{"tool", "lodkit_bench_bvh"},    {"input", file},
                              {"triangles", mesh.triangle_count()}, {"threads", threads}, {"coherent", coherent},
                              {"nodes", nodes},                  {"build_seconds", median(build)},
                              {"query_seconds", median(query)},  {"build_runs", build},
                              {"checksum", checksum}};
    if (json) std::printf("%s\n", j.dump().c_str());
    else
      std::printf("%zu triangles, %zu nodes: build %.4f s, queries %.4f s (medians of %d), checksum %.17g\n",
                  mesh.triangle_count(), nodes, median(build), median(query), runs, checksum);
    return 0;
  });
}
