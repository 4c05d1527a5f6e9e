// Heat maps: a fixed colour ramp, so maps made at different times compare by eye; the scale is the
// caller's (lodkit compare states it in its report).
#include <algorithm>
#include <cmath>

#include "lodkit/error.h"
#include "lodkit/measure.h"

namespace lod {

float4 heat_color(float t) {
  static constexpr float3 stops[5] = {{0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
  if (!(t > 0)) t = 0;  // NaN too
  t = std::min(t, 1.0f) * 4;
  const int k = std::min(int(t), 3);
  const float f = t - float(k);
  const float3 &a = stops[k], &b = stops[k + 1];
  const auto byte = [](float c) { return float(std::round(double(c) * 255) * (1.0 / 255)); };
  return {byte(a.x + (b.x - a.x) * f), byte(a.y + (b.y - a.y) * f), byte(a.z + (b.z - a.z) * f), 1.0f};
}

Mesh heatmap_mesh(const Mesh& mesh, const std::vector<float>& field, float scale) {
  if (field.size() != mesh.vertex_count())
    throw_usage("heatmap_mesh: the field has " + std::to_string(field.size()) + " values for " +
                std::to_string(mesh.vertex_count()) + " vertices");
  Mesh out;
  out.positions = mesh.positions;
  out.normals = mesh.normals;
  out.indices = mesh.indices;
  out.colors.resize(field.size());
  for (size_t v = 0; v < field.size(); ++v) out.colors[v] = heat_color(scale > 0 ? field[v] / scale : 0.0f);
  return out;
}

}  // namespace lod
