// lodkit: distance between two surfaces (Metro-style Hausdorff, mean and RMS), attribute deviation
// and a per-vertex error field for heat maps.
//
//   lod::Deviation d = lod::compare(original, lod_mesh, {.samples = 1'000'000});
//   // d.hausdorff, d.a_to_b.rms, d.relative_hausdorff ...
//
// Each surface is sampled (area-uniform random points, every vertex, points along every edge) and
// each sample's closest point on the other surface is found exactly (a BVH over its triangles and
// the exact point-triangle distance). "a -> b" means samples on a, distances to b. The result is the
// same for any number of threads.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lodkit/mesh.h"

namespace lod {

struct CompareOptions {
  // Area samples on each surface, spread in proportion to triangle area (systematic: every triangle
  // gets its share rounded up or down, then uniform random positions inside it). 0 chooses
  // 10 per triangle of the larger mesh, at least 10'000 and at most 2'000'000.
  uint64_t samples = 0;
  uint64_t seed = 1;  // the random positions repeat for a given seed

  // Edge samples: points spread evenly along each edge, as far apart as the area samples (sqrt of
  // area / samples); their total is capped at half the area samples. Vertices are always sampled.
  bool edge_samples = true;

  // Refinement around the worst places: triangles whose upper bound on the distance exceeds the
  // largest sample are subdivided (1 -> 4) and their new corners measured, until the bound is within
  // refine_tolerance of the largest distance found or refine_budget extra queries are spent. The
  // bound is certified (up to float rounding): the distance to a surface is 1-Lipschitz, and the
  // distance to one triangle is convex, so over a patch it is at most its largest corner value.
  bool refine = false;
  float refine_tolerance = 1e-4f;  // fraction of a's bounding-box diagonal
  uint64_t refine_budget = 0;      // extra queries per direction; 0: as many as the area samples

  // Normal angle, UV and colour differences at the closest point, when both meshes carry them.
  bool attributes = true;

  unsigned threads = 0;  // 0: one per hardware thread. The result never depends on it.
  std::function<void(double fraction)> progress;  // fraction of the queries done; called from the caller's thread
};

// Where a distance was largest: a point on the sampled surface and its closest point on the other.
struct MaxLocation {
  float3 point;
  float3 closest;
  uint32_t triangle = 0;          // triangle of the sampled mesh holding `point`
  uint32_t closest_triangle = 0;  // triangle of the other mesh holding `closest`
  friend bool operator==(const MaxLocation&, const MaxLocation&) = default;
};

// Differences of interpolated attributes between each area sample and its closest point.
// Means are area-weighted (over the area samples). A flag is false when either mesh lacks the stream.
struct AttributeDeviation {
  bool normals = false;
  double max_normal_angle = 0, mean_normal_angle = 0;  // degrees between the unit interpolated normals
  bool uvs = false;
  double max_uv = 0, mean_uv = 0;  // Euclidean distance in UV set 0 units
  bool colors = false;
  double max_color = 0, mean_color = 0;  // Euclidean distance of linear RGBA in [0, 1]
  friend bool operator==(const AttributeDeviation&, const AttributeDeviation&) = default;
};

// One direction: samples on `from`, distances to `to`.
struct OneSidedDeviation {
  // Object space. `max` is over every sample (area, vertex, edge, refinement); mean and RMS are
  // area-weighted, from the area samples only (vertices and edges would bias them).
  double max = 0, mean = 0, rms = 0;
  // The same divided by the bounding-box diagonal of a (in both directions, so they compare).
  double relative_max = 0, relative_mean = 0, relative_rms = 0;
  MaxLocation max_location;
  // With refinement: an upper bound on the true one-sided Hausdorff distance (>= max); without it,
  // equal to max (no claim beyond the samples).
  double max_bound = 0, relative_max_bound = 0;
  bool refined = false;

  uint64_t area_samples = 0, vertex_samples = 0, edge_samples = 0, refine_samples = 0;
  double area = 0;  // surface area of `from`
  AttributeDeviation attributes;

  uint64_t samples() const { return area_samples + vertex_samples + edge_samples + refine_samples; }
  friend bool operator==(const OneSidedDeviation&, const OneSidedDeviation&) = default;
};

struct Deviation {
  OneSidedDeviation a_to_b, b_to_a;
  // Symmetric: Hausdorff is the larger one-sided max; mean and RMS are over both surfaces together
  // (area-weighted union of a's and b's area samples).
  double hausdorff = 0, mean = 0, rms = 0;
  double relative_hausdorff = 0, relative_mean = 0, relative_rms = 0;
  double hausdorff_bound = 0, relative_hausdorff_bound = 0;  // max of the one-sided bounds
  double diagonal = 0;  // bounding-box diagonal of a

  // Per vertex of a: its distance to b.
  std::vector<float> vertex_distance;
  // Per vertex of a: the largest distance to b measured in the vertex's region: at the vertex, and at
  // every sample (area, edge, refinement) of a triangle around it that lies nearer to it than to
  // that triangle's other corners. Its maximum is a_to_b.max, held by the corner of the maximum's
  // triangle nearest to it. Vertices sharing a position share the value; vertices used by no
  // triangle hold their own distance.
  std::vector<float> vertex_error;

  // Timing, not part of the result (it varies between runs).
  double build_seconds = 0;  // until the queries start: the smaller mesh's BVH, both surfaces' sample plans
  double query_seconds = 0;  // the rest: the samples drawn and queried (the larger BVH is built alongside)
  uint64_t queries = 0;      // closest-point queries made (deterministic)
};

// Throws lod::Error (bad_input) if either mesh has no triangle or fails lod::validate, and (usage)
// for options out of range.
Deviation compare(const Mesh& a, const Mesh& b, const CompareOptions& options = {});

// ---- heat maps ------------------------------------------------------------------------------------
// A fixed colour ramp over [0, 1]: blue, cyan, green, yellow, red (the hottest), linear RGB, alpha 1.
// Values outside [0, 1] are clamped. Each channel is a multiple of 1/255 (as k * (1.0 / 255) reads
// it): what a display shows, and what a PLY stores in unsigned bytes, the type every viewer reads.
float4 heat_color(float t);
inline constexpr const char* heat_ramp_names[] = {"blue", "cyan", "green", "yellow", "red"};

// A copy of `mesh`'s positions, normals and triangles whose vertex colours show `field / scale` on
// the ramp (scale > 0, else every vertex is blue). Write it with lod::write_mesh (PLY, glTF, OBJ, OFF).
Mesh heatmap_mesh(const Mesh& mesh, const std::vector<float>& field, float scale);

}  // namespace lod
