// Overdraw-aware triangle order. The input order (from the vertex-cache optimiser) is cut into
// clusters of consecutive triangles, each starting where the simulated FIFO misses at least two
// corners of a triangle (a new fan away from the last), once the current cluster holds
// `min_cluster` triangles; the clusters are then drawn in order of decreasing occlusion potential, a
// view-independent guess at how much a cluster hides: how far its area-weighted centroid lies out
// from the mesh's centroid along its mean normal. Outer, outward-facing clusters go first, so the
// depth test rejects more of what they hide, from most directions. The first cluster size (16, 32,
// ... triangles) whose order keeps the FIFO misses within `threshold` times the input order's wins;
// if none does, the input order is returned.
#include <algorithm>
#include <cmath>

#include "lodkit/error.h"
#include "lodkit/optimize.h"

namespace lod {

namespace {

// FIFO misses of each triangle of `indices` in order (0 to 3).
std::vector<uint8_t> misses_per_triangle(std::span<const uint32_t> indices, size_t vertex_count, uint32_t cache_size) {
  std::vector<uint8_t> out(indices.size() / 3, 0);
  std::vector<uint64_t> entered(vertex_count, 0);
  uint64_t misses = 0;
  for (size_t k = 0; k < indices.size(); ++k) {
    const uint32_t v = indices[k];
    if (entered[v] && misses - entered[v] < cache_size) continue;
    entered[v] = ++misses;
    ++out[k / 3];
  }
  return out;
}

}  // namespace

std::vector<uint32_t> overdraw_order(std::span<const uint32_t> indices, std::span<const float3> positions,
                                     const OverdrawOrderOptions& options) {
  if (indices.size() % 3) throw_usage("optimize_overdraw: the index count is not a multiple of 3");
  if (options.cache_size < 3) throw_usage("optimize_overdraw: cache size must be at least 3");
  if (!(options.threshold >= 1)) throw_usage("optimize_overdraw: threshold must be at least 1");
  for (const uint32_t i : indices)
    if (i >= positions.size()) throw_usage("optimize_overdraw: index " + std::to_string(i) + " out of range");
  const size_t F = indices.size() / 3;
  std::vector<uint32_t> out(F);
  for (uint32_t t = 0; t < F; ++t) out[t] = t;
  if (F < 2) return out;

  // Per triangle: twice its area times its unit normal (the cross product) and its centroid; the
  // mesh's area-weighted centroid.
  std::vector<float3> area_normal(F), centroid(F);
  double cx = 0, cy = 0, cz = 0, total_area = 0;
  for (size_t t = 0; t < F; ++t) {
    const float3 a = positions[indices[3 * t]], b = positions[indices[3 * t + 1]], c = positions[indices[3 * t + 2]];
    const float ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    area_normal[t] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
    centroid[t] = {(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, (a.z + b.z + c.z) / 3};
    const double area = std::sqrt(double(area_normal[t].x) * area_normal[t].x + double(area_normal[t].y) * area_normal[t].y +
                                  double(area_normal[t].z) * area_normal[t].z);
    cx += area * centroid[t].x, cy += area * centroid[t].y, cz += area * centroid[t].z, total_area += area;
  }
  if (total_area > 0) cx /= total_area, cy /= total_area, cz /= total_area;

  const std::vector<uint8_t> misses = misses_per_triangle(indices, positions.size(), options.cache_size);
  uint64_t input_misses = 0;
  for (const uint8_t m : misses) input_misses += m;
  const double limit = double(input_misses) * options.threshold;

  struct Cluster {
    uint32_t begin, end;
    double potential;
  };
  std::vector<Cluster> clusters;
  std::vector<uint32_t> candidate(indices.size()), candidate_order(F);
  for (size_t min_cluster = 16; min_cluster < F; min_cluster *= 2) {
    clusters.clear();
    for (uint32_t begin = 0; begin < F;) {
      uint32_t end = begin + 1;
      while (end < F && (end - begin < min_cluster || misses[end] < 2)) ++end;
      // Occlusion potential: the signed distance of the cluster's centroid from the mesh's centroid
      // along the cluster's mean normal (both area-weighted).
      double nx = 0, ny = 0, nz = 0, px = 0, py = 0, pz = 0, area = 0;
      for (uint32_t t = begin; t < end; ++t) {
        const float3& n = area_normal[t];
        const double a = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
        nx += n.x, ny += n.y, nz += n.z;
        px += a * centroid[t].x, py += a * centroid[t].y, pz += a * centroid[t].z, area += a;
      }
      const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
      double potential = 0;
      if (area > 0 && length > 0) potential = ((px / area - cx) * nx + (py / area - cy) * ny + (pz / area - cz) * nz) / length;
      clusters.push_back({begin, end, potential});
      begin = end;
    }
    if (clusters.size() < 2) break;
    std::stable_sort(clusters.begin(), clusters.end(), [](const Cluster& a, const Cluster& b) { return a.potential > b.potential; });
    size_t k = 0;
    for (const Cluster& c : clusters)
      for (uint32_t t = c.begin; t < c.end; ++t) {
        candidate_order[k] = t;
        for (uint32_t j = 0; j < 3; ++j) candidate[3 * k + j] = indices[3 * size_t(t) + j];
        ++k;
      }
    uint64_t candidate_misses = 0;
    for (const uint8_t m : misses_per_triangle(candidate, positions.size(), options.cache_size)) candidate_misses += m;
    if (double(candidate_misses) <= limit) {
      out = std::move(candidate_order);
      break;
    }
  }
  return out;
}

std::vector<uint32_t> optimize_overdraw(std::span<const uint32_t> indices, std::span<const float3> positions,
                                        const OverdrawOrderOptions& options) {
  const std::vector<uint32_t> order = overdraw_order(indices, positions, options);
  std::vector<uint32_t> out(indices.size());
  for (size_t k = 0; k < order.size(); ++k)
    for (uint32_t c = 0; c < 3; ++c) out[3 * k + c] = indices[3 * size_t(order[k]) + c];
  return out;
}

}  // namespace lod
