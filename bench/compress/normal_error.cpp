// lodkit_bench_normal_error REFERENCE CANDIDATE: how far a compressed file's normals stray from the
// reference's. Both scenes are flattened (a skinned character at rest); each candidate vertex is
// matched to the reference vertices at its position (the nearest, or any within two steps of a
// 14-bit grid over the reference's extent, as -q and gltfpack place positions), and its normal's
// angle to the nearest of their normals is its error. Prints JSON: {"max_degrees", "mean_degrees",
// "vertices"}. Tools that reorder vertices (gltfpack) are judged by the same measure.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <nlohmann/json.hpp>

#include "lodkit/io.h"

namespace {

// The angle between two directions, in degrees: atan2 of |a x b| and a . b, well conditioned near 0.
double degrees(const lod::float3& a, const lod::float3& b) {
  const double x = double(a.y) * b.z - double(a.z) * b.y, y = double(a.z) * b.x - double(a.x) * b.z, z = double(a.x) * b.y - double(a.y) * b.x;
  return std::atan2(std::hypot(x, y, z), double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z) * 180 / M_PI;
}

double distance(const lod::float3& a, const lod::float3& b) { return std::hypot(double(a.x) - b.x, double(a.y) - b.y, double(a.z) - b.z); }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: lodkit_bench_normal_error REFERENCE CANDIDATE\n");
    return 1;
  }
  try {
    const lod::Mesh ref = lod::flatten(lod::read_scene(argv[1])), got = lod::flatten(lod::read_scene(argv[2]));
    if (ref.normals.empty() || got.normals.empty()) throw std::runtime_error("a file without normals");
    double extent = 0;
    for (int c = 0; c < 3; ++c) {
      float lo = INFINITY, hi = -INFINITY;
      for (const lod::float3& p : ref.positions) lo = std::min(lo, (&p.x)[c]), hi = std::max(hi, (&p.x)[c]);
      extent = std::max(extent, double(hi) - lo);
    }
    const double radius = 2 * std::sqrt(3.0) * extent / 16383;
    double worst = 0, sum = 0;
    for (size_t v = 0; v < got.vertex_count(); ++v) {
      double nearest = INFINITY;
      for (const lod::float3& p : ref.positions) nearest = std::min(nearest, distance(got.positions[v], p));
      double error = INFINITY;
      for (size_t r = 0; r < ref.vertex_count(); ++r)
        if (distance(got.positions[v], ref.positions[r]) <= std::max(nearest, radius)) error = std::min(error, degrees(got.normals[v], ref.normals[r]));
      worst = std::max(worst, error), sum += error;
    }
    const nlohmann::json out = {{"max_degrees", worst}, {"mean_degrees", got.vertex_count() ? sum / double(got.vertex_count()) : 0.0},
                                {"vertices", got.vertex_count()}};
    std::printf("%s\n", out.dump().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodkit_bench_normal_error: %s\n", e.what());
    return 2;
  }
}
