// Skinned simplification: Houle's single-pose method, subset placement, and lodkit's multi-pose
// quadrics (src/simplify/multipose_metric.h), all on the one collapse engine.
#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "lodkit/error.h"
#include "lodkit/skin.h"
#include "simplify/multipose_metric.h"

namespace lod {

namespace {

// Weights summing to 1 within 1e-6: renormalised in double, the rounding left on the heaviest.
void normalize_influences(ushort4& joint, float4& weight) {
  float* w[4] = {&weight.x, &weight.y, &weight.z, &weight.w};
  double sum = 0;
  for (float* x : w) sum += std::max(0.0f, *x);
  if (!(sum > 0)) {
    weight = {1, 0, 0, 0};
    return;
  }
  int heaviest = 0;
  for (int i = 0; i < 4; ++i) {
    *w[i] = float(std::max(0.0f, *w[i]) / sum);
    if (*w[i] > *w[heaviest]) heaviest = i;
  }
  double rest = 0;
  for (int i = 0; i < 4; ++i)
    if (i != heaviest) rest += *w[i];
  *w[heaviest] = float(1.0 - rest);
  for (int i = 0; i < 4; ++i)
    if (*w[i] == 0) joint[size_t(i)] = 0;  // unused slots point at joint 0 (valid whatever the skin)
}

void check_skinned(const Mesh& mesh, size_t joints, const char* what) {
  if (mesh.joints.size() != mesh.vertex_count() || mesh.weights.size() != mesh.vertex_count())
    throw_usage(std::string(what) + ": the mesh needs joints and weights on every vertex");
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float4& w = mesh.weights[v];
    const float ws[4] = {w.x, w.y, w.z, w.w};
    for (int i = 0; i < 4; ++i)
      if (ws[i] != 0 && mesh.joints[v][size_t(i)] >= joints)
        throw_usage(std::string(what) + ": vertex " + std::to_string(v) + " uses joint " +
                    std::to_string(mesh.joints[v][size_t(i)]) + " but the poses have " + std::to_string(joints));
  }
}

// The mesh with positions and normals skinned by `joints`.
Mesh posed_mesh(const Mesh& mesh, const std::vector<mat4>& joints, unsigned threads) {
  SkinnedVertices v;
  skin_vertices(mesh, joints, v, threads);
  Mesh out = mesh;
  out.positions = std::move(v.positions);
  if (!mesh.normals.empty()) out.normals = std::move(v.normals);
  return out;
}

float3 normalized3(const float3& v) {
  const double l = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
  return l > 0 ? float3{float(v.x / l), float(v.y / l), float(v.z / l)} : v;
}

// Houle: simplify in the pose, then bring each survivor back to bind space through its own blended
// matrix B: p = B^-1 P. Skinned again in that pose it lands exactly at P; in any other pose the
// displacement follows the survivor's bones (it is applied in their frame, not in world space).
SimplifyResult simplify_houle(const Mesh& mesh, const SkinSimplifyOptions& o) {
  const std::vector<mat4>& pose = o.poses[0];
  SimplifyResult r = simplify(posed_mesh(mesh, pose, o.simplify.threads), o.simplify);
  Mesh& out = r.mesh;
  core::parallel_for(out.vertex_count(), core::thread_count(o.simplify.threads), [&](size_t v) {
    const uint32_t origin = r.vertex_origin[v];
    out.joints[v] = mesh.joints[origin];
    out.weights[v] = mesh.weights[origin];
    const mat4 blended = blend_matrix(pose, out.joints[v], out.weights[v]);
    out.positions[v] = transform_point(affine_inverse(blended), out.positions[v]);
    if (!out.normals.empty()) {
      // Normals go back by the transpose of the linear part (the inverse of the inverse transpose).
      mat4 transposed = identity_matrix();
      for (int r3 = 0; r3 < 3; ++r3)
        for (int c = 0; c < 3; ++c) transposed[size_t(4 * c + r3)] = blended[size_t(4 * r3 + c)];
      out.normals[v] = normalized3(transform_vector(transposed, out.normals[v]));
    }
  });
  return r;
}

// `count` moments spread over the scene's clips played one after another: the mid-points of equal
// steps (clips of zero length share the steps evenly instead). Needs at least one clip.
std::vector<std::pair<size_t, float>> spread_over_clips(const Scene& scene, uint32_t count) {
  std::vector<float> durations;
  double total = 0;
  for (size_t a = 0; a < scene.animations.size(); ++a) total += durations.emplace_back(animation_duration(scene, a));
  std::vector<std::pair<size_t, float>> moments;
  for (uint32_t i = 0; i < count; ++i) {
    size_t clip = 0;
    double t = 0;
    if (total > 0) {
      t = (i + 0.5) / count * total;
      while (clip + 1 < durations.size() && t > durations[clip]) t -= durations[clip++];
    } else {
      clip = size_t(i) * durations.size() / count;
    }
    moments.emplace_back(clip, float(t));
  }
  return moments;
}

}  // namespace

const char* skin_mode_name(SkinMode mode) {
  switch (mode) {
    case SkinMode::houle: return "houle";
    case SkinMode::subset: return "subset";
    case SkinMode::multipose: return "multipose";
  }
  return "?";
}

SimplifyResult simplify_skinned(const Mesh& mesh, const SkinSimplifyOptions& options) {
  const size_t joints = options.poses.empty() ? 0 : options.poses[0].size();
  for (const auto& pose : options.poses)
    if (pose.size() != joints) throw_usage("simplify_skinned: every pose needs the same joint count");
  if (options.mode != SkinMode::subset && options.poses.empty())
    throw_usage(std::string("simplify_skinned: the ") + skin_mode_name(options.mode) + " mode needs at least one pose");
  if (!(options.bone_weight >= 0) || !std::isfinite(options.bone_weight))
    throw_usage("simplify_skinned: bone_weight must be finite and >= 0");
  check_skinned(mesh, options.mode == SkinMode::subset && options.poses.empty() ? size_t(65536) : joints,
                "simplify_skinned");

  SimplifyResult r;
  switch (options.mode) {
    case SkinMode::subset: {
      SimplifyOptions so = options.simplify;
      so.keep_vertices = true;
      return simplify(mesh, so);  // every output vertex is an input vertex: weights untouched
    }
    case SkinMode::houle: r = simplify_houle(mesh, options); break;
    case SkinMode::multipose: {
      collapse::MultiposeInput in;
      in.poses = options.poses;
      in.pose_weights = options.pose_weights;
      in.bone_weight = options.bone_weight;
      r = collapse::simplify_multipose(mesh, options.simplify, in);
      break;
    }
  }
  for (size_t v = 0; v < r.mesh.vertex_count(); ++v) normalize_influences(r.mesh.joints[v], r.mesh.weights[v]);
  return r;
}

void skin_and_morph(const Mesh& finer, const Mesh& coarser, const Geomorph& table, std::span<const mat4> joints,
                    float t, SkinnedVertices& out, SkinnedVertices& coarser_skinned, unsigned threads) {
  if (table.target.size() != finer.vertex_count())
    throw_usage("skin_and_morph: the table has " + std::to_string(table.target.size()) + " entries for " +
                std::to_string(finer.vertex_count()) + " vertices");
  for (const uint32_t target : table.target)
    if (target >= coarser.vertex_count()) throw_usage("skin_and_morph: a target is outside the coarser level");
  skin_vertices(finer, joints, out, threads);
  if (t <= 0) return;
  skin_vertices(coarser, joints, coarser_skinned, threads);
  morph_positions(out.positions, coarser_skinned.positions, table, t, out.positions);  // in place: v reads v only
  if (out.normals.empty() || coarser_skinned.normals.empty()) return;
  const float s = t >= 1 ? 0.0f : 1 - t, u = t >= 1 ? 1.0f : t;
  for (size_t v = 0; v < out.normals.size(); ++v) {
    const float3 &a = out.normals[v], &b = coarser_skinned.normals[table.target[v]];
    out.normals[v] = t >= 1 ? b : normalized3({s * a.x + u * b.x, s * a.y + u * b.y, s * a.z + u * b.z});
  }
}

std::vector<std::vector<mat4>> sample_poses(const Scene& scene, uint32_t skin, uint32_t count) {
  if (skin >= scene.skins.size()) throw_usage("sample_poses: skin " + std::to_string(skin) + " does not exist");
  if (count == 0) throw_usage("sample_poses: ask for at least one pose");
  std::vector<std::vector<mat4>> poses;
  const Pose rest = rest_pose(scene);
  if (scene.animations.empty()) {
    poses.push_back(joint_matrices(scene, skin, world_matrices(scene, rest)));
    return poses;
  }
  for (const auto& [clip, time] : spread_over_clips(scene, count)) {
    Pose pose = rest;
    sample_animation(scene, clip, time, pose);
    poses.push_back(joint_matrices(scene, skin, world_matrices(scene, pose)));
  }
  return poses;
}

Pose mid_range_pose(const Scene& scene, uint32_t samples) {
  Pose mean = rest_pose(scene);
  if (scene.animations.empty() || samples == 0) return mean;
  const size_t nodes = mean.translation.size();
  std::vector<double> t(3 * nodes, 0.0), s(3 * nodes, 0.0), q(4 * nodes, 0.0);
  const Pose rest = mean;
  for (const auto& [clip, time] : spread_over_clips(scene, samples)) {
    Pose pose = rest;
    sample_animation(scene, clip, time, pose);
    for (size_t n = 0; n < nodes; ++n) {
      const float3& a = pose.translation[n];
      const float3& b = pose.scale[n];
      float4 r = pose.rotation[n];
      // One hemisphere (that of the rest rotation), so that q and -q do not cancel.
      const float4& ref = rest.rotation[n];
      if (r.x * ref.x + r.y * ref.y + r.z * ref.z + r.w * ref.w < 0) r = {-r.x, -r.y, -r.z, -r.w};
      t[3 * n] += a.x, t[3 * n + 1] += a.y, t[3 * n + 2] += a.z;
      s[3 * n] += b.x, s[3 * n + 1] += b.y, s[3 * n + 2] += b.z;
      q[4 * n] += r.x, q[4 * n + 1] += r.y, q[4 * n + 2] += r.z, q[4 * n + 3] += r.w;
    }
  }
  for (size_t n = 0; n < nodes; ++n) {
    mean.translation[n] = {float(t[3 * n] / samples), float(t[3 * n + 1] / samples), float(t[3 * n + 2] / samples)};
    mean.scale[n] = {float(s[3 * n] / samples), float(s[3 * n + 1] / samples), float(s[3 * n + 2] / samples)};
    const double l = std::sqrt(q[4 * n] * q[4 * n] + q[4 * n + 1] * q[4 * n + 1] + q[4 * n + 2] * q[4 * n + 2] +
                               q[4 * n + 3] * q[4 * n + 3]);
    if (l > 0)
      mean.rotation[n] = {float(q[4 * n] / l), float(q[4 * n + 1] / l), float(q[4 * n + 2] / l), float(q[4 * n + 3] / l)};
  }
  return mean;
}

}  // namespace lod
