// The skinned test characters of fixtures.h. Everything is computed from the constants below in a
// fixed order (no randomness, no threads), so every run builds bit-identical scenes.
#include "skin/fixtures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "lodkit/error.h"
#include "lodkit/skin.h"

namespace lod::fixtures {

namespace {

// ---- small vector helpers -------------------------------------------------------------------------

float3 operator+(float3 a, float3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
float3 operator-(float3 a, float3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
float3 operator*(float s, float3 a) { return {s * a.x, s * a.y, s * a.z}; }
float dot(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
float3 cross(float3 a, float3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
float length(float3 a) { return std::sqrt(dot(a, a)); }

float3 closest_on_segment(float3 p, float3 a, float3 b) {
  const float3 ab = b - a;
  const float len2 = dot(ab, ab);
  const float t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return a + t * ab;
}

// Unit quaternion (x, y, z, w) of a rotation by `degrees` about a unit axis.
float4 axis_angle(float3 axis, float degrees) {
  const double half = degrees * std::numbers::pi / 360.0;
  const float s = float(std::sin(half));
  return {axis.x * s, axis.y * s, axis.z * s, float(std::cos(half))};
}

// Hamilton product a * b: rotate by b first, then by a.
float4 qmul(float4 a, float4 b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

float4 unit(float4 q) {
  const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return {q.x / len, q.y / len, q.z / len, q.w / len};
}

constexpr float3 axis_x = {1, 0, 0}, axis_y = {0, 1, 0}, axis_z = {0, 0, 1};

// ---- the skeleton -----------------------------------------------------------------------------------

constexpr const char* joint_names[joint_count] = {"hips",       "spine",   "chest",   "neck",       "head",    "shoulder_l",
                                                  "elbow_l",    "wrist_l", "shoulder_r", "elbow_r", "wrist_r", "hip_l",
                                                  "knee_l",     "ankle_l", "hip_r",   "knee_r",     "ankle_r"};
constexpr int32_t joint_parents[joint_count] = {-1, hips, spine, chest, neck, chest, shoulder_l, elbow_l, chest,
                                                shoulder_r, elbow_r, hips, hip_l, knee_l, hips, hip_r, knee_r};

// Joint positions in the bind pose, plus the far ends of the leaf bones and the bottom of the pelvis,
// which the weight falloff needs.
struct Rig {
  float3 joint[joint_count];
  float3 head_end, hand_end_l, hand_end_r, toe_l, toe_r, pelvis_low;
  float band = 0;  // a bone's weight falls to 0 this much farther away than the nearest bone
  uint32_t smoothing = 0;  // passes of neighbour averaging
};

struct Segment {
  uint32_t joint;
  float3 a, b;
};

// The part of the body each joint moves: its bone to the next joint, plus the pelvis bar and the
// clavicles, which make the hips and the chest the nearest bones of the pelvis and the shoulder tops.
std::vector<Segment> bone_segments(const Rig& r) {
  const auto* j = r.joint;
  return {
      {hips, j[hips], j[spine]},           {hips, j[hip_l], j[hip_r]},           {hips, j[hips], r.pelvis_low},
      {spine, j[spine], j[chest]},         {chest, j[chest], j[neck]},           {chest, j[chest], j[shoulder_l]},
      {chest, j[chest], j[shoulder_r]},    {neck, j[neck], j[head]},             {head, j[head], r.head_end},
      {shoulder_l, j[shoulder_l], j[elbow_l]}, {elbow_l, j[elbow_l], j[wrist_l]}, {wrist_l, j[wrist_l], r.hand_end_l},
      {shoulder_r, j[shoulder_r], j[elbow_r]}, {elbow_r, j[elbow_r], j[wrist_r]}, {wrist_r, j[wrist_r], r.hand_end_r},
      {hip_l, j[hip_l], j[knee_l]},        {knee_l, j[knee_l], j[ankle_l]},      {ankle_l, j[ankle_l], r.toe_l},
      {hip_r, j[hip_r], j[knee_r]},        {knee_r, j[knee_r], j[ankle_r]},      {ankle_r, j[ankle_r], r.toe_r},
  };
}

// Smooth weights. A bone takes part only where the vertex sees it from the inside (the bone's closest
// point lies behind the surface, against the normal): a belly next to a hanging forearm must not follow
// the arm. Among those, the nearest bone gets 1 before normalisation and its parent and children fade
// out (smoothstep) over `band` of extra distance; no other bone takes part, so the inside of one leg
// never follows the other. Optional neighbour averaging (rig.smoothing passes) softens the seams where
// the nearest bone changes; then the top 4, normalised to sum 1.
void assign_weights(Mesh& mesh, const Rig& rig) {
  const std::vector<Segment> segments = bone_segments(rig);
  const size_t n = mesh.vertex_count();
  std::vector<std::array<double, joint_count>> dense(n);
  for (size_t v = 0; v < n; ++v) {
    const float3 p = mesh.positions[v];
    float seen[joint_count], any[joint_count];
    std::fill(std::begin(seen), std::end(seen), std::numeric_limits<float>::max());
    std::fill(std::begin(any), std::end(any), std::numeric_limits<float>::max());
    for (const Segment& s : segments) {
      const float3 q = closest_on_segment(p, s.a, s.b);
      const float d = length(p - q);
      any[s.joint] = std::min(any[s.joint], d);
      if (d > 0 && dot(mesh.normals[v], p - q) > -0.1f * d) seen[s.joint] = std::min(seen[s.joint], d);
    }
    // Only bones about as near as the nearest one count (a fingertip must not pick a thigh it happens
    // to see); a vertex that sees none of them (deep in a crease) goes by plain distances.
    const float near_limit = *std::min_element(std::begin(any), std::end(any)) + rig.band;
    bool sees_near_bone = false;
    for (float& d : seen) {
      if (d > near_limit) d = std::numeric_limits<float>::max();
      sees_near_bone = sees_near_bone || d < std::numeric_limits<float>::max();
    }
    const float* distance = sees_near_bone ? seen : any;
    uint32_t nearest = 0;
    for (uint32_t j = 1; j < joint_count; ++j)
      if (distance[j] < distance[nearest]) nearest = j;
    double total = 0;
    for (uint32_t j = 0; j < joint_count; ++j) {
      const bool related = j == nearest || joint_parents[j] == int32_t(nearest) || joint_parents[nearest] == int32_t(j);
      const double x = related ? 1.0 - (double(distance[j]) - distance[nearest]) / rig.band : 0.0;
      dense[v][j] = x > 0 ? x * x * (3 - 2 * x) : 0.0;
      total += dense[v][j];
    }
    for (double& w : dense[v]) w /= total;
  }
  if (rig.smoothing > 0) {
    std::vector<std::vector<uint32_t>> neighbours(n);
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = mesh.indices[t + size_t(k)], b = mesh.indices[t + size_t((k + 1) % 3)];
        neighbours[a].push_back(b);
        neighbours[b].push_back(a);
      }
    for (uint32_t pass = 0; pass < rig.smoothing; ++pass) {
      std::vector<std::array<double, joint_count>> next = dense;
      for (size_t v = 0; v < n; ++v) {
        if (neighbours[v].empty()) continue;
        std::array<double, joint_count> mean{};
        for (const uint32_t u : neighbours[v])
          for (uint32_t j = 0; j < joint_count; ++j) mean[j] += dense[u][j];
        for (uint32_t j = 0; j < joint_count; ++j) next[v][j] = 0.5 * dense[v][j] + 0.5 * mean[j] / double(neighbours[v].size());
      }
      dense = std::move(next);
    }
  }
  mesh.joints.assign(n, ushort4{0, 0, 0, 0});
  mesh.weights.assign(n, float4{0, 0, 0, 0});
  for (size_t v = 0; v < n; ++v) {
    std::array<std::pair<double, uint32_t>, joint_count> candidates{};
    for (uint32_t j = 0; j < joint_count; ++j) candidates[j] = {dense[v][j], j};
    // Largest first; ties by joint index keep the order deterministic.
    std::sort(candidates.begin(), candidates.end(),
              [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
    double total = 0;
    size_t count = 0;
    // Influences under 1% (mostly what smoothing spread around) would only add work and noise.
    for (; count < 4 && candidates[count].first >= 0.01; ++count) total += candidates[count].first;
    float w[4] = {0, 0, 0, 0};
    ushort4 joints = {0, 0, 0, 0};  // unused slots: joint 0 with weight 0
    for (size_t k = 0; k < count; ++k) {
      w[k] = float(candidates[k].first / total);
      joints[k] = uint16_t(candidates[k].second);
    }
    // The largest weight absorbs the rounding, so the float sum is 1 to half an ulp.
    w[0] = 1.0f - (w[1] + w[2] + w[3]);
    mesh.joints[v] = joints;
    mesh.weights[v] = {w[0], w[1], w[2], w[3]};
  }
}

// Area-weighted vertex normals (the cross products' lengths are twice the areas).
void compute_normals(Mesh& mesh) {
  std::vector<float3> sum(mesh.vertex_count());
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    const float3 face = cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
    sum[a] = sum[a] + face, sum[b] = sum[b] + face, sum[c] = sum[c] + face;
  }
  mesh.normals.resize(mesh.vertex_count());
  for (size_t v = 0; v < sum.size(); ++v) {
    const float len = length(sum[v]);
    mesh.normals[v] = len > 0 ? (1.0f / len) * sum[v] : float3{0, 1, 0};
  }
}

// ---- the humanoid's surface: closed tubes around straight axes ----------------------------------------

struct Station {
  float u;       // position along the tube, 0..1
  float r1, r2;  // radii along e1 and e2
};

struct Tube {
  float3 origin, direction, e1;  // unit direction and a unit vector perpendicular to it
  float length = 0;
  uint32_t rings = 0, segments = 0;
  std::vector<Station> profile;  // sorted by u, first at 0 and last at 1
  float cap_start = 0, cap_end = 0;  // lengths of the rounded ends
};

// Rings of `segments` vertices between two pole vertices, wound counter-clockwise seen from outside:
// with e2 = direction x e1 the ring's angle runs e1 -> e2, and (d/dangle) x (d/dalong) points outward.
void add_tube(Mesh& mesh, const Tube& tube) {
  const float3 e2 = cross(tube.direction, tube.e1);
  const uint32_t first = uint32_t(mesh.positions.size());
  const uint32_t m = tube.segments;
  auto radii = [&](float u) {
    size_t k = 0;
    while (k + 2 < tube.profile.size() && u > tube.profile[k + 1].u) ++k;
    const Station& a = tube.profile[k];
    const Station& b = tube.profile[k + 1];
    const float t = std::clamp((u - a.u) / (b.u - a.u), 0.0f, 1.0f);
    float r1 = a.r1 + (b.r1 - a.r1) * t, r2 = a.r2 + (b.r2 - a.r2) * t;
    // Quarter-circle ends: the radius goes to 0 at the poles with a vertical tangent.
    const float along = u * tube.length;
    float cap = 1;
    if (along < tube.cap_start) {
      const float x = 1 - along / tube.cap_start;
      cap = std::sqrt(std::max(0.0f, 1 - x * x));
    } else if (tube.length - along < tube.cap_end) {
      const float x = 1 - (tube.length - along) / tube.cap_end;
      cap = std::sqrt(std::max(0.0f, 1 - x * x));
    }
    return std::pair{r1 * cap, r2 * cap};
  };
  mesh.positions.push_back(tube.origin);  // start pole
  for (uint32_t i = 1; i <= tube.rings; ++i) {
    const float u = float(i) / float(tube.rings + 1);
    const auto [r1, r2] = radii(u);
    const float3 center = tube.origin + (u * tube.length) * tube.direction;
    for (uint32_t k = 0; k < m; ++k) {
      const double angle = 2 * std::numbers::pi * k / m;
      mesh.positions.push_back(center + (r1 * float(std::cos(angle))) * tube.e1 + (r2 * float(std::sin(angle))) * e2);
    }
  }
  mesh.positions.push_back(tube.origin + tube.length * tube.direction);  // end pole
  const uint32_t start_pole = first, end_pole = first + 1 + tube.rings * m;
  auto ring = [&](uint32_t i, uint32_t k) { return first + 1 + (i - 1) * m + k % m; };
  for (uint32_t k = 0; k < m; ++k) mesh.indices.insert(mesh.indices.end(), {start_pole, ring(1, k + 1), ring(1, k)});
  for (uint32_t i = 1; i < tube.rings; ++i)
    for (uint32_t k = 0; k < m; ++k) {
      const uint32_t a = ring(i, k), b = ring(i, k + 1), c = ring(i + 1, k), d = ring(i + 1, k + 1);
      mesh.indices.insert(mesh.indices.end(), {a, b, c, b, d, c});
    }
  for (uint32_t k = 0; k < m; ++k) mesh.indices.insert(mesh.indices.end(), {ring(tube.rings, k), ring(tube.rings, k + 1), end_pole});
}

const Rig humanoid_rig = [] {
  Rig r;
  r.joint[hips] = {0, 1.0f, 0};
  r.joint[spine] = {0, 1.12f, 0};
  r.joint[chest] = {0, 1.32f, 0};
  r.joint[neck] = {0, 1.54f, 0};
  r.joint[head] = {0, 1.64f, 0};
  r.joint[shoulder_l] = {0.18f, 1.47f, 0};
  r.joint[elbow_l] = {0.46f, 1.47f, 0};
  r.joint[wrist_l] = {0.72f, 1.47f, 0};
  r.joint[shoulder_r] = {-0.18f, 1.47f, 0};
  r.joint[elbow_r] = {-0.46f, 1.47f, 0};
  r.joint[wrist_r] = {-0.72f, 1.47f, 0};
  r.joint[hip_l] = {0.1f, 0.95f, 0};
  r.joint[knee_l] = {0.1f, 0.52f, 0};
  r.joint[ankle_l] = {0.1f, 0.1f, 0};
  r.joint[hip_r] = {-0.1f, 0.95f, 0};
  r.joint[knee_r] = {-0.1f, 0.52f, 0};
  r.joint[ankle_r] = {-0.1f, 0.1f, 0};
  r.head_end = {0, 1.8f, 0};
  r.hand_end_l = {0.83f, 1.47f, 0};
  r.hand_end_r = {-0.83f, 1.47f, 0};
  r.toe_l = {0.1f, 0.06f, 0.15f};
  r.toe_r = {-0.1f, 0.06f, 0.15f};
  r.pelvis_low = {0, 0.9f, 0};
  r.band = 0.07f;
  return r;
}();

Mesh humanoid_mesh() {
  Mesh mesh;
  // Torso, neck and head in one surface of revolution with elliptical sections (wider along x).
  Tube torso{.origin = {0, 0.85f, 0}, .direction = axis_y, .e1 = axis_z, .length = 1.0f, .rings = 40, .segments = 24};
  // (u = (y - 0.85) / 1.0, depth along z, width along x)
  torso.profile = {{0.00f, 0.10f, 0.15f}, {0.10f, 0.11f, 0.16f}, {0.25f, 0.095f, 0.14f}, {0.45f, 0.10f, 0.16f},
                   {0.60f, 0.10f, 0.17f}, {0.67f, 0.07f, 0.10f}, {0.71f, 0.05f, 0.05f}, {0.77f, 0.05f, 0.05f},
                   {0.81f, 0.09f, 0.08f}, {0.90f, 0.105f, 0.095f}, {1.00f, 0.08f, 0.07f}};
  torso.cap_start = 0.08f;
  torso.cap_end = 0.07f;
  add_tube(mesh, torso);
  for (const float side : {1.0f, -1.0f}) {
    // Arms along +-x from inside the shoulders to the finger tips; hands flat (thin along y).
    Tube arm{.origin = {0.08f * side, 1.47f, 0}, .direction = {side, 0, 0}, .e1 = axis_y, .length = 0.75f, .rings = 36, .segments = 16};
    // (u = (|x| - 0.08) / 0.75)
    arm.profile = {{0.00f, 0.055f, 0.055f}, {0.13f, 0.055f, 0.055f}, {0.51f, 0.045f, 0.045f}, {0.65f, 0.042f, 0.045f},
                   {0.85f, 0.03f, 0.035f},  {0.90f, 0.022f, 0.045f}, {1.00f, 0.018f, 0.04f}};
    arm.cap_start = 0.05f;
    arm.cap_end = 0.03f;
    add_tube(mesh, arm);
    // Legs from inside the pelvis down to below the ankle.
    Tube leg{.origin = {0.1f * side, 1.0f, 0}, .direction = {0, -1, 0}, .e1 = axis_z, .length = 0.95f, .rings = 44, .segments = 16};
    // (u = (1.0 - y) / 0.95)
    leg.profile = {{0.00f, 0.085f, 0.085f}, {0.20f, 0.075f, 0.075f}, {0.50f, 0.05f, 0.05f},
                   {0.68f, 0.055f, 0.055f}, {0.95f, 0.04f, 0.04f},  {1.00f, 0.04f, 0.04f}};
    leg.cap_start = 0.06f;
    leg.cap_end = 0.04f;
    add_tube(mesh, leg);
    // Feet pointing forward (+z), flatter than wide.
    Tube foot{.origin = {0.1f * side, 0.06f, -0.05f}, .direction = axis_z, .e1 = axis_y, .length = 0.22f, .rings = 10, .segments = 12};
    foot.profile = {{0.0f, 0.035f, 0.045f}, {1.0f, 0.03f, 0.045f}};
    foot.cap_start = 0.04f;
    foot.cap_end = 0.05f;
    add_tube(mesh, foot);
  }
  compute_normals(mesh);
  assign_weights(mesh, humanoid_rig);
  return mesh;
}

// ---- animation helpers ----------------------------------------------------------------------------------

AnimationChannel rotation_channel(uint32_t node, const std::vector<float>& times, const std::vector<float4>& keys) {
  AnimationChannel ch;
  ch.node = int32_t(node);
  ch.path = AnimationPath::rotation;
  ch.interpolation = Interpolation::linear;
  ch.components = 4;
  ch.times = times;
  for (const float4& q : keys) ch.values.insert(ch.values.end(), {q.x, q.y, q.z, q.w});
  return ch;
}

// A rotation about one axis, one angle per key.
AnimationChannel bend_channel(uint32_t node, const std::vector<float>& times, float3 axis, const std::vector<float>& degrees) {
  std::vector<float4> keys;
  for (const float d : degrees) keys.push_back(axis_angle(axis, d));
  return rotation_channel(node, times, keys);
}

// For each key: first `lower` about `lower_axis`, then `swing` about `swing_axis` (both in the parent's frame).
AnimationChannel swing_channel(uint32_t node, const std::vector<float>& times, float3 lower_axis, float lower, float3 swing_axis,
                               const std::vector<float>& swing) {
  std::vector<float4> keys;
  for (const float s : swing) keys.push_back(unit(qmul(axis_angle(swing_axis, s), axis_angle(lower_axis, lower))));
  return rotation_channel(node, times, keys);
}

Animation walk_clip(const Rig& rig) {
  Animation clip;
  clip.name = "walk";
  const std::vector<float> t = {0.0f, 0.3f, 0.6f, 0.9f, 1.2f};
  // Hip flexion is a negative rotation about +x (the thigh swings forward, to +z); knee flexion positive.
  clip.channels.push_back(bend_channel(hip_l, t, axis_x, {-30, 0, 30, 0, -30}));
  clip.channels.push_back(bend_channel(knee_l, t, axis_x, {10, 5, 15, 75, 10}));
  clip.channels.push_back(bend_channel(hip_r, t, axis_x, {30, 0, -30, 0, 30}));
  clip.channels.push_back(bend_channel(knee_r, t, axis_x, {15, 75, 10, 5, 15}));
  clip.channels.push_back(bend_channel(ankle_l, t, axis_x, {-10, 0, 15, 0, -10}));
  clip.channels.push_back(bend_channel(ankle_r, t, axis_x, {15, 0, -10, 0, 15}));
  // Arms lowered 70 degrees from the T-pose, swinging against the legs; elbows bend forward.
  clip.channels.push_back(swing_channel(shoulder_l, t, axis_z, -70, axis_x, {25, 0, -25, 0, 25}));
  clip.channels.push_back(swing_channel(shoulder_r, t, axis_z, 70, axis_x, {-25, 0, 25, 0, -25}));
  clip.channels.push_back(bend_channel(elbow_l, t, axis_y, {-60, -75, -90, -75, -60}));
  clip.channels.push_back(bend_channel(elbow_r, t, axis_y, {90, 75, 60, 75, 90}));
  clip.channels.push_back(bend_channel(spine, t, axis_y, {-8, 0, 8, 0, -8}));
  // The hips bob down when the legs pass each other.
  AnimationChannel bob;
  bob.node = hips;
  bob.path = AnimationPath::translation;
  bob.interpolation = Interpolation::linear;
  bob.components = 3;
  bob.times = t;
  const float3 rest = rig.joint[hips];
  for (const float dy : {0.0f, -0.03f, 0.0f, -0.03f, 0.0f}) bob.values.insert(bob.values.end(), {rest.x, rest.y + dy, rest.z});
  clip.channels.push_back(std::move(bob));
  return clip;
}

Animation wave_clip() {
  Animation clip;
  clip.name = "wave";
  const std::vector<float> t = {0.0f, 0.5f, 1.0f, 1.5f, 2.0f};
  // Right arm raised 20 degrees above the horizontal, forearm up (about -z for the arm along -x).
  clip.channels.push_back(bend_channel(shoulder_r, t, axis_z, {0, -20, -20, -20, 0}));
  clip.channels.push_back(bend_channel(elbow_r, t, axis_z, {0, -120, -60, -120, -60}));
  clip.channels.push_back(bend_channel(wrist_r, t, axis_z, {0, 30, -30, 30, 0}));
  clip.channels.push_back(swing_channel(shoulder_l, t, axis_z, -75, axis_x, {0, 5, 0, 5, 0}));
  clip.channels.push_back(bend_channel(elbow_l, t, axis_y, {0, -30, -30, -30, 0}));
  clip.channels.push_back(bend_channel(neck, t, axis_z, {0, -10, 5, -10, 0}));
  clip.channels.push_back(bend_channel(knee_l, t, axis_x, {0, 20, 0, 20, 0}));
  return clip;
}

Animation bend_clip() {
  Animation clip;
  clip.name = "bend";
  const std::vector<float> t = {0.0f, 0.5f, 1.0f, 1.5f, 2.0f};
  // The man's arms hang down: elbow flexion (hand forward, +z) is negative about +x, as is shoulder
  // flexion; raising the right arm sideways (to -x) is negative about +z.
  clip.channels.push_back(bend_channel(elbow_l, t, axis_x, {0, -90, -30, -110, 0}));
  clip.channels.push_back(bend_channel(elbow_r, t, axis_x, {0, -60, -110, -30, 0}));
  clip.channels.push_back(bend_channel(shoulder_l, t, axis_x, {0, -40, 0, -60, 0}));
  clip.channels.push_back(bend_channel(shoulder_r, t, axis_z, {0, -45, -80, -20, 0}));
  clip.channels.push_back(bend_channel(hip_l, t, axis_x, {0, -50, 0, -30, 0}));
  clip.channels.push_back(bend_channel(knee_l, t, axis_x, {0, 90, 20, 110, 0}));
  clip.channels.push_back(bend_channel(hip_r, t, axis_x, {0, 0, -60, 0, 0}));
  clip.channels.push_back(bend_channel(knee_r, t, axis_x, {0, 30, 100, 60, 0}));
  return clip;
}

// ---- scene assembly -----------------------------------------------------------------------------------

// Joint nodes 0..16 (translation from the parent, no rotation), the skinned mesh node 17, skin 0
// with inverse bind matrices from the rest pose.
Scene rigged_scene(const std::string& name, Mesh mesh, const Rig& rig, std::vector<Animation> animations) {
  Scene scene;
  scene.name = name;
  scene.nodes.resize(joint_count + 1);
  for (uint32_t j = 0; j < joint_count; ++j) {
    Node& node = scene.nodes[j];
    node.name = joint_names[j];
    node.parent = joint_parents[j];
    node.translation = node.parent < 0 ? rig.joint[j] : rig.joint[j] - rig.joint[node.parent];
    if (node.parent >= 0) scene.nodes[size_t(node.parent)].children.push_back(int32_t(j));
  }
  Node& mesh_node = scene.nodes[joint_count];
  mesh_node.name = name;
  mesh_node.mesh = 0;
  mesh_node.skin = 0;
  scene.roots = {hips, int32_t(joint_count)};

  Skin skin;
  skin.name = name + "_skeleton";
  skin.skeleton = hips;
  const std::vector<mat4> world = world_matrices(scene, rest_pose(scene));
  for (uint32_t j = 0; j < joint_count; ++j) {
    skin.joints.push_back(int32_t(j));
    skin.inverse_bind_matrices.push_back(affine_inverse(world[j]));
  }
  scene.skins.push_back(std::move(skin));

  Primitive primitive;
  primitive.mesh = std::move(mesh);
  scene.primitives.push_back(std::move(primitive));
  scene.animations = std::move(animations);
  return scene;
}

// man.off's axes (+z up, facing -y) to glTF's (+y up, facing +z): a rotation, so windings survive.
float3 man_to_gltf(const float (&p)[3]) { return {p[0], p[2], -p[1]}; }
float3 man_to_gltf(float3 p) { return {p.x, p.z, -p.y}; }

}  // namespace

// Read off the mesh's cross-sections (z slices) and checked on front and side renderings.
const JointPlacement joint_positions_man[joint_count] = {
    {{-0.022f, -0.015f, 0.00f}},  // hips: centre of the pelvis
    {{-0.024f, -0.015f, 0.08f}},  // spine
    {{-0.025f, -0.010f, 0.20f}},  // chest
    {{-0.022f, 0.000f, 0.34f}},   // neck
    {{-0.025f, -0.020f, 0.39f}},  // head
    {{0.095f, -0.035f, 0.28f}},   // shoulder_l (the figure's left is +x)
    {{0.128f, -0.085f, 0.10f}},   // elbow_l
    {{0.120f, -0.100f, 0.00f}},   // wrist_l: the left hand rests in front of the thigh
    {{-0.150f, 0.030f, 0.28f}},   // shoulder_r
    {{-0.185f, 0.044f, 0.11f}},   // elbow_r
    {{-0.187f, 0.035f, -0.01f}},  // wrist_r
    {{0.030f, -0.040f, -0.01f}},  // hip_l
    {{0.110f, -0.045f, -0.22f}},  // knee_l: the left leg steps forward and out
    {{0.175f, -0.050f, -0.45f}},  // ankle_l
    {{-0.072f, 0.000f, -0.01f}},  // hip_r
    {{-0.117f, 0.070f, -0.24f}},  // knee_r: the right leg is behind
    {{-0.140f, 0.105f, -0.45f}},  // ankle_r
};

const char* joint_name(uint32_t joint) { return joint < joint_count ? joint_names[joint] : "?"; }
int32_t joint_parent(uint32_t joint) { return joint < joint_count ? joint_parents[joint] : -1; }

Scene humanoid_scene() {
  std::vector<Animation> clips;
  clips.push_back(walk_clip(humanoid_rig));
  clips.push_back(wave_clip());
  return rigged_scene("humanoid", humanoid_mesh(), humanoid_rig, std::move(clips));
}

std::array<Mesh, 2> halves_by_x(const Mesh& mesh) {
  std::array<Mesh, 2> halves;
  std::array<std::vector<uint32_t>, 2> remap;
  for (std::vector<uint32_t>& r : remap) r.assign(mesh.vertex_count(), ~0u);
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    float x = 0;
    for (size_t c = 0; c < 3; ++c) x += mesh.positions[mesh.indices[3 * t + c]].x;
    const size_t h = x < 0 ? 0 : 1;
    for (size_t c = 0; c < 3; ++c) {
      const uint32_t v = mesh.indices[3 * t + c];
      if (remap[h][v] == ~0u) remap[h][v] = uint32_t(halves[h].vertex_count()), append_vertex(halves[h], mesh, v);
      halves[h].indices.push_back(remap[h][v]);
    }
  }
  return halves;
}

Scene humanoid_baked_scene() {
  Scene scene = humanoid_scene();
  const Pose rest = rest_pose(scene);
  Animation clip;
  clip.name = "dance (baked)";
  for (uint32_t j = 0; j < joint_count; ++j) {
    AnimationChannel t, r, s;
    t.node = r.node = s.node = int32_t(j);
    t.path = AnimationPath::translation, r.path = AnimationPath::rotation, s.path = AnimationPath::scale;
    r.components = 4;
    const bool still = j % 3 == 2;
    const double frequency = 0.4 + 0.13 * (j % 7), amplitude = 8.5 + 2.9 * (j % 5);  // Hz, degrees
    for (int k = 0; k <= 20 * 60; ++k) {
      const float time = float(k) / 60;
      for (AnimationChannel* c : {&t, &r, &s}) c->times.push_back(time);
      float3 p = rest.translation[j];
      if (j == hips) p.z += 1.2f * time, p.y += 0.03f * float(std::sin(2 * std::numbers::pi * 1.8 * time));
      t.values.insert(t.values.end(), {p.x, p.y, p.z});
      const float swing = still ? 0.0f : float(amplitude * std::sin(2 * std::numbers::pi * frequency * time + j));
      const float4 q = unit(qmul(rest.rotation[j], axis_angle(axis_x, swing)));
      r.values.insert(r.values.end(), {q.x, q.y, q.z, q.w});
      s.values.insert(s.values.end(), {rest.scale[j].x, rest.scale[j].y, rest.scale[j].z});
    }
    clip.channels.insert(clip.channels.end(), {t, r, s});
  }
  scene.animations.push_back(std::move(clip));
  return scene;
}

Scene rigged_man_scene(const std::filesystem::path& man_off) {
  Mesh source = read_mesh(man_off);
  Mesh mesh;
  mesh.positions.reserve(source.positions.size());
  for (const float3& p : source.positions) mesh.positions.push_back(man_to_gltf(p));
  mesh.indices = std::move(source.indices);
  compute_normals(mesh);
  Rig rig;
  for (uint32_t j = 0; j < joint_count; ++j) rig.joint[j] = man_to_gltf(joint_positions_man[j].position);
  rig.head_end = man_to_gltf(float3{-0.028f, -0.025f, 0.49f});
  rig.hand_end_l = man_to_gltf(float3{0.115f, -0.100f, -0.05f});
  rig.hand_end_r = man_to_gltf(float3{-0.190f, 0.030f, -0.10f});
  rig.toe_l = man_to_gltf(float3{0.185f, -0.130f, -0.49f});
  rig.toe_r = man_to_gltf(float3{-0.165f, 0.030f, -0.49f});
  rig.pelvis_low = man_to_gltf(float3{-0.022f, -0.010f, -0.06f});
  rig.band = 0.035f;  // limbs are 0.04-0.07 thick on this 1-unit figure
  rig.smoothing = 4;
  assign_weights(mesh, rig);
  std::vector<Animation> clips;
  clips.push_back(bend_clip());
  return rigged_scene("man", std::move(mesh), rig, std::move(clips));
}

Mesh arm(uint32_t along, uint32_t around) {
  constexpr float pi = std::numbers::pi_v<float>;
  Mesh m;
  for (uint32_t i = 0; i <= along; ++i)
    for (uint32_t j = 0; j < around; ++j) {
      const float x = 2.0f * float(i) / float(along), a = 2 * pi * float(j) / float(around);
      // A slight wobble so the surface is not trivially flat along x.
      const float r = 0.2f + 0.03f * std::sin(7 * x) * std::cos(3 * a);
      m.positions.push_back({x, r * std::cos(a), r * std::sin(a)});
      m.normals.push_back({0, std::cos(a), std::sin(a)});  // radial (ignoring the wobble)
      const float s = std::clamp((x - 0.8f) / 0.4f, 0.0f, 1.0f), w1 = s * s * (3 - 2 * s);
      m.joints.push_back({0, 1, 0, 0});
      m.weights.push_back({1 - w1, w1, 0, 0});
    }
  for (uint32_t i = 0; i < along; ++i)
    for (uint32_t j = 0; j < around; ++j) {
      const uint32_t a = i * around + j, b = i * around + (j + 1) % around, c = a + around, d = b + around;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  return m;
}

std::vector<mat4> bent(float angle) {
  const float c = std::cos(angle), s = std::sin(angle);
  mat4 r = {c, s, 0, 0, -s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const mat4 to = compose_trs({1, 0, 0}, {0, 0, 0, 1}, {1, 1, 1}), back = compose_trs({-1, 0, 0}, {0, 0, 0, 1}, {1, 1, 1});
  return {identity_matrix(), multiply(to, multiply(r, back))};
}

std::array<double, tentacle_bones> tentacle_weights(double x) {
  std::array<double, tentacle_bones> w{};
  double sum = 0;
  for (uint32_t i = 0; i < tentacle_bones; ++i) {
    const double d = (x - (i + 0.5)) / 2;
    sum += w[i] = std::exp(-d * d);
  }
  for (double& v : w) v /= sum;
  return w;
}

Mesh tentacle_mesh(uint32_t along, uint32_t around) {
  constexpr double pi = std::numbers::pi;
  Mesh m;
  for (uint32_t i = 0; i <= along; ++i) {
    const double x = 8.0 * i / along;
    // Bones by weight, heaviest first (ties: lower bone), in floats whose sum is 1 within 1e-6.
    const std::array<double, tentacle_bones> w = tentacle_weights(x);
    std::array<uint16_t, tentacle_bones> order;
    for (uint16_t b = 0; b < tentacle_bones; ++b) order[b] = b;
    std::stable_sort(order.begin(), order.end(), [&](uint16_t a, uint16_t b) { return w[a] > w[b]; });
    float slot[tentacle_bones];
    double rest = 0;
    for (uint32_t k = 1; k < tentacle_bones; ++k) rest += slot[k] = float(w[order[k]]);
    slot[0] = float(1.0 - rest);
    for (uint32_t j = 0; j < around; ++j) {
      const double a = 2 * pi * j / around;
      m.positions.push_back({float(x), float(0.3 * std::cos(a)), float(0.3 * std::sin(a))});
      m.normals.push_back({0, float(std::cos(a)), float(std::sin(a))});
      m.joints.push_back({order[0], order[1], order[2], order[3]});
      m.weights.push_back({slot[0], slot[1], slot[2], slot[3]});
      m.joints1.push_back({order[4], order[5], order[6], order[7]});
      m.weights1.push_back({slot[4], slot[5], slot[6], slot[7]});
    }
  }
  for (uint32_t i = 0; i < along; ++i)
    for (uint32_t j = 0; j < around; ++j) {
      const uint32_t a = i * around + j, b = i * around + (j + 1) % around, c = a + around, d = b + around;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  return m;
}

Scene tentacle_scene(uint32_t along, uint32_t around) {
  Scene scene;
  scene.name = "tentacle";
  scene.nodes.resize(tentacle_bones + 1);
  Skin skin;
  skin.name = "tentacle_skeleton";
  skin.skeleton = 0;
  Animation curl;
  curl.name = "curl";
  for (uint32_t j = 0; j < tentacle_bones; ++j) {
    Node& node = scene.nodes[j];
    node.name = "bone" + std::to_string(j);
    node.parent = int32_t(j) - 1;
    node.translation = {j ? 1.0f : 0.0f, 0, 0};
    if (j + 1 < tentacle_bones) node.children = {int32_t(j + 1)};
    skin.joints.push_back(int32_t(j));
    skin.inverse_bind_matrices.push_back(compose_trs({-float(j), 0, 0}, {0, 0, 0, 1}, {1, 1, 1}));
    curl.channels.push_back(bend_channel(j, {0, 1, 2}, {0, 0, 1}, {0, 20, 0}));
  }
  Node& mesh_node = scene.nodes[tentacle_bones];
  mesh_node.name = "tentacle";
  mesh_node.mesh = 0;
  mesh_node.skin = 0;
  scene.roots = {0, int32_t(tentacle_bones)};
  scene.skins.push_back(std::move(skin));
  Primitive primitive;
  primitive.mesh = tentacle_mesh(along, around);
  scene.primitives.push_back(std::move(primitive));
  scene.animations.push_back(std::move(curl));
  return scene;
}

std::vector<std::filesystem::path> write_fixtures(const std::filesystem::path& out_dir, const std::filesystem::path& man_off) {
  std::filesystem::create_directories(out_dir);
  std::vector<std::filesystem::path> written;
  written.push_back(out_dir / "humanoid.glb");
  write_scene(humanoid_scene(), written.back());
  written.push_back(out_dir / "humanoid_baked.glb");
  write_scene(humanoid_baked_scene(), written.back());
  std::error_code ec;
  if (!man_off.empty() && std::filesystem::is_regular_file(man_off, ec)) {
    written.push_back(out_dir / "man.glb");
    write_scene(rigged_man_scene(man_off), written.back());
  }
  return written;
}

}  // namespace lod::fixtures
