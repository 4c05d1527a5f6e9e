// Scene <-> Mesh: flattening a glTF scene into one world-space mesh, and wrapping a mesh as a scene.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <vector>

#include "core/heap.h"
#include "core/vec3d.h"
#include "io/scene_world.h"
#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

using io::Matrix;
using io::multiply;
using io::rest_world_matrices;

constexpr Matrix identity_matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// T * R * S, or the node's matrix.
Matrix trs_matrix(const float3& t, const float4& r, const float3& s) {
  Matrix m{};
  const double x = r.x, y = r.y, z = r.z, w = r.w;
  m[0] = (1 - 2 * (y * y + z * z)) * s.x;
  m[1] = (2 * (x * y + z * w)) * s.x;
  m[2] = (2 * (x * z - y * w)) * s.x;
  m[4] = (2 * (x * y - z * w)) * s.y;
  m[5] = (1 - 2 * (x * x + z * z)) * s.y;
  m[6] = (2 * (y * z + x * w)) * s.y;
  m[8] = (2 * (x * z + y * w)) * s.z;
  m[9] = (2 * (y * z - x * w)) * s.z;
  m[10] = (1 - 2 * (x * x + y * y)) * s.z;
  m[12] = t.x;
  m[13] = t.y;
  m[14] = t.z;
  m[15] = 1;
  return m;
}

Matrix local_matrix(const Node& node) {
  if (!node.has_matrix) return trs_matrix(node.translation, node.rotation, node.scale);
  Matrix m{};
  for (int i = 0; i < 16; ++i) m[i] = node.matrix[i];
  return m;
}

struct Instance {
  size_t primitive;
  Matrix world;
  int32_t node = -1;  // that draws it
};

// A world matrix as flatten applies it: positions by `world`, normals by the inverse transpose of
// its upper 3x3 (its cofactor matrix over the determinant), winding and handedness flipped when it
// mirrors.
struct Placement {
  Matrix world;
  bool identity, mirrored;
  std::array<double, 9> normal;  // row-major: n' = N * n

  explicit Placement(const Matrix& m) : world(m), identity(m == identity_matrix) {
    const double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    const double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    const double scale = det != 0 ? 1 / det : 1;
    normal = {(e * i - f * h) * scale, (f * g - d * i) * scale, (d * h - e * g) * scale,
              (c * h - b * i) * scale, (a * i - c * g) * scale, (b * g - a * h) * scale,
              (b * f - c * e) * scale, (c * d - a * f) * scale, (a * e - b * d) * scale};
    mirrored = det < 0;
  }
  // The upper 3x3 times v: a displacement's image.
  core::vec3d linear(const float3& v) const {
    return {world[0] * v.x + world[4] * v.y + world[8] * v.z, world[1] * v.x + world[5] * v.y + world[9] * v.z,
            world[2] * v.x + world[6] * v.y + world[10] * v.z};
  }
  float3 apply_to_normal(const float3& v) const {
    const auto& n = normal;
    return core::unit_float3({n[0] * v.x + n[1] * v.y + n[2] * v.z, n[3] * v.x + n[4] * v.y + n[5] * v.z,
                              n[6] * v.x + n[7] * v.y + n[8] * v.z},
                             v);
  }
  // A tangent's xyz goes with the surface: by the upper 3x3 itself.
  float3 apply_to_tangent(const float3& t) const { return core::unit_float3(linear(t), t); }
};

// Where a skinned mesh drawn by `node` is placed. glTF ignores the node's transform: the joints
// place it. Flattening gives the bind pose, in the mesh's own space, except where every joint
// carries the same matrix at rest (world times inverse bind matrix): the whole skeleton moved or
// scaled after binding, or a quantized file's grid (lodkit -q, gltfpack), whose dequantization
// lives in the inverse bind matrices. That matrix then places it, where a viewer draws it.
// "The same" within 1e-4 of the mesh's size, at the corners of its bounding box; identity then
// stays exactly the identity.
Matrix skinned_placement(const Scene& scene, const Node& node, const std::vector<Matrix>& rest_world,
                         const std::vector<size_t>& primitives) {
  if (node.skin < 0 || size_t(node.skin) >= scene.skins.size()) return identity_matrix;
  const Skin& skin = scene.skins[size_t(node.skin)];
  if (skin.joints.empty()) return identity_matrix;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const size_t p : primitives)
    for (const float3& q : scene.primitives[p].mesh.positions) {
      const double c[3] = {q.x, q.y, q.z};
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c[k]), hi[k] = std::max(hi[k], c[k]);
    }
  if (!(lo[0] <= hi[0])) return identity_matrix;
  const auto corner = [&](const Matrix& m, int i) {
    const double x = i & 1 ? hi[0] : lo[0], y = i & 2 ? hi[1] : lo[1], z = i & 4 ? hi[2] : lo[2];
    return core::vec3d{m[0] * x + m[4] * y + m[8] * z + m[12], m[1] * x + m[5] * y + m[9] * z + m[13],
                       m[2] * x + m[6] * y + m[10] * z + m[14]};
  };
  std::vector<Matrix> joint(skin.joints.size());
  for (size_t j = 0; j < joint.size(); ++j) {
    const int32_t at = skin.joints[j];
    if (at < 0 || size_t(at) >= rest_world.size()) return identity_matrix;
    Matrix inverse_bind = identity_matrix;
    if (j < skin.inverse_bind_matrices.size()) std::copy(skin.inverse_bind_matrices[j].begin(), skin.inverse_bind_matrices[j].end(), inverse_bind.begin());
    joint[j] = multiply(rest_world[size_t(at)], inverse_bind);
  }
  const double size = core::length(corner(joint[0], 7) - corner(joint[0], 0));
  const auto same = [&](const Matrix& a, const Matrix& b) {
    for (int i = 0; i < 8; ++i)
      if (!(core::length(corner(a, i) - corner(b, i)) <= 1e-4 * size)) return false;
    return true;
  };
  if (!(size > 0) || !std::isfinite(size)) return identity_matrix;
  for (const Matrix& m : joint)
    if (!same(m, joint[0])) return identity_matrix;
  return same(joint[0], identity_matrix) ? identity_matrix : joint[0];
}

// Every (primitive, world matrix) pair of the default scene, in depth-first node order; hidden
// nodes (Node::visible) and those below them left out.
std::vector<Instance> collect_instances(const Scene& scene) {
  std::vector<Instance> instances;
  if (scene.nodes.empty() || scene.roots.empty()) {
    // No node hierarchy: every mesh once, untransformed.
    for (size_t p = 0; p < scene.primitives.size(); ++p) instances.push_back({p, identity_matrix});
    return instances;
  }
  std::map<int32_t, std::vector<size_t>> primitives_of_mesh;
  for (size_t p = 0; p < scene.primitives.size(); ++p)
    primitives_of_mesh[int32_t(scene.primitives[p].gltf_mesh)].push_back(p);

  // Iterative walk; a node is visited once even if a malformed hierarchy reaches it twice.
  std::vector<bool> visited(scene.nodes.size(), false);
  std::vector<Matrix> rest_world;  // every node's, once a skinned mesh needs them
  std::vector<std::pair<int32_t, Matrix>> stack;
  for (auto it = scene.roots.rbegin(); it != scene.roots.rend(); ++it) stack.push_back({*it, identity_matrix});
  while (!stack.empty()) {
    auto [index, parent_world] = stack.back();
    stack.pop_back();
    if (index < 0 || size_t(index) >= scene.nodes.size() || visited[size_t(index)]) continue;
    visited[size_t(index)] = true;
    const Node& node = scene.nodes[size_t(index)];
    if (!node.visible) continue;  // (KHR_node_visibility: nor anything below it)
    const Matrix world = multiply(parent_world, local_matrix(node));
    if (node.mesh >= 0) {
      auto found = primitives_of_mesh.find(node.mesh);
      if (found != primitives_of_mesh.end()) {
        if (node.skin >= 0 && rest_world.empty()) rest_world = rest_world_matrices(scene);
        const Matrix placement = node.skin >= 0 ? skinned_placement(scene, node, rest_world, found->second) : world;
        if (node.gpu_instances.empty()) {
          for (size_t p : found->second) instances.push_back({p, placement, index});
        } else {
          for (const Node::GpuInstance& gpu : node.gpu_instances) {
            const Matrix each = multiply(placement, trs_matrix(gpu.translation, gpu.rotation, gpu.scale));
            for (size_t p : found->second) instances.push_back({p, each, index});
          }
        }
      }
    }
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.push_back({*it, world});
  }
  return instances;
}

}  // namespace

Matrix io::multiply(const Matrix& a, const Matrix& b) {
  Matrix r{};
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row) {
      double sum = 0;
      for (int k = 0; k < 4; ++k) sum += a[k * 4 + row] * b[col * 4 + k];
      r[col * 4 + row] = sum;
    }
  return r;
}

std::vector<Matrix> io::rest_world_matrices(const Scene& scene) {
  const size_t n = scene.nodes.size();
  std::vector<Matrix> world(n);
  std::vector<uint8_t> state(n, 0);  // 0 to do, 1 on the current path, 2 done
  std::vector<size_t> path;
  for (size_t start = 0; start < n; ++start) {
    for (size_t at = start; state[at] == 0;) {  // walk up to a done node or a root
      state[at] = 1, path.push_back(at);
      const int32_t parent = scene.nodes[at].parent;
      if (parent < 0 || size_t(parent) >= n || state[size_t(parent)] == 1) break;
      at = size_t(parent);
    }
    for (auto it = path.rbegin(); it != path.rend(); ++it) {  // then down, root first
      const int32_t parent = scene.nodes[*it].parent;
      const bool above = parent >= 0 && size_t(parent) < n && state[size_t(parent)] == 2;
      world[*it] = above ? multiply(world[size_t(parent)], local_matrix(scene.nodes[*it])) : local_matrix(scene.nodes[*it]);
      state[*it] = 2;
    }
    path.clear();
  }
  return world;
}

// Streams: a vertex stream is kept only when every flattened primitive has it, unless the caller
// asks for the gaps filled. Filled with made-up values (zero UVs, arbitrary normals), they would
// look like real data to later stages, which would then preserve invented seams and measure errors
// against them: only a join whose result is split back into its parts, each dropping what it did not
// have, wants them. (Padding a second influence set with weights of 0 is not made up: those slots
// are unused, the skinning is the same.)
Mesh flatten(const Scene& scene, const FlattenOptions& options) {
  const std::vector<Instance> instances = collect_instances(scene);
  Mesh out;
  if (instances.empty()) return out;

  uint32_t every = ~0u, some = 0;  // stream_layout bits every instance has, some instance has
  for (const Instance& inst : instances) {
    const uint32_t layout = stream_layout(scene.primitives[inst.primitive].mesh);
    every &= layout, some |= layout;
  }
  const uint32_t filled = options.fill_streams ? some & ~influence_streams & ~every : 0;  // given to those without
  const uint32_t kept = every | filled;
  const bool normals = kept & stream_normals, tangents = kept & stream_tangents, colors = kept & stream_colors;
  const bool joints = kept & stream_joints, weights = kept & stream_weights;
  std::array<bool, max_uv_sets> uvs{};
  for (size_t k = 0; k < max_uv_sets; ++k) uvs[k] = kept & (stream_uv0 << k);
  // A second influence set if any part has one; parts with four influences get four of weight 0.
  const bool second_set = (some & stream_joints1) && joints && weights;
  bool any_material = false;
  size_t vertices = 0, corners = 0;
  for (const Instance& inst : instances) {
    const Primitive& prim = scene.primitives[inst.primitive];
    any_material = any_material || prim.material >= 0;
    vertices += prim.mesh.vertex_count();
    corners += prim.mesh.indices.size();
  }
  // Instancing multiplies a mesh: the merged one must still fit 32-bit indices.
  if (vertices > std::numeric_limits<uint32_t>::max() || corners > std::numeric_limits<uint32_t>::max())
    throw_bad_input(scene.name.empty() ? std::string("scene") : scene.name,
                    "its instances add up to " + std::to_string(vertices) + " vertices and " + std::to_string(corners / 3) +
                        " triangles, more than one mesh with 32-bit indices holds");
  core::reserve_huge(out.positions, vertices);
  core::reserve_huge(out.indices, corners);

  // A primitive lacking a filled stream is copied and filled once, however many instances draw it
  // (a forest's trees: the smooth normals it may need are not cheap).
  std::vector<std::optional<Mesh>> with_filled(filled ? scene.primitives.size() : 0);
  for (const Instance& inst : instances) {
    const Primitive& prim = scene.primitives[inst.primitive];
    const Mesh* from = &prim.mesh;
    if (filled && (stream_layout(prim.mesh) & filled) != filled) {
      std::optional<Mesh>& copy = with_filled[inst.primitive];
      if (!copy) fill_streams(copy.emplace(prim.mesh), filled);
      from = &*copy;
    }
    const Mesh& mesh = *from;
    const uint32_t base = uint32_t(out.positions.size());
    const Placement place(inst.world);
    const Matrix& m = inst.world;
    const bool identity = place.identity, mirrored = place.mirrored;

    if (identity) {
      out.positions.insert(out.positions.end(), mesh.positions.begin(), mesh.positions.end());
    } else {
      for (const float3& p : mesh.positions) {
        const float3 q = {float(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12]),
                          float(m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13]),
                          float(m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14])};
        // Finite inputs can still overflow float under a large node scale.
        if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
          throw_bad_input(scene.name.empty() ? std::string("scene") : scene.name,
                          "node transforms take a position of mesh primitive " + std::to_string(inst.primitive) +
                              " beyond the float range");
        out.positions.push_back(q);
      }
    }
    if (normals) {
      if (identity) {
        out.normals.insert(out.normals.end(), mesh.normals.begin(), mesh.normals.end());
      } else {
        for (const float3& v : mesh.normals) out.normals.push_back(place.apply_to_normal(v));
      }
    }
    if (tangents) {
      if (identity) {
        out.tangents.insert(out.tangents.end(), mesh.tangents.begin(), mesh.tangents.end());
      } else {
        for (const float4& t : mesh.tangents) {
          const float3 xyz = place.apply_to_tangent({t.x, t.y, t.z});
          // A mirroring transform flips the bitangent, so the handedness flips with it.
          out.tangents.push_back({xyz.x, xyz.y, xyz.z, mirrored ? -t.w : t.w});
        }
      }
    }
    for (size_t k = 0; k < max_uv_sets; ++k)
      if (uvs[k]) out.uvs[k].insert(out.uvs[k].end(), mesh.uvs[k].begin(), mesh.uvs[k].end());
    if (colors) out.colors.insert(out.colors.end(), mesh.colors.begin(), mesh.colors.end());
    if (joints) out.joints.insert(out.joints.end(), mesh.joints.begin(), mesh.joints.end());
    if (weights) out.weights.insert(out.weights.end(), mesh.weights.begin(), mesh.weights.end());
    if (second_set && mesh.joints1.empty()) {
      out.joints1.resize(out.joints1.size() + mesh.vertex_count());
      out.weights1.resize(out.weights1.size() + mesh.vertex_count());
    } else if (second_set) {
      out.joints1.insert(out.joints1.end(), mesh.joints1.begin(), mesh.joints1.end());
      out.weights1.insert(out.weights1.end(), mesh.weights1.begin(), mesh.weights1.end());
    }

    // A mirroring transform turns counter-clockwise triangles clockwise: swap two corners back.
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      const uint32_t i0 = base + mesh.indices[t], i1 = base + mesh.indices[t + 1], i2 = base + mesh.indices[t + 2];
      if (mirrored)
        out.indices.insert(out.indices.end(), {i0, i2, i1});
      else
        out.indices.insert(out.indices.end(), {i0, i1, i2});
    }
    if (any_material) out.materials.insert(out.materials.end(), mesh.indices.size() / 3, uint32_t(prim.material + 1));
  }

  if (any_material) {
    // Id 0 is "no material"; glTF material k is id k + 1.
    uint32_t max_id = 0;
    for (uint32_t id : out.materials) max_id = std::max(max_id, id);
    out.material_names.assign(std::max<size_t>(max_id, scene.material_names.size()) + 1, std::string());
    for (size_t k = 0; k < scene.material_names.size(); ++k) out.material_names[k + 1] = scene.material_names[k];
    if (!scene.material_looks.empty()) {
      const std::vector<MaterialLook> looks = source_material_looks(scene);
      out.material_looks.assign(out.material_names.size(), MaterialLook{});
      for (size_t k = 0; k < looks.size() && k + 1 < out.material_looks.size(); ++k) out.material_looks[k + 1] = looks[k];
    }
  }
  return out;
}

std::vector<size_t> flattened_primitives(const Scene& scene) {
  std::vector<size_t> out;
  std::vector<bool> seen(scene.primitives.size(), false);
  for (const Instance& inst : collect_instances(scene))
    if (!seen[inst.primitive]) seen[inst.primitive] = true, out.push_back(inst.primitive);
  return out;
}

FlatMorphTargets flatten_morph_targets(const Scene& scene) {
  FlatMorphTargets out;
  const std::vector<Instance> instances = collect_instances(scene);
  std::vector<std::vector<MorphTarget>> source(scene.primitives.size());  // decoded once per primitive
  std::vector<bool> decoded(scene.primitives.size(), false);
  std::vector<size_t> counts;  // per morphing node: its targets (glTF gives every primitive of a mesh as many)
  size_t vertices = 0;
  // flatten keeps normals and tangents when every instance has them; their displacements then.
  bool normals = !instances.empty(), tangents = !instances.empty(), target_normals = false, target_tangents = false;
  const auto node_index = [&](int32_t node) { return size_t(std::find(out.nodes.begin(), out.nodes.end(), node) - out.nodes.begin()); };
  for (const Instance& inst : instances) {
    const Mesh& mesh = scene.primitives[inst.primitive].mesh;
    if (!decoded[inst.primitive]) source[inst.primitive] = source_morph_targets(scene, inst.primitive), decoded[inst.primitive] = true;
    const std::vector<MorphTarget>& targets = source[inst.primitive];
    if (!targets.empty()) {
      const size_t j = node_index(inst.node);
      if (j == out.nodes.size()) out.nodes.push_back(inst.node), counts.push_back(0);
      counts[j] = std::max(counts[j], targets.size());
    }
    for (const MorphTarget& t : targets)
      target_normals = target_normals || !t.normals.empty(), target_tangents = target_tangents || !t.tangents.empty();
    normals = normals && !mesh.normals.empty(), tangents = tangents && !mesh.tangents.empty();
    vertices += mesh.vertex_count();
  }
  size_t count = 0;
  for (const size_t c : counts) out.first.push_back(count), count += c;
  if (count == 0) return out;
  target_normals = target_normals && normals, target_tangents = target_tangents && tangents;
  out.targets.resize(count);
  for (MorphTarget& t : out.targets) {
    core::resize_huge(t.positions, vertices);
    if (target_normals) core::resize_huge(t.normals, vertices);
    if (target_tangents) core::resize_huge(t.tangents, vertices);
  }
  size_t base = 0;
  for (const Instance& inst : instances) {
    const Mesh& mesh = scene.primitives[inst.primitive].mesh;
    const std::vector<MorphTarget>& targets = source[inst.primitive];
    const size_t first = targets.empty() ? 0 : out.first[node_index(inst.node)];
    const Placement place(inst.world);
    // A normal's or tangent's displacement: where the displaced one goes, less where it goes
    // (flatten's own). `apply` is the placement's map for that stream.
    const auto unit_displacements = [&](const std::vector<float3>& in, std::vector<float3>& out_stream, auto base_of, auto apply) {
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const float3 b = base_of(v), &d = in[v];
        const float3 to = apply(float3{b.x + d.x, b.y + d.y, b.z + d.z}), from = apply(b);
        out_stream[base + v] = place.identity ? d : float3{to.x - from.x, to.y - from.y, to.z - from.z};
      }
    };
    for (size_t k = 0; k < targets.size(); ++k) {
      MorphTarget& flat = out.targets[first + k];
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const float3& d = targets[k].positions[v];
        const core::vec3d moved = place.linear(d);
        flat.positions[base + v] = place.identity ? d : float3{float(moved.x), float(moved.y), float(moved.z)};
      }
      if (target_normals && !targets[k].normals.empty())
        unit_displacements(targets[k].normals, flat.normals, [&](size_t v) { return mesh.normals[v]; },
                           [&](const float3& n) { return place.apply_to_normal(n); });
      if (target_tangents && !targets[k].tangents.empty())
        unit_displacements(
            targets[k].tangents, flat.tangents,
            [&](size_t v) { return float3{mesh.tangents[v].x, mesh.tangents[v].y, mesh.tangents[v].z}; },
            [&](const float3& t) { return place.apply_to_tangent(t); });
    }
    base += mesh.vertex_count();
  }
  return out;
}

void sample_components(const AnimationChannel& ch, float time, float* out, float* slope, bool after) {
  const size_t n = ch.components, keys = ch.times.size();
  const bool cubic = ch.interpolation == Interpolation::cubic_spline;
  // Key k's value, in-tangent and out-tangent (cubic keys store in-tangent, value, out-tangent).
  const auto value = [&](size_t k) { return ch.values.data() + (cubic ? (3 * k + 1) * n : k * n); };
  const auto at_key = [&](size_t k) {
    std::copy_n(value(k), n, out);
    if (slope) std::fill_n(slope, n, 0.0f);
  };
  // Outside the keys the channel holds still. NaN compares false and lands on the first key.
  if (!(time > ch.times.front()) && !(after && time == ch.times.front() && keys > 1)) return at_key(0);
  if (time > ch.times.back() || (after && time == ch.times.back())) return at_key(keys - 1);
  // The interval [t_k, t_k+1] holding `time`: after it starts there, before it ends there.
  const auto it = after ? std::upper_bound(ch.times.begin(), ch.times.end(), time) : std::lower_bound(ch.times.begin(), ch.times.end(), time);
  const size_t k = size_t(it - ch.times.begin()) - 1;
  const float t0 = ch.times[k], t1 = ch.times[k + 1], interval = t1 - t0;
  const float t = interval > 0 ? std::clamp((time - t0) / interval, 0.0f, 1.0f) : 0.0f;
  const float* a = value(k);
  const float* b = value(k + 1);
  switch (ch.interpolation) {
    case Interpolation::step:
      return at_key(t < 1 ? k : k + 1);
    case Interpolation::linear:
      for (size_t c = 0; c < n; ++c) {
        out[c] = a[c] + (b[c] - a[c]) * t;
        if (slope) slope[c] = interval > 0 ? (b[c] - a[c]) / interval : 0.0f;
      }
      return;
    case Interpolation::cubic_spline: {
      // glTF's Hermite spline: tangents are per second, so they scale by the key interval.
      const float* out_tangent = a + n;
      const float* in_tangent = b - n;
      const float t2 = t * t, t3 = t2 * t;
      const float h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + t, h01 = -2 * t3 + 3 * t2, h11 = t3 - t2;
      const float d00 = 6 * t2 - 6 * t, d10 = 3 * t2 - 4 * t + 1, d01 = -6 * t2 + 6 * t, d11 = 3 * t2 - 2 * t;
      for (size_t c = 0; c < n; ++c) {
        out[c] = h00 * a[c] + h10 * interval * out_tangent[c] + h01 * b[c] + h11 * interval * in_tangent[c];
        if (slope)
          slope[c] = interval > 0 ? (d00 * a[c] + d01 * b[c]) / interval + d10 * out_tangent[c] + d11 * in_tangent[c] : 0.0f;
      }
      return;
    }
  }
}

const AnimationChannel* weights_channel(const Animation& clip, int32_t node) {
  for (const AnimationChannel& ch : clip.channels)
    if (ch.path == AnimationPath::weights && ch.node == node) return &ch;
  return nullptr;
}

std::optional<AnimationChannel> concatenate_weights(const std::vector<WeightsSource>& sources) {
  bool any = false, step = false, smooth = false, cubic = false;
  size_t total = 0;
  std::vector<float> times;
  for (const WeightsSource& s : sources) {
    total += s.rest.size();
    if (!s.channel) continue;
    const AnimationChannel& ch = *s.channel;
    const size_t per_key = ch.interpolation == Interpolation::cubic_spline ? 3 : 1;
    if (ch.path != AnimationPath::weights || ch.components != s.rest.size() || ch.times.empty() ||
        ch.values.size() != ch.times.size() * per_key * ch.components)
      return std::nullopt;
    any = true;
    step = step || ch.interpolation == Interpolation::step;
    smooth = smooth || ch.interpolation != Interpolation::step;
    cubic = cubic || ch.interpolation == Interpolation::cubic_spline;
    times.insert(times.end(), ch.times.begin(), ch.times.end());
  }
  if (!any || (step && smooth)) return std::nullopt;
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  AnimationChannel out;
  out.path = AnimationPath::weights;
  out.interpolation = step ? Interpolation::step : cubic ? Interpolation::cubic_spline : Interpolation::linear;
  out.components = uint32_t(total);
  out.times = times;
  const size_t groups = cubic ? 3 : 1;  // per key: (in-tangents,) values(, out-tangents)
  out.values.assign(times.size() * groups * total, 0.0f);
  std::vector<float> value(total), in(total), slope_after(total);
  for (size_t k = 0; k < times.size(); ++k) {
    float* key = out.values.data() + k * groups * total;
    size_t offset = 0;
    for (const WeightsSource& s : sources) {
      const size_t n = s.rest.size();
      if (!s.channel) {
        std::copy_n(s.rest.data(), n, key + (cubic ? total : 0) + offset);  // held: tangents stay 0
      } else if (!cubic) {
        sample_components(*s.channel, times[k], key + offset);
      } else {
        sample_components(*s.channel, times[k], key + total + offset, in.data(), false);
        sample_components(*s.channel, times[k], value.data(), slope_after.data(), true);
        std::copy_n(in.data(), n, key + offset);
        std::copy_n(slope_after.data(), n, key + 2 * total + offset);
      }
      offset += n;
    }
  }
  return out;
}

std::vector<MaterialPart> split_by_material(const Mesh& mesh) {
  if (!mesh.materials.empty() && mesh.materials.size() != mesh.triangle_count())
    throw_usage("split_by_material: " + std::to_string(mesh.materials.size()) + " material ids for " +
                std::to_string(mesh.triangle_count()) + " triangles");
  for (uint32_t index : mesh.indices)
    if (index >= mesh.vertex_count()) throw_usage("split_by_material: index " + std::to_string(index) + " out of range");
  std::vector<uint32_t> ids;  // material ids in use, ascending
  {
    std::vector<bool> used;
    for (uint32_t id : mesh.materials) {
      if (id >= used.size()) used.resize(size_t(id) + 1, false);
      used[id] = true;
    }
    for (size_t id = 0; id < used.size(); ++id)
      if (used[id]) ids.push_back(uint32_t(id));
  }
  std::vector<MaterialPart> parts;
  if (ids.size() <= 1) {
    // One material (or none): the whole mesh, unreferenced vertices included.
    MaterialPart part;
    part.material = ids.empty() ? 0 : ids[0];
    part.mesh = mesh;
    part.mesh.materials.clear();
    part.mesh.material_names.clear();
    part.mesh.material_looks.clear();
    part.mesh.groups.clear();
    part.mesh.group_names.clear();
    part.vertices.resize(mesh.vertex_count());
    std::iota(part.vertices.begin(), part.vertices.end(), 0u);
    parts.push_back(std::move(part));
    return parts;
  }
  std::vector<uint32_t> remap(mesh.vertex_count());
  for (uint32_t id : ids) {
    MaterialPart part;
    part.material = id;
    std::vector<bool> used(mesh.vertex_count(), false);
    for (size_t t = 0; t < mesh.triangle_count(); ++t)
      if (mesh.materials[t] == id)
        for (int k = 0; k < 3; ++k) used[mesh.indices[3 * t + k]] = true;
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      if (!used[v]) continue;
      remap[v] = uint32_t(part.vertices.size());
      part.vertices.push_back(uint32_t(v));
      append_vertex(part.mesh, mesh, uint32_t(v));
    }
    for (size_t t = 0; t < mesh.triangle_count(); ++t)
      if (mesh.materials[t] == id)
        for (int k = 0; k < 3; ++k) part.mesh.indices.push_back(remap[mesh.indices[3 * t + k]]);
    parts.push_back(std::move(part));
  }
  return parts;
}

Scene scene_from_mesh(const Mesh& mesh) {
  std::vector<MaterialPart> parts = split_by_material(mesh);
  Scene scene;
  scene.material_names = mesh.material_names;
  scene.material_looks = mesh.material_looks;
  Node node;
  node.mesh = 0;
  scene.nodes.push_back(node);
  scene.roots.push_back(0);
  for (MaterialPart& part : parts) {
    Primitive prim;
    if (!mesh.materials.empty()) prim.material = int32_t(part.material);
    else prim.material = mesh.material_names.empty() ? -1 : 0;
    prim.gltf_primitive = uint32_t(scene.primitives.size());
    prim.mesh = std::move(part.mesh);
    scene.primitives.push_back(std::move(prim));
  }
  // Names must cover every material index a primitive uses.
  for (const Primitive& prim : scene.primitives)
    if (prim.material >= 0 && size_t(prim.material) >= scene.material_names.size())
      scene.material_names.resize(size_t(prim.material) + 1);
  if (!scene.material_looks.empty()) scene.material_looks.resize(scene.material_names.size());
  return scene;
}

}  // namespace lod
