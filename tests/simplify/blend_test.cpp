// lod::vertex_blends and SimplifyResult::vertex_successor: where a simplified result's vertices lie
// on the input, for the per-vertex data the simplifier does not carry (glTF morph targets).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/shapes.h"
#include "test_support.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "lodkit/simplify.h"

namespace lod {
namespace {

double distance(const float3& a, const float3& b) {
  const double x = double(a.x) - b.x, y = double(a.y) - b.y, z = double(a.z) - b.z;
  return std::sqrt(x * x + y * y + z * z);
}

template <class T>
T blend_of(const std::vector<T>& values, const VertexBlend& b);
template <>
float3 blend_of(const std::vector<float3>& values, const VertexBlend& b) {
  float3 out;
  for (int k = 0; k < 3; ++k) {
    const float3& v = values[b.vertex[k]];
    out.x += b.weight[k] * v.x, out.y += b.weight[k] * v.y, out.z += b.weight[k] * v.z;
  }
  return out;
}
template <>
float2 blend_of(const std::vector<float2>& values, const VertexBlend& b) {
  float2 out;
  for (int k = 0; k < 3; ++k) out.x += b.weight[k] * values[b.vertex[k]].x, out.y += b.weight[k] * values[b.vertex[k]].y;
  return out;
}

// Each output vertex's blend is a point of an input triangle with a corner that became a wedge of
// the vertex's position, and no farther from the vertex than any input vertex that did (those are
// corners of the patch the point is nearest on).
TEST(VertexBlends, AreTheNearestPointsOfThePatchesTheVerticesReplace) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  for (const float ratio : {0.5f, 0.1f, 0.02f}) {
    const SimplifyResult r = simplify(torus, {.target_ratio = ratio});
    ASSERT_EQ(r.vertex_successor.size(), torus.vertex_count());
    for (uint32_t v = 0; v < r.mesh.vertex_count(); ++v) ASSERT_EQ(r.vertex_successor[r.vertex_origin[v]], v) << v;
    const std::vector<VertexBlend> blends = vertex_blends(torus, r.vertex_successor, r.mesh);
    ASSERT_EQ(blends.size(), r.mesh.vertex_count());
    const auto at_vertex = [&](uint32_t u, uint32_t v) {
      return r.vertex_successor[u] != ~0u && r.mesh.positions[r.vertex_successor[u]] == r.mesh.positions[v];
    };
    for (uint32_t v = 0; v < r.mesh.vertex_count(); ++v) {
      const VertexBlend& b = blends[v];
      double nearest_source = INFINITY;
      for (uint32_t u = 0; u < torus.vertex_count(); ++u)
        if (at_vertex(u, v)) nearest_source = std::min(nearest_source, distance(torus.positions[u], r.mesh.positions[v]));
      // The corners of one input triangle (up to seam copies), one of them a source of v's position.
      bool triangle = false;
      for (size_t t = 0; t < torus.triangle_count() && !triangle; ++t) {
        triangle = true;
        for (int k = 0; k < 3; ++k) triangle = triangle && torus.positions[torus.indices[3 * t + k]] == torus.positions[b.vertex[k]];
      }
      ASSERT_TRUE(triangle) << v;
      EXPECT_TRUE(at_vertex(b.vertex[0], v) || at_vertex(b.vertex[1], v) || at_vertex(b.vertex[2], v)) << v;
      for (const float w : b.weight) EXPECT_TRUE(w >= -1e-6f && w <= 1 + 1e-6f) << v;
      EXPECT_NEAR(b.weight[0] + b.weight[1] + b.weight[2], 1.0f, 1e-5f) << v;
      const float3 point = blend_of(torus.positions, b);
      EXPECT_LE(distance(point, r.mesh.positions[v]), nearest_source + 1e-5) << "ratio " << ratio << " vertex " << v;
    }
  }
}

// The torus's UV seams (u = 0 and u = 1 on copies of one position, and v likewise). A blend takes
// each corner on its own vertex's side of a seam wherever the input has a copy there that became
// the vertex, and a vertex no farther from its own side's triangles than from the others (one on the
// seam) blends its own side: the UVs it interpolates are then near the vertex's own. (A vertex the
// collapses moved across a seam blends the far side, where it is.)
TEST(VertexBlends, SeamVerticesBlendTheirOwnSide) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  const PositionIds ids = position_ids(torus);
  const SimplifyResult r = simplify(torus, {.target_ratio = 0.1f});
  const std::vector<VertexBlend> blends = vertex_blends(torus, r.vertex_successor, r.mesh);
  size_t on_seams = 0, checked = 0;
  for (uint32_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const float3 p = r.mesh.positions[v];
    bool own = true;
    for (const uint32_t c : blends[v].vertex) {
      bool copy_here = false;  // a copy of c's position that became v
      for (uint32_t u = 0; u < torus.vertex_count(); ++u) copy_here = copy_here || (ids.id[u] == ids.id[c] && r.vertex_successor[u] == v);
      EXPECT_TRUE(r.vertex_successor[c] == v || !copy_here) << v;
      const uint32_t to = r.vertex_successor[c];  // a copy that became another wedge of v's position
      own = own && !(to != v && to != ~0u && r.mesh.positions[to] == p);
    }
    // Brute force: the nearest point of the triangles around v's position, and of those with a corner
    // that became v itself.
    double all = INFINITY, mine = INFINITY;
    for (size_t t = 0; t < torus.triangle_count(); ++t) {
      bool at = false, self = false;
      for (int k = 0; k < 3; ++k) {
        const uint32_t to = r.vertex_successor[torus.indices[3 * t + k]];
        at = at || (to != ~0u && r.mesh.positions[to] == p), self = self || to == v;
      }
      if (!at) continue;
      const float3 &a = torus.positions[torus.indices[3 * t]], &b = torus.positions[torus.indices[3 * t + 1]],
                   &c = torus.positions[torus.indices[3 * t + 2]];
      const double d = test::triangle_distance(p, a, b, c);
      all = std::min(all, d);
      if (self) mine = std::min(mine, d);
    }
    const float2 uv = r.mesh.uvs[0][v];
    bool seam = false;  // another wedge of v's position
    for (uint32_t o = 0; o < r.mesh.vertex_count(); ++o) seam = seam || (o != v && r.mesh.positions[o] == p);
    on_seams += seam;
    // Across a seam from its own side, farther than the thousandth of the diagonal (3.72) it keeps to.
    if (mine > all + 3.72e-3 * 0.999) continue;
    checked += seam;
    EXPECT_TRUE(own) << v;
    const float2 blended = blend_of(torus.uvs[0], blends[v]);
    EXPECT_LT(std::fabs(blended.x - uv.x), 0.1f) << v;
    EXPECT_LT(std::fabs(blended.y - uv.y), 0.15f) << v;
  }
  EXPECT_GT(on_seams, 4u);
  EXPECT_GT(checked, on_seams / 3);  // (25 of 48 seam wedges when written)
}

// Unmoved: with keep_vertices every output vertex is an input vertex, whose own patch holds it.
TEST(VertexBlends, AnUnmovedVertexIsItsOrigin) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  const SimplifyResult r = simplify(torus, {.target_ratio = 0.1f, .keep_vertices = true});
  const std::vector<VertexBlend> blends = vertex_blends(torus, r.vertex_successor, r.mesh);
  for (uint32_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const float3 point = blend_of(torus.positions, blends[v]);
    EXPECT_LT(distance(point, torus.positions[r.vertex_origin[v]]), 1e-6) << v;
  }
}

// A smooth morph field (2% of the diagonal, a few waves across the bunny) carried to the 10% result:
// interpolated, the morphed result stays about as near the morphed input as the rest poses are to
// each other, and far nearer than with each survivor's own offset (what a subset simplifier keeps).
// scripts/bench.sh morphs measures more meshes.
TEST(VertexBlends, CarryAMorphFieldNearlyAsWellAsTheRestPose) {
  const std::filesystem::path dir = test::corpus_dir();
  if (dir.empty()) GTEST_SKIP() << "corpus not fetched";
  const Mesh bunny = read_mesh(dir / "bunny00.off");
  float3 lo, hi;
  bounding_box(bunny, lo, hi);
  const float d = float(distance(lo, hi));
  const auto field = [&](const float3& p) {
    const float x = (p.x - lo.x) / d, y = (p.y - lo.y) / d, z = (p.z - lo.z) / d;
    return float3{0.02f * d * std::sin(12 * y), 0.02f * d * std::cos(10 * z), 0.02f * d * std::sin(11 * x + 4 * y)};
  };
  const auto moved = [](Mesh m, const auto& offset) {
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const float3 o = offset(v);
      m.positions[v] = {m.positions[v].x + o.x, m.positions[v].y + o.y, m.positions[v].z + o.z};
    }
    return m;
  };
  std::vector<float3> offsets;
  for (const float3& p : bunny.positions) offsets.push_back(field(p));
  const SimplifyResult r = simplify(bunny, {.target_ratio = 0.1f});
  const std::vector<VertexBlend> blends = vertex_blends(bunny, r.vertex_successor, r.mesh);
  const Mesh morphed = moved(bunny, [&](size_t v) { return offsets[v]; });
  const double rest = compare(bunny, r.mesh).rms;
  const double interpolated = compare(morphed, moved(r.mesh, [&](size_t v) { return blend_of(offsets, blends[v]); })).rms;
  const double own = compare(morphed, moved(r.mesh, [&](size_t v) { return offsets[r.vertex_origin[v]]; })).rms;
  EXPECT_LT(interpolated, 2 * rest);
  EXPECT_LT(interpolated, 0.5 * own);
}

TEST(VertexBlends, RejectsSuccessorsOfAnotherMesh) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 12, 8);
  const SimplifyResult r = simplify(torus, {.target_ratio = 0.5f});
  std::vector<uint32_t> shorter(r.vertex_successor.begin(), r.vertex_successor.end() - 1);
  EXPECT_THROW(vertex_blends(torus, shorter, r.mesh), Error);
  std::vector<uint32_t> out_of_range = r.vertex_successor;
  out_of_range[0] = uint32_t(r.mesh.vertex_count());
  EXPECT_THROW(vertex_blends(torus, out_of_range, r.mesh), Error);
  Mesh more = r.mesh;
  more.positions.push_back({5, 5, 5});  // a vertex that comes from nowhere
  for (auto* stream : {&more.normals}) stream->push_back({0, 0, 1});
  more.uvs[0].push_back({0, 0});
  EXPECT_THROW(vertex_blends(torus, r.vertex_successor, more), Error);
}

}  // namespace
}  // namespace lod
