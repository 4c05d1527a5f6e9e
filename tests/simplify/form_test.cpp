// lod::surface_form and lod::restore_form (src/simplify/form.cpp): the forms are detected, the
// mesh handed to the simplifier is one a collapse can work on, and the result gets its form back.
#include <gtest/gtest.h>

#include <array>
#include <map>
#include <vector>

#include "core/shapes.h"
#include "lodkit/optimize.h"
#include "lodkit/simplify.h"
#include "simplify/form_fixtures.h"
#include "test_support.h"

namespace lod {
namespace {

// restore_form's successors, checked against the simplifier's: each input vertex's successor in the
// restored result stands where its successor in the simplified form stood, and of the restored
// vertices there with its UVs (a UV seam's other side is another vertex of the form), its normal is
// one nearest the input vertex's own (a back's the back's, a flat corner's its face's). Returns how
// many input vertices have one (all but those of wedges that left with their triangles).
size_t expect_successors_follow(const Mesh& input, const SurfaceForm& form, const Mesh& smooth,
                                const std::vector<uint32_t>& smooth_successor, const Mesh& restored,
                                const std::vector<uint32_t>& successor) {
  EXPECT_EQ(successor.size(), input.vertex_count());
  std::map<std::array<float, 5>, std::vector<uint32_t>> at;  // position and UV -> restored vertices
  const auto key = [&](uint32_t v) {
    const float3& p = restored.positions[v];
    const float2 uv = restored.uvs[0].empty() ? float2{} : restored.uvs[0][v];
    return std::array<float, 5>{p.x, p.y, p.z, uv.x, uv.y};
  };
  for (uint32_t v = 0; v < restored.vertex_count(); ++v) at[key(v)].push_back(v);
  const auto dot = [](const float3& a, const float3& b) { return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z; };
  size_t mapped = 0;
  for (uint32_t u = 0; u < input.vertex_count() && u < successor.size(); ++u) {
    const uint32_t s = successor[u], f = smooth_successor[form.source[u]];
    EXPECT_EQ(s == ~0u, f == ~0u) << "input vertex " << u;  // (~0u: left with its triangles)
    if (s == ~0u || f == ~0u) continue;
    ++mapped;
    EXPECT_LT(s, restored.vertex_count()) << u;
    if (s >= restored.vertex_count()) continue;
    EXPECT_EQ(restored.positions[s], smooth.positions[f]) << "input vertex " << u;
    for (const uint32_t w : at[key(s)])
      EXPECT_GE(dot(restored.normals[s], input.normals[u]), dot(restored.normals[w], input.normals[u]) - 1e-6)
          << "input vertex " << u << " has a copy nearer its normal";
  }
  return mapped;
}

TEST(SurfaceForm, OtherMeshesAreLeftAsTheyAre) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);  // smooth normals
  const SurfaceForm form = surface_form(torus);
  EXPECT_FALSE(form.changed());
  EXPECT_EQ(form.mesh.vertex_count(), 0u);  // no copy made
  EXPECT_EQ(&form.to_simplify(torus), &torus);
  Mesh result = torus;
  std::vector<uint32_t> successor;
  restore_form(form, result, successor);
  EXPECT_TRUE(successor.empty());
  EXPECT_EQ(test::mesh_difference(result, torus), "");

  // A single-sided soup with face normals is flat-shaded, not double-sided; without the normals
  // (nothing to facet) it is neither.
  Mesh bare = torus;
  bare.normals.clear();
  EXPECT_FALSE(surface_form(test::triangle_soup(bare)).changed());
}

// Flat shading: the simplifier gets the surface without its normals, welded (the torus's own 800
// positions), and simplifies it; the result gets its face normals back.
TEST(SurfaceForm, FlatShadedIsSimplifiedSmoothAndFacetedAgain) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  const Mesh flat = test::flat_shaded(torus);
  ASSERT_EQ(flat.vertex_count(), 3 * torus.triangle_count());
  const SurfaceForm form = surface_form(flat);
  EXPECT_TRUE(form.flat_shaded);
  EXPECT_FALSE(form.double_sided);
  EXPECT_TRUE(form.mesh.normals.empty());
  EXPECT_EQ(form.mesh.vertex_count(), torus.vertex_count());  // (its UV seam's copies stay apart)
  EXPECT_EQ(form.mesh.triangle_count(), torus.triangle_count());

  // As it came, every vertex is a seam of copies and nothing collapses; prepared, it simplifies.
  EXPECT_EQ(simplify(flat, {.target_ratio = 0.1f}).output_triangles, flat.triangle_count());
  SimplifyResult r = simplify(form.to_simplify(flat), {.target_ratio = 0.1f});
  ASSERT_LE(r.output_triangles, flat.triangle_count() / 10);
  const Mesh smooth_result = r.mesh;
  const std::vector<uint32_t> smooth_successor = r.vertex_successor;
  restore_form(form, r.mesh, r.vertex_successor);
  // Almost every corner of the soup has a successor, on a copy with its own normal.
  EXPECT_GT(expect_successors_follow(flat, form, smooth_result, smooth_successor, r.mesh, r.vertex_successor),
            flat.vertex_count() * 99 / 100);
  EXPECT_EQ(r.mesh.triangle_count(), smooth_result.triangle_count());
  EXPECT_EQ(test::faceted_problem(r.mesh), "");
  // Refaceting moves no position: the same triangles, corner by corner.
  for (size_t c = 0; c < r.mesh.indices.size(); ++c)
    ASSERT_EQ(r.mesh.positions[r.mesh.indices[c]], smooth_result.positions[smooth_result.indices[c]]) << c;
}

TEST(SurfaceForm, DoubleSidedIsSimplifiedByItsFrontsAndGetsItsBacksAgain) {
  const test::TwoSided s = test::double_sided_sheet();
  const SurfaceForm form = surface_form(s.two);
  EXPECT_TRUE(form.double_sided);
  EXPECT_FALSE(form.flat_shaded);
  // The fronts are the sheet: its triangles, on its vertices, with its normals (one normal per
  // position, so not flat-shaded: the backs' vertices are gone).
  EXPECT_EQ(test::mesh_difference(form.mesh, s.sheet), "");

  EXPECT_EQ(simplify(s.two, {.target_ratio = 0.1f}).output_triangles, s.two.triangle_count());  // edges of four triangles
  SimplifyResult r = simplify(form.to_simplify(s.two), {.target_ratio = 0.1f});
  ASSERT_LE(r.output_triangles, s.sheet.triangle_count() / 10);
  const size_t fronts = r.mesh.triangle_count(), front_vertices = r.mesh.vertex_count();
  const Mesh smooth_result = r.mesh;
  const std::vector<uint32_t> smooth_successor = r.vertex_successor;
  restore_form(form, r.mesh, r.vertex_successor);
  EXPECT_EQ(r.mesh.triangle_count(), 2 * fronts);
  EXPECT_GT(expect_successors_follow(s.two, form, smooth_result, smooth_successor, r.mesh, r.vertex_successor),
            s.two.vertex_count() * 99 / 100);
  // The backs (the second half of the input's vertices) go to the backs' copies.
  for (size_t u = 0; u < s.two.vertex_count(); ++u)
    if (r.vertex_successor[u] != ~0u) {
      EXPECT_EQ(r.vertex_successor[u] >= front_vertices, u >= s.sheet.vertex_count()) << u;
    }
  EXPECT_EQ(test::double_sided_problem(r.mesh), "");
}

// Both at once: a double-sided soup with face normals (the backs' are their own face normals, the
// fronts' negated). The fronts are found, then found flat-shaded; the result gets both back.
TEST(SurfaceForm, DoubleSidedAndFlatShaded) {
  const test::TwoSided s = test::double_sided_sheet();
  const Mesh both = test::flat_shaded(s.two);
  const SurfaceForm form = surface_form(both);
  EXPECT_TRUE(form.double_sided);
  EXPECT_TRUE(form.flat_shaded);
  EXPECT_TRUE(form.mesh.normals.empty());
  EXPECT_EQ(form.mesh.vertex_count(), s.sheet.vertex_count());
  SimplifyResult r = simplify(form.to_simplify(both), {.target_ratio = 0.1f});
  ASSERT_LE(r.output_triangles, s.sheet.triangle_count() / 10);
  const Mesh smooth_result = r.mesh;
  const std::vector<uint32_t> smooth_successor = r.vertex_successor;
  restore_form(form, r.mesh, r.vertex_successor);
  EXPECT_GT(expect_successors_follow(both, form, smooth_result, smooth_successor, r.mesh, r.vertex_successor),
            both.vertex_count() * 99 / 100);
  EXPECT_EQ(test::faceted_problem(r.mesh), "");
  EXPECT_EQ(test::double_sided_problem(r.mesh), "");
}

// One back missing, or two: not double-sided (a triangle without a twin would lose its surface).
TEST(SurfaceForm, AnUnpairedTriangleIsNotDoubleSided) {
  const test::TwoSided s = test::double_sided_sheet();
  for (size_t missing : {1, 2}) {
    Mesh m = s.two;
    m.indices.resize(m.indices.size() - 3 * missing);
    EXPECT_FALSE(surface_form(m).double_sided) << missing;
  }
  // The last back wound like its front: the counts match, the pairs do not.
  Mesh m = s.two;
  const size_t last = m.indices.size() - 3;
  std::swap(m.indices[last + 1], m.indices[last + 2]);
  EXPECT_FALSE(surface_form(m).double_sided);
}

}  // namespace
}  // namespace lod
