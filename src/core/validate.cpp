#include <cmath>
#include <string>

#include "lodkit/error.h"
#include "lodkit/mesh.h"

namespace lod {

namespace {

bool finite(const float2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
bool finite(const float3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const float4& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w); }

template <class T>
void check_stream(const std::vector<T>& stream, size_t vertex_count, const std::string& source, const char* what) {
  if (stream.empty()) return;
  if (stream.size() != vertex_count)
    throw_bad_input(source, std::string(what) + " has " + std::to_string(stream.size()) + " entries for " +
                                std::to_string(vertex_count) + " vertices");
  for (size_t v = 0; v < stream.size(); ++v)
    if (!finite(stream[v])) throw_bad_input(source, std::string(what) + " of vertex " + std::to_string(v) + " is not finite");
}

}  // namespace

void validate(const Mesh& mesh, const std::string& source, const ValidateOptions& options) {
  const size_t n = mesh.vertex_count();
  check_stream(mesh.positions, n, source, "position");
  check_stream(mesh.normals, n, source, "normal");
  check_stream(mesh.tangents, n, source, "tangent");
  for (size_t k = 0; k < max_uv_sets; ++k) check_stream(mesh.uvs[k], n, source, "uv");
  check_stream(mesh.colors, n, source, "color");
  check_stream(mesh.weights, n, source, "weight");
  check_stream(mesh.weights1, n, source, "second-set weight");
  if (!mesh.joints.empty() && mesh.joints.size() != n) throw_bad_input(source, "joints stream size does not match the vertex count");
  if (!mesh.joints1.empty() && mesh.joints1.size() != n)
    throw_bad_input(source, "second-set joints stream size does not match the vertex count");
  if (mesh.joints.empty() != mesh.weights.empty()) throw_bad_input(source, "joints and weights must come together");
  if (mesh.joints1.empty() != mesh.weights1.empty())
    throw_bad_input(source, "second-set joints and weights must come together");
  if (!mesh.joints1.empty() && mesh.joints.empty())
    throw_bad_input(source, "a second set of joints and weights needs the first");
  const bool second = !mesh.weights1.empty();
  auto negative = [](const float4& w) { return w.x < 0 || w.y < 0 || w.z < 0 || w.w < 0; };
  for (size_t v = 0; v < mesh.weights.size(); ++v) {
    const float4& w = mesh.weights[v];
    const float4 w1 = second ? mesh.weights1[v] : float4{};
    if (negative(w) || negative(w1)) throw_bad_input(source, "negative skin weight at vertex " + std::to_string(v));
    const double sum = double(w.x) + w.y + w.z + w.w + (double(w1.x) + w1.y + w1.z + w1.w);
    if (std::fabs(sum - 1.0) > options.weight_tolerance)
      throw_bad_input(source, "skin weights of vertex " + std::to_string(v) + " sum to " + std::to_string(sum) + ", expected 1");
  }
  if (mesh.indices.size() % 3 != 0) throw_bad_input(source, "index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");
  for (size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= n)
      throw_bad_input(source, "index " + std::to_string(i) + " is " + std::to_string(mesh.indices[i]) + ", past the " +
                                  std::to_string(n) + " vertices");
  const size_t t = mesh.triangle_count();
  if (!mesh.materials.empty() && mesh.materials.size() != t) throw_bad_input(source, "material stream size does not match the triangle count");
  if (!mesh.groups.empty() && mesh.groups.size() != t) throw_bad_input(source, "group stream size does not match the triangle count");
}

}  // namespace lod
