// Image metrics: coverage (silhouette) difference, per-pixel depth difference and the largest
// screen-space displacement of the silhouette, between two images and over many views.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "lodkit/error.h"
#include "lodkit/render.h"

namespace lod {

namespace {

constexpr float infinity = std::numeric_limits<float>::infinity();

// Covered pixels with an uncovered 4-neighbour, or on the image border.
std::vector<uint8_t> silhouette(const Image& image) {
  const uint32_t w = image.width, h = image.height;
  std::vector<uint8_t> edge(size_t(w) * h, 0);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      if (!image.covered(x, y)) continue;
      edge[size_t(y) * w + x] = x == 0 || y == 0 || x + 1 == w || y + 1 == h || !image.covered(x - 1, y) ||
                                !image.covered(x + 1, y) || !image.covered(x, y - 1) || !image.covered(x, y + 1);
    }
  return edge;
}

// Squared distance along one line to the nearest seed (Felzenszwalb and Huttenlocher's lower envelope
// of parabolas): f holds 0 at seeds and +infinity elsewhere on input, or the previous pass's values.
void distance_1d(std::vector<double>& f, size_t n, std::vector<double>& d, std::vector<size_t>& v, std::vector<double>& z) {
  size_t k = 0;
  size_t first = n;
  for (size_t q = 0; q < n; ++q)
    if (f[q] < infinity) {
      first = q;
      break;
    }
  if (first == n) return;  // no seed on this line: all infinite
  v[0] = first;
  z[0] = -infinity;
  z[1] = infinity;
  for (size_t q = first + 1; q < n; ++q) {
    if (!(f[q] < infinity)) continue;
    double s;
    while (true) {  // z[0] is -infinity, so k stops at 0
      const double p = double(v[k]);
      s = ((f[q] + double(q) * q) - (f[v[k]] + p * p)) / (2.0 * (double(q) - p));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = infinity;
  }
  k = 0;
  for (size_t q = 0; q < n; ++q) {
    while (z[k + 1] < double(q)) ++k;
    const double dq = double(q) - double(v[k]);
    d[q] = dq * dq + f[v[k]];
  }
  std::copy(d.begin(), d.begin() + ptrdiff_t(n), f.begin());
}

// Exact squared Euclidean distance from every pixel to the nearest set pixel of `seeds`.
std::vector<double> squared_distance(const std::vector<uint8_t>& seeds, uint32_t w, uint32_t h) {
  std::vector<double> grid(size_t(w) * h);
  for (size_t i = 0; i < grid.size(); ++i) grid[i] = seeds[i] ? 0.0 : infinity;
  const size_t n = std::max(w, h);
  std::vector<double> line(n), d(n), z(n + 1);
  std::vector<size_t> v(n);
  for (uint32_t x = 0; x < w; ++x) {
    for (uint32_t y = 0; y < h; ++y) line[y] = grid[size_t(y) * w + x];
    distance_1d(line, h, d, v, z);
    for (uint32_t y = 0; y < h; ++y) grid[size_t(y) * w + x] = line[y];
  }
  for (uint32_t y = 0; y < h; ++y) {
    std::copy_n(&grid[size_t(y) * w], w, line.begin());
    distance_1d(line, w, d, v, z);
    std::copy_n(line.begin(), w, &grid[size_t(y) * w]);
  }
  return grid;
}

// The largest distance from a pixel of `from` to the nearest pixel of `to`, in pixels.
double directed_distance(const std::vector<uint8_t>& from, const std::vector<double>& to_distance) {
  double worst = 0;
  for (size_t i = 0; i < from.size(); ++i)
    if (from[i]) worst = std::max(worst, to_distance[i]);
  return std::sqrt(worst);
}

}  // namespace

ImageDifference compare_images(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw_usage("compare_images: the images differ in size (" + std::to_string(a.width) + "x" +
                std::to_string(a.height) + " and " + std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
  const size_t pixels = size_t(a.width) * a.height;
  if (a.depth.size() != pixels || b.depth.size() != pixels) throw_usage("compare_images: both images need depth");
  ImageDifference r;
  double depth_sum = 0;
  for (size_t i = 0; i < pixels; ++i) {
    const bool ca = a.depth[i] != infinity, cb = b.depth[i] != infinity;
    r.covered_a += ca;
    r.covered_b += cb;
    r.covered_one += ca != cb;
    if (ca && cb) {
      ++r.covered_both;
      const double d = std::abs(double(a.depth[i]) - double(b.depth[i]));
      depth_sum += d;
      r.max_depth_difference = std::max(r.max_depth_difference, d);
    }
  }
  const uint64_t either = r.covered_both + r.covered_one;
  r.coverage_difference = either ? double(r.covered_one) / double(either) : 0.0;
  r.mean_depth_difference = r.covered_both ? depth_sum / double(r.covered_both) : 0.0;
  if (r.covered_a == 0 || r.covered_b == 0) {
    r.silhouette_displacement_px = r.covered_a == r.covered_b ? 0.0 : std::numeric_limits<double>::infinity();
    return r;
  }
  const std::vector<uint8_t> sa = silhouette(a), sb = silhouette(b);
  r.silhouette_displacement_px = std::max(directed_distance(sa, squared_distance(sb, b.width, b.height)),
                                          directed_distance(sb, squared_distance(sa, a.width, a.height)));
  return r;
}

ViewsDifference compare_views(RenderContext& context, const Mesh& a, const Mesh& b, const ViewDifferenceOptions& options) {
  if (options.views == 0) throw_usage("compare_views: at least one view");
  const GpuMesh ga(context, a, "a"), gb(context, b, "b");
  const RenderOptions render_options{.width = options.width, .height = options.height, .samples = 1};
  ViewsDifference r;
  double depth_sum = 0;
  uint64_t depth_pixels = 0;
  for (const float3& direction : sphere_directions(options.views)) {
    const RenderCamera camera = fit_camera(ga.bounds(), direction, double(options.width) / options.height, options.fov,
                                           options.orthographic);
    const ImageDifference d =
        compare_images(render(context, ga, camera, render_options), render(context, gb, camera, render_options));
    r.max_coverage_difference = std::max(r.max_coverage_difference, d.coverage_difference);
    r.max_depth_difference = std::max(r.max_depth_difference, d.max_depth_difference);
    r.max_silhouette_displacement_px = std::max(r.max_silhouette_displacement_px, d.silhouette_displacement_px);
    depth_sum += d.mean_depth_difference * double(d.covered_both);
    depth_pixels += d.covered_both;
    r.cameras.push_back(camera);
    r.views.push_back(d);
  }
  r.mean_depth_difference = depth_pixels ? depth_sum / double(depth_pixels) : 0.0;
  return r;
}

}  // namespace lod
