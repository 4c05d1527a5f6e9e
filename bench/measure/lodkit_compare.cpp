// lod::compare with the options the CLI does not expose, for the measurement bench (issue 4):
//
//   lodkit_compare A B [--samples N] [--seed S] [--threads T] [--no-edges] [--refine] [--runs R] [--json]
//
// Loads both meshes as positions and triangles (bench/peers/harness.h, as cgal_distance does), then
// times lod::compare alone (both BVHs, sampling, queries), R times; "seconds" is the median, "runs"
// every time. --no-edges drops the edge samples (area samples and vertices only, as CGAL samples);
// --refine adds the certified refinement of the maximum and reports its upper bound.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "harness.h"
#include "lodkit/measure.h"

int main(int argc, char** argv) {
  return bench::run_main(
      "lodkit_compare", "lodkit_compare A B [--samples N] [--seed S] [--threads T] [--no-edges] [--refine] [--runs R] [--json]", [&] {
        std::vector<std::string> a(argv + 1, argv + argc);
        std::vector<std::string> files;
        lod::CompareOptions options;
        int runs = 1;
        bool json = false;
        for (size_t i = 0; i < a.size(); ++i) {
          if (a[i] == "--samples" && i + 1 < a.size()) options.samples = std::stoull(a[++i]);
          else if (a[i] == "--seed" && i + 1 < a.size()) options.seed = std::stoull(a[++i]);
          else if (a[i] == "--threads" && i + 1 < a.size()) options.threads = unsigned(std::stoul(a[++i]));
          else if (a[i] == "--runs" && i + 1 < a.size()) runs = std::max(1, std::stoi(a[++i]));
          else if (a[i] == "--no-edges") options.edge_samples = false;
          else if (a[i] == "--refine") options.refine = true;
          else if (a[i] == "--json") json = true;
          else if (a[i].rfind("--", 0) == 0) throw std::invalid_argument("unknown option " + a[i]);
          else files.push_back(a[i]);
        }
        if (files.size() != 2) throw std::invalid_argument("expected two meshes");
        options.attributes = false;  // positions only, as the peers
        const lod::Mesh ma = bench::load_positions(files[0]), mb = bench::load_positions(files[1]);
        lod::Deviation d;
        std::vector<double> times;
        for (int r = 0; r < runs; ++r) {
          const auto start = std::chrono::steady_clock::now();
          d = lod::compare(ma, mb, options);
          times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
        std::vector<double> sorted = times;
        std::sort(sorted.begin(), sorted.end());
        const double seconds = sorted[sorted.size() / 2];
        auto side = [](const lod::OneSidedDeviation& s) {
          return nlohmann::json{{"hausdorff", s.max}, {"max_bound", s.max_bound}, {"mean", s.mean}, {"rms", s.rms},
                                {"area_samples", s.area_samples}, {"vertex_samples", s.vertex_samples},
                                {"edge_samples", s.edge_samples}, {"refine_samples", s.refine_samples},
                                {"worst", {s.max_location.point.x, s.max_location.point.y, s.max_location.point.z}}};
        };
        const nlohmann::json j = {{"tool", "lodkit_compare"},
                                  {"a", files[0]},
                                  {"b", files[1]},
                                  {"edges", options.edge_samples},
                                  {"refine", options.refine},
                                  {"threads", options.threads},
                                  {"diagonal", d.diagonal},
                                  {"hausdorff", d.hausdorff},
                                  {"hausdorff_bound", d.hausdorff_bound},
                                  {"rms", d.rms},
                                  {"mean", d.mean},
                                  {"hausdorff_relative", d.relative_hausdorff},
                                  {"hausdorff_bound_relative", d.relative_hausdorff_bound},
                                  {"rms_relative", d.relative_rms},
                                  {"mean_relative", d.relative_mean},
                                  {"a_to_b", side(d.a_to_b)},
                                  {"b_to_a", side(d.b_to_a)},
                                  {"queries", d.queries},
                                  {"build_seconds", d.build_seconds},
                                  {"query_seconds", d.query_seconds},
                                  {"seconds", seconds},
                                  {"runs", times}};
        if (json) {
          std::printf("%s\n", j.dump().c_str());
        } else {
          std::printf("hausdorff %.6g (%.6g of diag), rms %.6g (%.6g); A->B %.6g, B->A %.6g; %llu queries, %.3f s\n",
                      d.hausdorff, d.relative_hausdorff, d.rms, d.relative_rms, d.a_to_b.max, d.b_to_a.max,
                      (unsigned long long)d.queries, seconds);
        }
        return 0;
      });
}
