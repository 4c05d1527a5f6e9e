// lodkit: skinned (articulated) models. Skeletons and animation sampling from glTF, linear blend
// skinning on the CPU, and simplification whose LODs keep playing the original animations
// (Houle 2000; lodkit's multi-pose quadrics go past his single simplification pose).
//
//   lod::Scene scene = lod::read_scene("character.glb");
//   lod::Pose pose = lod::rest_pose(scene);
//   lod::sample_animation(scene, 0, 0.5f, pose);               // clip 0 at t = 0.5 s
//   auto world = lod::world_matrices(scene, pose);
//   auto joints = lod::joint_matrices(scene, 0, world);        // skin 0
//   lod::SkinnedVertices v;
//   lod::skin_vertices(scene.primitives[0].mesh, joints, v);   // world-space positions and normals
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "lodkit/simplify.h"

namespace lod {

// ---- small matrix helpers -----------------------------------------------------------------------
using mat4 = std::array<float, 16>;  // column-major, like glTF: m[4 * column + row]

mat4 identity_matrix();
mat4 multiply(const mat4& a, const mat4& b);  // a * b
// Inverse of an affine matrix (last row 0 0 0 1); a singular linear part gives the identity.
mat4 affine_inverse(const mat4& m);
mat4 compose_trs(const float3& translation, const float4& rotation, const float3& scale);
float3 transform_point(const mat4& m, const float3& p);
float3 transform_vector(const mat4& m, const float3& v);  // linear part only

// ---- poses and animation ------------------------------------------------------------------------
// The local transform of every node of a scene. Nodes given by a matrix keep it (glTF does not
// animate them); the others are translation * rotation * scale.
struct Pose {
  std::vector<float3> translation;
  std::vector<float4> rotation;  // unit quaternions x, y, z, w
  std::vector<float3> scale;
};

// The nodes' own transforms (the pose the file was saved in).
Pose rest_pose(const Scene& scene);
// The largest key time over the clip's channels, seconds (0 for an empty clip).
float animation_duration(const Scene& scene, size_t animation);
// Overwrites the channels of clip `animation` at `time` (clamped to its keys): step, linear (slerp
// for rotations, shortest arc) and cubic spline (glTF's Hermite form). Rotations come out unit
// length. Morph-weight channels are ignored. Throws lod::Error (usage) for a bad clip index.
void sample_animation(const Scene& scene, size_t animation, float time, Pose& pose);
// World matrix of every node: parent's world * local. Throws lod::Error (bad_input) on a cycle.
std::vector<mat4> world_matrices(const Scene& scene, const Pose& pose);
// Joint matrices of skin `skin` (glTF): world(joint) * inverse_bind_matrix(joint). Skinned vertices
// land in world space (the skinned mesh node's own transform is ignored, as glTF requires).
std::vector<mat4> joint_matrices(const Scene& scene, size_t skin, const std::vector<mat4>& world);

// A primitive that is skinned: its node and that node's skin.
struct SkinnedPrimitive {
  uint32_t primitive = 0;  // index into Scene::primitives
  uint32_t node = 0;
  uint32_t skin = 0;
};
// Every primitive instanced by a node that has a skin, and whose mesh has joints and weights.
std::vector<SkinnedPrimitive> skinned_primitives(const Scene& scene);

// ---- linear blend skinning ----------------------------------------------------------------------
// p' = sum_i w_i J[j_i] p over a vertex's four or eight influences (Mesh::joints1/weights1 when
// present); normals by the blended linear part, renormalised. Structure of arrays: positions,
// normals, joints and weights are separate streams.
struct SkinnedVertices {
  std::vector<float3> positions;
  std::vector<float3> normals;  // empty when the mesh has none
};
void skin_vertices(const Mesh& mesh, std::span<const mat4> joints, SkinnedVertices& out, unsigned threads = 1);
// The blended matrix sum_i w_i J[j_i] of one vertex: its first influence set, plus the second one
// (joint1, weight1) for a vertex with up to eight; the default second set has weight 0.
mat4 blend_matrix(std::span<const mat4> joints, const ushort4& joint, const float4& weight, const ushort4& joint1 = {},
                  const float4& weight1 = {});

// ---- skeletal geomorph ---------------------------------------------------------------------------
// Houle's skinned geomorph: the finer and the coarser level are skinned in this frame, then morphed
// with the LOD chain's table (lod::Geomorph): P' = (1 - t) skin(P) + t skin(P_target), normals
// likewise and renormalised (blended before the skinned normals are normalised: within 1.5 degrees
// of blending unit normals, for a third of the per-frame cost). At t = 0 it is the skinned finer
// level, at t = 1 every vertex sits exactly on its skinned target (the coarser level's triangles).
//
// Built once per pair of levels: a finer vertex whose target has the same bind position, normal and
// influences (untouched by the collapses) skins to the same point, so only the others are morphed,
// and only the coarser vertices they lead to are skinned. A morphing frame then costs little more
// than skinning the finer level. Keeps pointers to both meshes: they must outlive it.
class SkinnedGeomorph {
 public:
  SkinnedGeomorph(const Mesh& finer, const Mesh& coarser, const Geomorph& table);
  // Into `out` (resized; nothing is allocated once it has the size). One object per thread.
  void evaluate(std::span<const mat4> joints, float t, SkinnedVertices& out, unsigned threads = 1);
  size_t moving_vertices() const { return moving_; }

 private:
  const Mesh* finer_;
  std::vector<float3> unit_normals_;  // the finer level's normals at unit length, for the blend
  Mesh needed_;                       // the coarser vertices some moving vertex leads to
  std::vector<float3> needed_unit_normals_;
  std::vector<uint32_t> slot_;      // per finer vertex: its target in needed_, or UINT32_MAX if it does not move
  size_t moving_ = 0;
  size_t joints_used_ = 0;          // joint matrices both levels need (checked once, when built)
  SkinnedVertices needed_skinned_;  // scratch
};

// ---- skinned simplification ---------------------------------------------------------------------
enum class SkinMode : uint8_t {
  // Houle (2000): simplify in one pose (SkinSimplifyOptions::poses[0]), then carry each survivor's
  // world-space displacement back to bind space through its blended joint matrix; the survivor keeps
  // its weights.
  houle,
  // Subset placement in the bind pose: only input vertices, weights untouched (what meshoptimizer and
  // gltfpack effectively do).
  subset,
  // lodkit's default: one quadric per sampled pose, the bind-space position optimal over all of them,
  // the survivor's weights chosen among the ends' and their blend by the same error, and a bone-weight
  // term against collapsing across different influences.
  multipose,
};
const char* skin_mode_name(SkinMode mode);  // "houle", "subset", "multipose"

// Joint matrices of skin `skin` in `count` poses spread evenly over the time of the clips that
// shape it, clip after clip: those that move one of its joints or a node between them (not another
// character's clips, nor one that only carries the skeleton along). The rest pose alone when no
// clip does.
std::vector<std::vector<mat4>> sample_poses(const Scene& scene, uint32_t skin, uint32_t count);
// A "mid-range" pose for skin `skin`: per node, the mean of its local transforms over `samples`
// poses spread over the clips that shape it, as sample_poses's (rotations averaged in one
// hemisphere, renormalised): each joint half way through its range of motion. The rest pose when
// no clip shapes it.
Pose mid_range_pose(const Scene& scene, uint32_t skin, uint32_t samples = 64);

struct SkinSimplifyOptions {
  SkinMode mode = SkinMode::multipose;
  SimplifyOptions simplify;  // targets, safety, threads; the metric applies to houle and subset
  // Joint matrices of the poses (lod::joint_matrices, lod::sample_poses). multipose sums its quadrics
  // over all of them (rigid copies once, lod::merge_rigid_poses); houle simplifies in poses[0];
  // subset ignores them.
  std::vector<std::vector<mat4>> poses;
  std::vector<float> pose_weights;  // multipose: importance per pose; empty: all alike
  // multipose: collapsing an edge whose ends have disjoint influences costs as much as moving by
  // bone_weight times its length (half the L1 distance of the weights scales it).
  float bone_weight = 1.0f;
};

// Poses that shape `mesh` alike, merged: a pose that is an earlier one moved as a whole by one
// rigid motion, in every joint the mesh weights (within 1e-5, relative), goes, and its weight (1
// each when `weights` is empty) is added to that pose's. A crowd's copies of one skeleton playing
// one clip, or the rest poses of clips that move none of its joints, then count once. Multipose's
// costs are distances, which a rigid motion keeps, so the simplification is the same (to rounding)
// for the cost of the poses kept; simplify_skinned merges them. `weights` is left empty when no pose
// goes. Returns how many went.
size_t merge_rigid_poses(const Mesh& mesh, std::vector<std::vector<mat4>>& poses, std::vector<float>& weights);

// Simplifies a skinned mesh given in bind space (positions, normals, joints and weights) so that it
// keeps playing the skeleton's clips. The result is in bind space, and every vertex has at most four
// influences (eight, in joints1/weights1 too, when the input has a second set) with valid joints and
// weights summing to 1 within 1e-6 (subset: the input's, untouched).
// In multipose mode, the input's weights are first normalised (lod::normalize_influences): the
// collapse record, with its influence changes, replays on that mesh, and a vertex no collapse kept
// has its weights.
// SimplifyResult::error is the engine's error: in poses[0] (houle), in the bind pose (subset), or the
// root mean square over the poses (multipose). Throws lod::Error (usage) for a mesh without joints
// and weights, joints outside the poses, or a mode without the poses it needs.
SimplifyResult simplify_skinned(const Mesh& mesh, const SkinSimplifyOptions& options);

// Each vertex's four or eight weights renormalised to sum 1 within 1e-6 (summed in double, the
// rounding left on the heaviest); a slot of weight 0 points at joint 0, and a vertex without weight
// gets all of it on slot 0.
void normalize_influences(Mesh& mesh);

// A LodOptions::simplifier for a skinned chain: simplify_skinned with `options` (mode, poses, pose
// weights, bone weight), each level's SimplifyOptions in place of options.simplify.
//   lod_options.simplifier = lod::skinned_simplifier({.poses = lod::sample_poses(scene, 0, 16)});
std::function<SimplifyResult(const Mesh&, const SimplifyOptions&)> skinned_simplifier(SkinSimplifyOptions options);

}  // namespace lod
