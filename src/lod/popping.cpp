// Popping: the per-frame screen displacement of a LOD chain's drawn surface along a camera flight,
// with geomorphs and with hard switches, driven by the LodRuntime.
#include <algorithm>
#include <cmath>

#include "lodkit/error.h"
#include "lodkit/lod.h"
#include "lodkit/runtime.h"

namespace lod {

namespace {

// image[L][v]: the vertex of level L that finest vertex v has become (chains through the tables).
std::vector<std::vector<uint32_t>> images(const LodChain& chain) {
  std::vector<std::vector<uint32_t>> image(chain.levels.size());
  image[0].resize(chain.levels[0].mesh.vertex_count());
  for (uint32_t v = 0; v < image[0].size(); ++v) image[0][v] = v;
  for (size_t l = 1; l < chain.levels.size(); ++l) {
    image[l].resize(image[0].size());
    for (size_t v = 0; v < image[0].size(); ++v) image[l][v] = chain.morphs[l - 1].target[image[l - 1][v]];
  }
  return image;
}

PoppingRun fly(const LodChain& chain, const std::vector<std::vector<uint32_t>>& image, const PoppingOptions& o,
               double transition_seconds) {
  const Mesh& finest = chain.levels[0].mesh;
  const std::vector<float3> normal = smooth_normals(finest);
  const BoundingSphere bounds = bounding_sphere(finest);
  const std::vector<RuntimeLevel> levels = runtime_levels(chain);
  LodRuntime runtime({.error_px = o.error_px, .transition_zone = transition_seconds > 0 ? o.transition_zone : 0.0,
                      .transition_seconds = transition_seconds});
  runtime.add(bounds, levels);

  // From where even the coarsest level is within the threshold (twice as far), past the object, to
  // as far on the other side.
  const double coarsest = std::max(levels.back().error, 1e-6f * float(chain.diagonal));
  const double far = 2 * coarsest * o.screen_height / (2 * o.error_px * std::tan(o.fov / 2)) + bounds.radius;
  // Closest approach: half the finest switch distance, but outside the bounding sphere (inside it
  // the runtime draws the finest level anyway, and vertices at the eye would project without bound).
  const double near = std::max(1.1 * bounds.radius, 0.5 * (levels.size() > 1 ? levels[1].error : coarsest) *
                                                        o.screen_height / (2 * o.error_px * std::tan(o.fov / 2)));
  const uint32_t frames = uint32_t(std::max(2.0, std::round(o.fps * o.flight_seconds)));
  const double dt = 1 / o.fps;

  PoppingRun run;
  run.frames = frames;
  std::vector<float3> previous, current(image[0].size());
  uint32_t last_level = ~0u;
  double sum = 0;
  for (uint32_t f = 0; f < frames; ++f) {
    // Along x through the closest approach at (0, near, 0) from the sphere's centre.
    const double s = -1 + 2 * double(f) / double(frames - 1);
    const double x = s * std::sqrt(std::max(0.0, far * far - near * near));
    const float3 eye = {float(bounds.center.x + x), float(bounds.center.y + near), bounds.center.z};
    const DrawItem item = runtime.update({.position = eye, .fov = o.fov, .screen_height = o.screen_height}, dt).items[0];
    const Mesh& drawn = chain.levels[item.level].mesh;
    const Mesh& toward = chain.levels[item.target].mesh;
    for (size_t v = 0; v < current.size(); ++v) {
      const float3& a = drawn.positions[image[item.level][v]];
      const float3& b = toward.positions[image[item.target][v]];
      const float t = item.target == item.level ? 0.0f : item.t;
      current[v] = {(1 - t) * a.x + t * b.x, (1 - t) * a.y + t * b.y, (1 - t) * a.z + t * b.z};
    }
    if (last_level != ~0u && item.level != last_level) ++run.level_changes;
    last_level = item.level;
    float moved = 0;
    if (!previous.empty()) {
      for (size_t v = 0; v < current.size(); ++v) {
        const double dx = current[v].x - previous[v].x, dy = current[v].y - previous[v].y, dz = current[v].z - previous[v].z;
        // The surface moves by the displacement across it: sliding along the surface (a vertex
        // following its collapse over a flat part) changes nothing visible.
        const double across = std::fabs(dx * normal[v].x + dy * normal[v].y + dz * normal[v].z);
        const double d2 = across * across;
        if (d2 == 0) continue;
        // Pixels per object unit at the vertex's distance (perspective, conservative: the whole
        // displacement, as if across the view direction).
        const double ex = current[v].x - eye.x, ey = current[v].y - eye.y, ez = current[v].z - eye.z;
        const double depth = std::max(1e-9, std::sqrt(ex * ex + ey * ey + ez * ez));
        moved = std::max(moved, float(std::sqrt(d2) * o.screen_height / (2 * depth * std::tan(o.fov / 2))));
      }
    }
    run.per_frame_px.push_back(moved);
    run.max_px = std::max(run.max_px, double(moved));
    if (moved > 0) ++run.moving_frames, sum += moved;
    previous = current;
  }
  run.mean_px = run.moving_frames ? sum / run.moving_frames : 0;
  return run;
}

}  // namespace

PoppingResult measure_popping(const LodChain& chain, const PoppingOptions& options) {
  if (chain.levels.empty() || chain.morphs.size() + 1 != chain.levels.size())
    throw_usage("popping: the chain needs geomorph tables (build it with LodOptions::morph)");
  if (!(options.fps > 0) || !(options.flight_seconds > 0) || !(options.transition_seconds > 0))
    throw_usage("popping: fps, flight_seconds and transition_seconds must be > 0");
  const auto image = images(chain);
  return {fly(chain, image, options, options.transition_seconds), fly(chain, image, options, 0.0)};
}

}  // namespace lod
