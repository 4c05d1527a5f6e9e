// Checks shared by the skinned-simplification tests: posing a mesh, the validity of its influences,
// and the ends of the skeletal geomorph along a multi-pose LOD chain.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lodkit/skin.h"

namespace lod::skin_test {

// The mesh with its positions skinned in `pose` (normals dropped).
inline Mesh skinned(const Mesh& m, const std::vector<mat4>& pose) {
  SkinnedVertices v;
  skin_vertices(m, pose, v);
  Mesh out = m;
  out.positions = v.positions;
  out.normals.clear();
  return out;
}

// Every vertex's four (or, with joints1/weights1, eight) influences: weights >= 0 summing to 1 within
// 1e-6, and joints below `joints` wherever the weight is not 0. Returns how many vertices use more
// than four influences.
inline size_t expect_valid_influences(const Mesh& m, size_t joints) {
  const size_t slots = m.influence_slots();
  EXPECT_EQ(m.joints.size(), m.vertex_count());
  EXPECT_EQ(m.weights.size(), m.vertex_count());
  if (slots == 8) {
    EXPECT_EQ(m.joints1.size(), m.vertex_count());
    EXPECT_EQ(m.weights1.size(), m.vertex_count());
  }
  if (m.joints.size() != m.vertex_count() || m.weights.size() != m.vertex_count() ||
      (slots == 8 && (m.joints1.size() != m.vertex_count() || m.weights1.size() != m.vertex_count())))
    return 0;
  size_t wide = 0;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float4 &a = m.weights[v], &b = slots == 8 ? m.weights1[v] : float4{};
    const float w[8] = {a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w};
    double sum = 0;
    size_t used = 0;
    for (size_t i = 0; i < slots; ++i) {
      EXPECT_GE(w[i], 0.0f) << v;
      if (w[i] > 0) {
        EXPECT_LT(i < 4 ? m.joints[v][i] : m.joints1[v][i - 4], joints) << "vertex " << v << " slot " << i;
        ++used;
      }
      sum += w[i];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6) << "vertex " << v;
    wide += used > 4;
  }
  return wide;
}

// simplify_skinned in `mode` to `ratio` of the triangles: houle in poses[houle_pose], the other modes
// over all of `poses`.
inline SimplifyResult simplify_in_mode(const Mesh& m, SkinMode mode, float ratio, const std::vector<std::vector<mat4>>& poses,
                                       size_t houle_pose) {
  SkinSimplifyOptions o;
  o.mode = mode;
  o.simplify.target_ratio = ratio;
  o.poses = mode == SkinMode::houle ? std::vector<std::vector<mat4>>{poses[houle_pose]} : poses;
  return simplify_skinned(m, o);
}

// A LOD chain at `ratios` (each level from the previous one) by the multi-pose simplifier, with
// geomorph tables.
inline LodChain multipose_chain(const Mesh& m, const std::vector<std::vector<mat4>>& poses, std::vector<float> ratios) {
  LodOptions lo;
  lo.ratios = std::move(ratios);
  lo.morph = true;
  lo.measure = false;
  lo.simplifier = skinned_simplifier({.poses = poses});
  return build_lod_chain(m, lo);
}

// The skeletal geomorph of each pair of levels in `pose`: t = 0 is the skinned finer level, t = 1
// puts every vertex exactly on its skinned target, t = 0.5 half way (positions within `tolerance`)
// with the normalised blend of the two skinned unit normals.
inline void expect_geomorph_ends(const LodChain& chain, const std::vector<mat4>& pose, float tolerance) {
  SkinnedVertices out, fine, coarse;
  for (size_t i = 0; i + 1 < chain.levels.size(); ++i) {
    const Mesh &finer = chain.levels[i].mesh, &coarser = chain.levels[i + 1].mesh;
    SkinnedGeomorph morph(finer, coarser, chain.morphs[i]);
    EXPECT_GT(morph.moving_vertices(), 0u);
    skin_vertices(finer, pose, fine);
    skin_vertices(coarser, pose, coarse);
    morph.evaluate(pose, 0.0f, out);
    EXPECT_EQ(out.positions, fine.positions);
    morph.evaluate(pose, 1.0f, out);
    for (size_t v = 0; v < finer.vertex_count(); ++v) {
      ASSERT_EQ(out.positions[v], coarse.positions[chain.morphs[i].target[v]]) << "level " << i << " vertex " << v;
      ASSERT_EQ(out.normals[v], coarse.normals[chain.morphs[i].target[v]]) << "level " << i << " vertex " << v;
    }
    morph.evaluate(pose, 0.5f, out);
    for (size_t v = 0; v < finer.vertex_count(); ++v) {
      const float3 &a = fine.positions[v], &b = coarse.positions[chain.morphs[i].target[v]];
      EXPECT_NEAR(out.positions[v].x, 0.5f * (a.x + b.x), tolerance);
      EXPECT_NEAR(out.positions[v].y, 0.5f * (a.y + b.y), tolerance);
      // Normals: the normalised blend of the two skinned unit normals, within 2 degrees (the morph
      // blends the skinned normals before normalising them; where rotations blend they are shorter,
      // by an amount that grows with the angle between the two levels' normals).
      const float3 &n = fine.normals[v], &q = coarse.normals[chain.morphs[i].target[v]];
      const float3 mid = {n.x + q.x, n.y + q.y, n.z + q.z};
      const float len = std::sqrt(mid.x * mid.x + mid.y * mid.y + mid.z * mid.z);
      if (len > 0.5f) {
        EXPECT_NEAR(out.normals[v].x, mid.x / len, 0.035f) << v;
        EXPECT_NEAR(out.normals[v].y, mid.y / len, 0.035f) << v;
        EXPECT_NEAR(out.normals[v].z, mid.z / len, 0.035f) << v;
      }
    }
  }
}

}  // namespace lod::skin_test
