// Deterministic skinned test characters (no downloaded data needed for the first one):
//  - humanoid_scene(): a procedural humanoid of tube limbs in a T-pose, 17 joints, clips "walk" and "wave";
//  - rigged_man_scene(): the corpus figure data/corpus/man.off with a hand-placed skeleton and clip "bend".
// Both use the same skeleton layout (the Joint enum: node index = skin joint index), glTF axes (+Y up,
// the character faces +Z, its left is +X) and metres for the humanoid. Weights come from a smooth
// falloff along bone segments (only bones the vertex sees from the inside, and the nearest one's
// parent and children): at most 4 influences, summing to 1 within 1e-6; unused slots hold joint 0
// with weight 0.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lodkit/io.h"
#include "lodkit/skin.h"

namespace lod::fixtures {

// Joints in node (and skin) order; the skinned mesh node comes right after them (node joint_count).
enum Joint : uint32_t {
  hips,  // the root
  spine,
  chest,
  neck,
  head,
  shoulder_l,
  elbow_l,
  wrist_l,
  shoulder_r,
  elbow_r,
  wrist_r,
  hip_l,
  knee_l,
  ankle_l,
  hip_r,
  knee_r,
  ankle_r,
  joint_count
};
const char* joint_name(uint32_t joint);  // "hips", "spine", ..., "ankle_r"
int32_t joint_parent(uint32_t joint);     // -1 for hips

// The humanoid: 7 closed tubes (torso with neck and head, two arms, two legs, two feet) with 7520
// triangles and 3774 vertices (positions, normals, joints, weights), 1.85 m tall. Bind pose = rest
// pose (the node transforms) = T-pose. Clips: 0 "walk" (1.2 s, legs +-30 degrees at the hips, knees
// up to 75, arms lowered and swinging with elbows bent 60-90, a hips bob), 1 "wave" (2.0 s, right arm
// raised, elbow between 60 and 120 degrees, left arm lowered). Linear interpolation, quaternions.
Scene humanoid_scene();
// The humanoid with a third clip, 2 "dance (baked)": 20 s keyed at 60 Hz on every joint's
// translation, rotation and scale, as exporters bake animation. The hips walk forward (1.2 m/s) and
// bob; two joints in three swing about their x axis (8.5-20 degrees, 0.4-1.2 Hz), the third stays
// still; translations and scales hold the rest values but the hips'. For the compress benchmark.
Scene humanoid_baked_scene();
// A mesh's triangles split by the sign of their centre's x (x < 0 first), each half with only the
// vertices it uses, in order: two materials of one skinned mesh. Along the cut both have copies of
// the same vertices.
std::array<Mesh, 2> halves_by_x(const Mesh& mesh);
inline constexpr uint32_t humanoid_triangles = 7520;
inline constexpr uint32_t humanoid_vertices = 3774;

// man.off (34986 triangles, 17495 vertices, about 1 unit tall) turned to +Y up, facing +Z, with area-
// weighted normals and the same 17 joints placed by hand (joint_positions_man). Clip 0 "bend" (2.0 s):
// elbows to 110 degrees, knees to 110, shoulders and hips to 60-80. Throws lod::Error if the file is
// missing or malformed.
Scene rigged_man_scene(const std::filesystem::path& man_off);

// The hand-placed joint positions of man.off, in the file's own coordinates (+Z up, facing -Y).
struct JointPlacement {
  float position[3];
};
extern const JointPlacement joint_positions_man[joint_count];

// ---- small rigs for unit tests -----------------------------------------------------------------------

// A tube along +x from 0 to 2 (radius 0.2, a slight wobble), bone 0 = upper arm, bone 1 = forearm from
// the elbow at x = 1. Weights blend smoothly over x in [0.8, 1.2]; outside they are a single bone.
Mesh arm(uint32_t along = 60, uint32_t around = 20);
// The arm's joint matrices with the elbow bent by `angle` about +z: joint 1 = T(1,0,0) R_z(angle)
// T(-1,0,0); joint 0 the identity.
std::vector<mat4> bent(float angle);

// Eight influences: an open tube along +x from 0 to 8 (radius 0.3) on a chain of 8 joints at x = 0..7
// (node i the child of node i - 1, one unit along x; the skinned mesh node 8). Each vertex blends all
// 8 bones by tentacle_weights(x): its heaviest four in joints/weights, the next four in
// joints1/weights1. Clip 0 "curl" (2 s, linear): every joint turns about +z by 0, 20, 0 degrees.
inline constexpr uint32_t tentacle_bones = 8;
// The bones' weights at x: exp(-((x - (i + 0.5)) / 2)^2) for bone i, normalised to sum 1.
std::array<double, tentacle_bones> tentacle_weights(double x);
Mesh tentacle_mesh(uint32_t along = 64, uint32_t around = 12);
Scene tentacle_scene(uint32_t along = 64, uint32_t around = 12);

// Writes humanoid.glb, humanoid_baked.glb, and man.glb when `man_off` names an existing file; returns
// the paths written.
std::vector<std::filesystem::path> write_fixtures(const std::filesystem::path& out_dir, const std::filesystem::path& man_off = {});

}  // namespace lod::fixtures
