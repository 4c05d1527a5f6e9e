// Skinned simplification: Houle's single-pose method, subset placement, and lodkit's multi-pose
// quadrics (src/simplify/multipose_metric.h), all on the one collapse engine.
#include <algorithm>
#include <cmath>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "core/parallel.h"
#include "lodkit/error.h"
#include "lodkit/skin.h"
#include "simplify/multipose_metric.h"
#include "skin/lbs_kernel.h"

namespace lod {

namespace {

// Vertex v's four or eight weights renormalised (collapse::normalize_weights).
void normalize_vertex(Mesh& mesh, size_t v) {
  const bool eight = mesh.influence_slots() == 8;
  const float4 &a = mesh.weights[v], &b = eight ? mesh.weights1[v] : float4{};
  const ushort4 &ja = mesh.joints[v], &jb = eight ? mesh.joints1[v] : ushort4{};
  float w[8] = {a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w};
  uint16_t j[8] = {ja[0], ja[1], ja[2], ja[3], jb[0], jb[1], jb[2], jb[3]};
  collapse::normalize_weights(j, w, eight ? 8 : 4);
  mesh.weights[v] = {w[0], w[1], w[2], w[3]};
  mesh.joints[v] = {j[0], j[1], j[2], j[3]};
  if (eight) mesh.weights1[v] = {w[4], w[5], w[6], w[7]}, mesh.joints1[v] = {j[4], j[5], j[6], j[7]};
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

// v / |v| by the hardware's reciprocal square root and one Newton step (relative error ~1e-7): the
// morph normalises three normals per vertex, and sqrt + divide made it cost 1.7x plain skinning.
inline float3 rough_unit(const float3& v) {
  const float l2 = std::max(v.x * v.x + v.y * v.y + v.z * v.z, 1e-30f);
#if defined(__SSE__)
  float r = _mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(l2)));
  r = r * (1.5f - 0.5f * l2 * r * r);
#else
  const float r = 1.0f / std::sqrt(l2);
#endif
  return {v.x * r, v.y * r, v.z * r};
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
    ushort4 joint1{};
    float4 weight1{};  // weight 0: no second set
    if (!out.joints1.empty()) {
      joint1 = out.joints1[v] = mesh.joints1[origin];
      weight1 = out.weights1[v] = mesh.weights1[origin];
    }
    const mat4 blended = blend_matrix(pose, out.joints[v], out.weights[v], joint1, weight1);
    out.positions[v] = transform_point(affine_inverse(blended), out.positions[v]);
    if (!out.normals.empty()) {
      // Normals go back by the transpose of the linear part (the inverse of the inverse transpose).
      mat4 transposed = identity_matrix();
      for (int r3 = 0; r3 < 3; ++r3)
        for (int c = 0; c < 3; ++c) transposed[size_t(4 * c + r3)] = blended[size_t(4 * r3 + c)];
      out.normals[v] = skinning::unit(transform_vector(transposed, out.normals[v]));
    }
  });
  return r;
}

// The clips that change the shape of skin `skin`: those with a channel that moves one of its
// joints or a node between them (an ancestor of some of its joints, not of all). A clip that moves
// none of them (another character's, or one that only carries the skeleton along) moves the skinned
// mesh rigidly at most: its poses would teach the simplification nothing.
std::vector<size_t> shaping_clips(const Scene& scene, uint32_t skin) {
  const std::vector<int32_t>& joints = scene.skins[skin].joints;
  std::vector<uint32_t> below(scene.nodes.size(), 0);  // per node, the joints it is or is above
  std::vector<bool> joint(scene.nodes.size(), false);
  for (const int32_t j : joints) {
    if (j < 0 || size_t(j) >= scene.nodes.size() || joint[size_t(j)]) continue;
    joint[size_t(j)] = true;
    // (Bounded: the reader refuses cycles, and a path is at most every node.)
    for (int32_t n = j, steps = 0; n >= 0 && size_t(n) < below.size() && size_t(steps) <= below.size(); n = scene.nodes[size_t(n)].parent, ++steps)
      ++below[size_t(n)];
  }
  const uint32_t all = uint32_t(std::count(joint.begin(), joint.end(), true));
  std::vector<size_t> clips;
  for (size_t a = 0; a < scene.animations.size(); ++a)
    for (const AnimationChannel& ch : scene.animations[a].channels) {
      if (ch.path == AnimationPath::weights || ch.node < 0 || size_t(ch.node) >= below.size()) continue;
      const size_t n = size_t(ch.node);
      if (joint[n] || (below[n] > 0 && below[n] < all)) {
        clips.push_back(a);
        break;
      }
    }
  return clips;
}

// `count` moments spread over `clips` of the scene played one after another: the mid-points of equal
// steps (clips of zero length share the steps evenly instead). Needs at least one clip.
std::vector<std::pair<size_t, float>> spread_over_clips(const Scene& scene, const std::vector<size_t>& clips, uint32_t count) {
  std::vector<float> durations;
  double total = 0;
  for (const size_t a : clips) total += durations.emplace_back(animation_duration(scene, a));
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
    moments.emplace_back(clips[clip], float(t));
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

size_t merge_rigid_poses(const Mesh& mesh, std::vector<std::vector<mat4>>& poses, std::vector<float>& weights) {
  if (!weights.empty() && weights.size() != poses.size()) throw_usage("merge_rigid_poses: one weight per pose, or none");
  // The joints the mesh weights (the others may move as they like).
  std::vector<uint32_t> used;
  {
    std::vector<bool> weighted;
    const auto note = [&](const std::vector<ushort4>& joints, const std::vector<float4>& w) {
      for (size_t v = 0; v < joints.size() && v < w.size(); ++v) {
        const float wv[4] = {w[v].x, w[v].y, w[v].z, w[v].w};
        for (int k = 0; k < 4; ++k) {
          if (wv[k] == 0) continue;
          if (joints[v][k] >= weighted.size()) weighted.resize(size_t(joints[v][k]) + 1, false);
          weighted[joints[v][k]] = true;
        }
      }
    };
    note(mesh.joints, mesh.weights);
    note(mesh.joints1, mesh.weights1);
    for (uint32_t j = 0; j < weighted.size(); ++j)
      if (weighted[j]) used.push_back(j);
  }
  for (const std::vector<mat4>& pose : poses)
    if (!used.empty() && pose.size() <= used.back()) return 0;  // (simplify_skinned refuses these poses)
  if (used.empty() || poses.size() < 2) return 0;
  constexpr double tolerance = 1e-5;
  // Whether pose b is pose a moved by one rigid motion T (taken from the first used joint).
  const auto rigid_copy = [&](const std::vector<mat4>& a, const std::vector<mat4>& b) {
    const mat4 t = multiply(b[used[0]], affine_inverse(a[used[0]]));
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        double dot = 0;  // columns i and k of T's linear part: orthonormal
        for (int r = 0; r < 3; ++r) dot += double(t[size_t(4 * i + r)]) * t[size_t(4 * k + r)];
        if (std::abs(dot - (i == k)) > tolerance) return false;
      }
    const double det = double(t[0]) * (double(t[5]) * t[10] - double(t[9]) * t[6]) -
                       double(t[4]) * (double(t[1]) * t[10] - double(t[9]) * t[2]) +
                       double(t[8]) * (double(t[1]) * t[6] - double(t[5]) * t[2]);
    if (!(det > 0)) return false;
    for (const uint32_t j : used) {
      const mat4 moved = multiply(t, a[j]);
      double size = 1;  // the entries' scale, for a relative tolerance
      for (int e = 0; e < 16; ++e) size = std::max({size, std::abs(double(moved[size_t(e)])), std::abs(double(b[j][size_t(e)]))});
      for (int e = 0; e < 16; ++e)
        if (!(std::abs(double(moved[size_t(e)]) - b[j][size_t(e)]) <= tolerance * size)) return false;
    }
    return true;
  };
  std::vector<size_t> kept;  // indices into poses
  std::vector<double> summed;
  for (size_t p = 0; p < poses.size(); ++p) {
    const double w = weights.empty() ? 1.0 : double(weights[p]);
    size_t k = 0;
    while (k < kept.size() && !rigid_copy(poses[kept[k]], poses[p])) ++k;
    if (k < kept.size()) {
      summed[k] += w;
    } else {
      kept.push_back(p);
      summed.push_back(w);
    }
  }
  const size_t gone = poses.size() - kept.size();
  if (gone == 0) return 0;
  std::vector<std::vector<mat4>> merged;
  for (const size_t p : kept) merged.push_back(std::move(poses[p]));
  poses = std::move(merged);
  weights.assign(summed.begin(), summed.end());
  return gone;
}

SimplifyResult simplify_skinned(const Mesh& mesh, const SkinSimplifyOptions& options) {
  const size_t joints = options.poses.empty() ? 0 : options.poses[0].size();
  for (const auto& pose : options.poses)
    if (pose.size() != joints) throw_usage("simplify_skinned: every pose needs the same joint count");
  if (options.mode != SkinMode::subset && options.poses.empty())
    throw_usage(std::string("simplify_skinned: the ") + skin_mode_name(options.mode) + " mode needs at least one pose");
  if (!(options.bone_weight >= 0) || !std::isfinite(options.bone_weight))
    throw_usage("simplify_skinned: bone_weight must be finite and >= 0");
  skinning::check_influences(mesh, options.mode == SkinMode::subset && options.poses.empty() ? size_t(65536) : joints,
                             "simplify_skinned");

  switch (options.mode) {
    case SkinMode::subset: {
      SimplifyOptions so = options.simplify;
      so.keep_vertices = true;
      return simplify(mesh, so);  // every output vertex is an input vertex: weights untouched
    }
    case SkinMode::houle: {
      SimplifyResult r = simplify_houle(mesh, options);
      for (size_t v = 0; v < r.mesh.vertex_count(); ++v) normalize_vertex(r.mesh, v);
      return r;
    }
    case SkinMode::multipose: {
      // The engine's chosen influences come normalised, and the others are the input's: normalise
      // those first, so that the record replays on the normalised input (lod::normalize_influences).
      Mesh normalized = mesh;
      normalize_influences(normalized);
      std::vector<std::vector<mat4>> poses = options.poses;
      std::vector<float> weights = options.pose_weights;
      merge_rigid_poses(normalized, poses, weights);
      collapse::MultiposeInput in;
      in.poses = poses;
      in.pose_weights = weights;
      in.bone_weight = options.bone_weight;
      return collapse::simplify_multipose(normalized, options.simplify, in);
    }
  }
  throw_usage("simplify_skinned: unknown mode");
}

void normalize_influences(Mesh& mesh) {
  for (size_t v = 0; v < mesh.vertex_count(); ++v) normalize_vertex(mesh, v);
}

std::function<SimplifyResult(const Mesh&, const SimplifyOptions&)> skinned_simplifier(SkinSimplifyOptions options) {
  return [options = std::move(options)](const Mesh& mesh, const SimplifyOptions& simplify) {
    SkinSimplifyOptions o = options;
    o.simplify = simplify;
    return simplify_skinned(mesh, o);
  };
}

SkinnedGeomorph::SkinnedGeomorph(const Mesh& finer, const Mesh& coarser, const Geomorph& table) : finer_(&finer) {
  if (table.target.size() != finer.vertex_count())
    throw_usage("SkinnedGeomorph: the table has " + std::to_string(table.target.size()) + " entries for " +
                std::to_string(finer.vertex_count()) + " vertices");
  skinning::check_influences(finer, 65536, "SkinnedGeomorph (finer level)");
  skinning::check_influences(coarser, 65536, "SkinnedGeomorph (coarser level)");
  if (finer.normals.empty() != coarser.normals.empty())
    throw_usage("SkinnedGeomorph: both levels need normals, or neither");
  if (finer.joints1.empty() != coarser.joints1.empty())
    throw_usage("SkinnedGeomorph: both levels need a second influence set, or neither");
  const bool second = !finer.joints1.empty();
  std::vector<uint32_t> slot_of(coarser.vertex_count(), UINT32_MAX);
  std::vector<uint32_t> needed;
  slot_.assign(finer.vertex_count(), UINT32_MAX);
  for (uint32_t v = 0; v < finer.vertex_count(); ++v) {
    const uint32_t c = table.target[v];
    if (c >= coarser.vertex_count()) throw_usage("SkinnedGeomorph: a target is outside the coarser level");
    const bool same = finer.positions[v] == coarser.positions[c] && finer.joints[v] == coarser.joints[c] &&
                      finer.weights[v] == coarser.weights[c] && (finer.normals.empty() || finer.normals[v] == coarser.normals[c]) &&
                      (!second || (finer.joints1[v] == coarser.joints1[c] && finer.weights1[v] == coarser.weights1[c]));
    if (same) continue;  // skins to the very same point (and normal) in every frame
    if (slot_of[c] == UINT32_MAX) slot_of[c] = uint32_t(needed.size()), needed.push_back(c);
    slot_[v] = slot_of[c];
    ++moving_;
  }
  joints_used_ = std::max(skinning::joints_used(finer), skinning::joints_used(coarser));
  // The blend weighs the skinned normals by their lengths: start from unit ones (the simplifier may
  // leave interpolated normals a little short).
  for (const float3& n : finer.normals) unit_normals_.push_back(skinning::unit(n));
  for (const uint32_t c : needed) {
    needed_.positions.push_back(coarser.positions[c]);
    if (!coarser.normals.empty()) needed_.normals.push_back(coarser.normals[c]);
    if (!coarser.normals.empty()) needed_unit_normals_.push_back(skinning::unit(coarser.normals[c]));
    needed_.joints.push_back(coarser.joints[c]);
    needed_.weights.push_back(coarser.weights[c]);
    if (second) needed_.joints1.push_back(coarser.joints1[c]), needed_.weights1.push_back(coarser.weights1[c]);
  }
}

void SkinnedGeomorph::evaluate(std::span<const mat4> joints, float t, SkinnedVertices& out, unsigned threads) {
  if (t <= 0 || moving_ == 0) return skin_vertices(*finer_, joints, out, threads);
  if (joints.size() < joints_used_)
    throw_usage("SkinnedGeomorph: the levels use " + std::to_string(joints_used_) + " joints, got " +
                std::to_string(joints.size()) + " matrices");
  if (t >= 1) {
    // Exactly the skinned coarser vertices, through the very function that skins them (a vertex that
    // does not move is its own target).
    skin_vertices(*finer_, joints, out, threads);
    skin_vertices(needed_, joints, needed_skinned_, threads);
    for (size_t v = 0; v < slot_.size(); ++v)
      if (slot_[v] != UINT32_MAX) {
        out.positions[v] = needed_skinned_.positions[slot_[v]];
        if (!out.normals.empty()) out.normals[v] = needed_skinned_.normals[slot_[v]];
      }
    return;
  }
  const Mesh& f = *finer_;
  const size_t n = f.vertex_count(), m = needed_.vertex_count();
  const bool with_normals = !f.normals.empty();
  const mat4* J = joints.data();
  const skinning::InfluenceStreams needed_influences(needed_);
  // The coarser vertices first; normals stay unnormalised until after the blend.
  needed_skinned_.positions.resize(m);
  needed_skinned_.normals.resize(with_normals ? m : 0);
  float3* np = needed_skinned_.positions.data();
  float3* nn = with_normals ? needed_skinned_.normals.data() : nullptr;
  core::parallel_blocks(m, 8192, threads, [&](size_t, size_t begin, size_t stop) {
    for (size_t k = begin; k < stop; ++k) {
      const skinning::Affine a = needed_influences.blend(J, k);
      np[k] = skinning::apply_point(a, needed_.positions[k]);
      if (nn) nn[k] = skinning::apply_linear(a, needed_unit_normals_[k]);
    }
  });
  out.positions.resize(n);
  out.normals.resize(with_normals ? n : 0);
  const float s = 1 - t;
  // Raw pointers: through the vectors the compiler must assume every store may alias the inputs.
  const uint32_t* slots = slot_.data();
  const float3* positions = f.positions.data();
  const float3* normals = with_normals ? unit_normals_.data() : nullptr;
  const skinning::InfluenceStreams influences(f);
  float3* out_p = out.positions.data();
  float3* out_n = with_normals ? out.normals.data() : nullptr;
  // One pass: skin each finer vertex and blend it with its skinned target right away. Branch-free:
  // a vertex that does not move blends with weight 0 (1 * p + 0 * b is p exactly), since about one
  // vertex in four does not move, in no predictable pattern. Normals are blended as skinned (from unit
  // bind normals; blended rotations shorten them) and normalised once: exact at both ends, within
  // 1.5 degrees of blending unit normals at a 110-degree elbow, and square roots are what skinning
  // costs here: normalising each skinned normal first made a morphing frame 1.8x plain skinning
  // instead of 1.2x.
  core::parallel_blocks(n, 8192, threads, [&](size_t, size_t begin, size_t stop) {
    for (size_t v = begin; v < stop; ++v) {
      const uint32_t slot = slots[v];
      const bool moves = slot != UINT32_MAX;
      const float tv = moves ? t : 0.0f, sv = moves ? s : 1.0f;
      const uint32_t k = moves ? slot : 0;
      const skinning::Affine a = influences.blend(J, v);
      const float3 p = skinning::apply_point(a, positions[v]);
      const float3& b = np[k];
      out_p[v] = {sv * p.x + tv * b.x, sv * p.y + tv * b.y, sv * p.z + tv * b.z};
      if (!out_n) continue;
      const float3 q = skinning::apply_linear(a, normals[v]);
      const float3& c = nn[k];
      out_n[v] = rough_unit({sv * q.x + tv * c.x, sv * q.y + tv * c.y, sv * q.z + tv * c.z});
    }
  });
}

std::vector<std::vector<mat4>> sample_poses(const Scene& scene, uint32_t skin, uint32_t count) {
  if (skin >= scene.skins.size()) throw_usage("sample_poses: skin " + std::to_string(skin) + " does not exist");
  if (count == 0) throw_usage("sample_poses: ask for at least one pose");
  std::vector<std::vector<mat4>> poses;
  const Pose rest = rest_pose(scene);
  const std::vector<size_t> clips = shaping_clips(scene, skin);
  if (clips.empty()) {
    poses.push_back(joint_matrices(scene, skin, world_matrices(scene, rest)));
    return poses;
  }
  for (const auto& [clip, time] : spread_over_clips(scene, clips, count)) {
    Pose pose = rest;
    sample_animation(scene, clip, time, pose);
    poses.push_back(joint_matrices(scene, skin, world_matrices(scene, pose)));
  }
  return poses;
}

Pose mid_range_pose(const Scene& scene, uint32_t skin, uint32_t samples) {
  if (skin >= scene.skins.size()) throw_usage("mid_range_pose: skin " + std::to_string(skin) + " does not exist");
  Pose mean = rest_pose(scene);
  const std::vector<size_t> clips = shaping_clips(scene, skin);
  if (clips.empty() || samples == 0) return mean;
  const size_t nodes = mean.translation.size();
  std::vector<double> t(3 * nodes, 0.0), s(3 * nodes, 0.0), q(4 * nodes, 0.0);
  const Pose rest = mean;
  for (const auto& [clip, time] : spread_over_clips(scene, clips, samples)) {
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
