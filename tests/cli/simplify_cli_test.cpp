// lodkit simplify from the command line: the report matches the written file and the library, and
// a missing target is a usage error.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "core/shapes.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "lodkit/simplify.h"
#include "optimize/optimize_test_support.h"
#include "simplify/form_fixtures.h"
#include "cli/torus_morph.h"
#include "test_support.h"

namespace lod {
namespace {

// A glTF morph target (here each vertex's offset is a linear, invertible function of its position).
// --keep-vertices keeps input vertices unmoved, so it keeps their offsets exactly. Moved vertices get
// offsets interpolated on the input's triangles: the point they stand for (the function inverted)
// lies on the input torus, next to the vertex.
TEST(CliSimplify, KeepsMorphTargetsExactOrInterpolated) {
  test::TempDir dir;
  const Scene scene = test::morphing_torus();
  write_scene(scene, dir / "in.glb");
  ASSERT_EQ(test::glb_morph_positions(dir / "in.glb").size(), scene.primitives[0].mesh.vertex_count());

  test::RunResult r = test::run_cli({"simplify", (dir / "in.glb").string(), "-o", (dir / "subset.glb").string(),
                                     "--ratio", "0.25", "--keep-vertices"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh subset = read_scene(dir / "subset.glb").primitives[0].mesh;
  EXPECT_LE(subset.triangle_count(), scene.primitives[0].mesh.triangle_count() / 4);
  std::vector<float3> offsets = test::glb_morph_positions(dir / "subset.glb");
  ASSERT_EQ(offsets.size(), subset.vertex_count());
  for (size_t v = 0; v < subset.vertex_count(); ++v) ASSERT_EQ(offsets[v], test::morph_offset(subset.positions[v])) << v;

  for (const char* ratio : {"0.25", "0.05"}) {
    r = test::run_cli({"simplify", (dir / "in.glb").string(), "-o", (dir / "moved.glb").string(), "--ratio", ratio});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Mesh moved = read_scene(dir / "moved.glb").primitives[0].mesh;
    offsets = test::glb_morph_positions(dir / "moved.glb");
    ASSERT_EQ(offsets.size(), moved.vertex_count());
    // The vertices moved: offsets were interpolated.
    EXPECT_GT(test::expect_points_on_torus(moved, offsets, ratio), moved.vertex_count() / 10) << ratio;
    test::expect_valid_gltf({dir / "subset.glb", dir / "moved.glb"});
    // lodkit info counts the blend shape.
    const test::RunResult info = test::run_cli({"info", "--json", (dir / "moved.glb").string()});
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_EQ(nlohmann::json::parse(info.out)["gltf"]["morph_targets"], 1) << info.out;
    EXPECT_EQ(nlohmann::json::parse(info.out)["gltf"]["morphing_primitives"], 1);
  }
}

// The same through the forms lodkit simplify changes and gives back (flat-shaded, double-sided,
// both): the restored result's vertices get offsets interpolated on the input's patch too. A second,
// NORMAL displacement (a tenth of each vertex's normal) tells the sides apart: each output vertex's
// must point along its own normal, so a back's came from the backs and a facet's from faces turned
// its way (where the normal says: not at a sliver's corners).
TEST(CliSimplify, KeepsMorphTargetsThroughFlatShadingAndDoubleSides) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  const std::pair<const char*, Mesh> forms[] = {{"flat_shaded", test::flat_shaded(torus)},
                                                {"double_sided", test::double_sided(torus)},
                                                {"both", test::flat_shaded(test::double_sided(torus))}};
  for (const auto& [name, mesh] : forms) {
    Scene scene = scene_from_mesh(mesh);
    MorphTarget target;
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      const float3& n = mesh.normals[v];
      target.positions.push_back(test::morph_offset(mesh.positions[v])), target.normals.push_back({0.1f * n.x, 0.1f * n.y, 0.1f * n.z});
    }
    scene.primitives[0].targets.push_back(target);
    const std::filesystem::path in = dir / (std::string(name) + ".glb"), out = dir / (std::string(name) + "-out.glb");
    write_scene(scene, in);
    const test::RunResult r = test::run_cli({"simplify", in.string(), "-o", out.string(), "--ratio", "0.25", "--json"});
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    const nlohmann::json report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["flat_shaded"].get<bool>(), std::string(name) != "double_sided") << name;
    EXPECT_EQ(report["double_sided"].get<bool>(), std::string(name) != "flat_shaded") << name;
    const Scene result = read_scene(out);
    ASSERT_EQ(result.primitives.size(), 1u);
    const Mesh& moved = result.primitives[0].mesh;
    EXPECT_LE(moved.triangle_count(), mesh.triangle_count() / 4 + 2) << name;
    const std::vector<MorphTarget> targets = source_morph_targets(result, 0);
    ASSERT_EQ(targets.size(), 1u) << name;
    EXPECT_GT(test::expect_points_on_torus(moved, targets[0].positions, name), moved.vertex_count() / 10) << name;
    ASSERT_EQ(targets[0].normals.size(), moved.vertex_count()) << name;
    size_t turned = 0;  // vertices whose normal is off the round torus's by more than 60 degrees
    for (size_t v = 0; v < moved.vertex_count(); ++v) {
      const float3 &d = targets[0].normals[v], &n = moved.normals[v], &p = moved.positions[v];
      // The round torus's outward normal there: from the nearest point of the tube's centre circle.
      const double ring = std::hypot(double(p.x), double(p.y));
      const double tx = p.x - p.x / ring, ty = p.y - p.y / ring, tz = p.z, tl = std::hypot(tx, ty, tz);
      // Only where the normal says which side the vertex is on: a sliver's face normal (a flat
      // result's) may point anywhere.
      if (std::fabs((tx * n.x + ty * n.y + tz * n.z) / tl) < 0.5) {
        ++turned;
        continue;
      }
      // Input displacements are within 20 degrees of the round torus's normal (faces of 9 and 18
      // degrees): along the vertex's normal, by more than 0.1 cos(80 degrees), on its own side.
      EXPECT_GT(double(d.x) * n.x + double(d.y) * n.y + double(d.z) * n.z, 0.017) << name << " vertex " << v;
    }
    EXPECT_LT(turned, moved.vertex_count() / 50) << name;
    test::expect_valid_gltf({out});
  }
}

TEST(CliSimplify, WritesTheLibraryResultAndReportsIt) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  write_mesh(torus, dir / "torus.ply");
  const test::RunResult r =
      test::run_cli({"simplify", (dir / "torus.ply").string(), "-o", (dir / "out.ply").string(), "--ratio", "0.1",
                     "--metric", "cqem", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const Mesh out = read_mesh(dir / "out.ply");
  EXPECT_EQ(j["output_triangles"], out.triangle_count());
  EXPECT_LE(out.triangle_count(), torus.triangle_count() / 10);
  EXPECT_GT(j["fit_seconds"].get<double>(), 0.0);  // the default final fit, part of simplify_seconds
  EXPECT_LE(j["fit_seconds"].get<double>(), j["simplify_seconds"].get<double>());
  double steps = 0;  // the collapses' steps, also part of simplify_seconds
  for (const char* step : {"stars", "ranking", "ordering", "checks", "applying"}) {
    EXPECT_GT(j["collapse_step_seconds"][step].get<double>(), 0.0) << step;
    steps += j["collapse_step_seconds"][step].get<double>();
  }
  EXPECT_LE(steps + j["fit_seconds"].get<double>(), j["simplify_seconds"].get<double>());
  // The same call through the library gives the same mesh (the PLY round trip is exact).
  const SimplifyResult lib = simplify(read_mesh(dir / "torus.ply"), {.target_ratio = 0.1f, .metric = Metric::constrained_qem});
  EXPECT_EQ(lib.mesh.indices, out.indices);
  EXPECT_EQ(lib.mesh.positions, out.positions);
}

// A triangle soup (every triangle its own three vertices, as a non-indexed glTF has them) is welded
// first, so it simplifies like the indexed mesh; a morph target that agrees on the copies of each
// vertex comes through --keep-vertices exact. Before, the soup came back unchanged: every vertex
// was a seam of copies.
TEST(CliSimplify, TriangleSoupsAreWeldedFirst) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  torus.normals.clear();  // positions only: the copies of a vertex are identical
  const Mesh soup = test::triangle_soup(torus);
  write_mesh(soup, dir / "soup.ply");
  test::RunResult r = test::run_cli({"simplify", (dir / "soup.ply").string(), "-o", (dir / "out.ply").string(), "--ratio", "0.1", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["input_vertices"].get<size_t>(), soup.vertex_count());
  EXPECT_EQ(nlohmann::json::parse(r.out)["welded_vertices"].get<size_t>(), torus.vertex_count());
  EXPECT_FALSE(nlohmann::json::parse(r.out)["flat_shaded"].get<bool>());
  const Mesh out = read_mesh(dir / "out.ply");
  EXPECT_LE(out.triangle_count(), torus.triangle_count() / 10);
  const SimplifyResult indexed = simplify(torus, {.target_ratio = 0.1f});
  EXPECT_LE(compare(torus, out).hausdorff, 1.5 * compare(torus, indexed.mesh).hausdorff);

  Scene scene = scene_from_mesh(soup);
  const auto offset = [](const float3& p) { return float3{0.0f, 0.0f, 0.25f * p.x + 0.5f * p.y}; };
  MorphTarget target;
  for (const float3& p : soup.positions) target.positions.push_back(offset(p));
  scene.primitives[0].targets.push_back(target);
  write_scene(scene, dir / "soup.glb");
  r = test::run_cli({"simplify", (dir / "soup.glb").string(), "-o", (dir / "out.glb").string(), "--ratio", "0.25", "--keep-vertices"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh subset = read_scene(dir / "out.glb").primitives[0].mesh;
  EXPECT_LE(subset.triangle_count(), torus.triangle_count() / 4);
  const std::vector<float3> offsets = test::glb_morph_positions(dir / "out.glb");
  ASSERT_EQ(offsets.size(), subset.vertex_count());
  for (size_t v = 0; v < subset.vertex_count(); ++v) ASSERT_EQ(offsets[v], offset(subset.positions[v])) << v;
  // Moved vertices: blends of the welded vertices, taken back to the soup's copies.
  r = test::run_cli({"simplify", (dir / "soup.glb").string(), "-o", (dir / "moved.glb").string(), "--ratio", "0.25"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh moved = read_scene(dir / "moved.glb").primitives[0].mesh;
  const std::vector<float3> interpolated = test::glb_morph_positions(dir / "moved.glb");
  ASSERT_EQ(interpolated.size(), moved.vertex_count());
  for (size_t v = 0; v < moved.vertex_count(); ++v)  // |gradient| < 0.56, vertices within 0.05 of their point
    ASSERT_NEAR(interpolated[v].z, offset(moved.positions[v]).z, 0.03) << v;
  test::expect_valid_gltf({dir / "out.glb", dir / "moved.glb"});
}

// A kind of mesh that lodkit simplify and lodkit lod keep: `input` (as a .glb) at 10% reports `flag`
// in --json and lands within 1.5x the Hausdorff distance of `plain` (the same surface without the
// trait) simplified by the library; that result and each level of a 1, 1/2, 1/4 chain (which
// reports `flag` too) pass `keeps` and have at most their share of the triangles.
void expect_kept_through_simplify_and_lod(const Mesh& input, const char* flag, const Mesh& plain,
                                          const std::function<void(const Mesh&)>& keeps) {
  test::TempDir dir;
  write_mesh(input, dir / "in.glb");
  test::RunResult r = test::run_cli({"simplify", (dir / "in.glb").string(), "-o", (dir / "out.glb").string(), "--ratio", "0.1", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)[flag].get<bool>());
  const Mesh out = read_scene(dir / "out.glb").primitives[0].mesh;
  EXPECT_LE(out.triangle_count(), input.triangle_count() / 10);
  EXPECT_GT(out.triangle_count(), 0u);
  keeps(out);
  const SimplifyResult reference = simplify(plain, {.target_ratio = 0.1f});
  EXPECT_LE(compare(plain, out).hausdorff, 1.5 * compare(plain, reference.mesh).hausdorff);

  r = test::run_cli({"lod", (dir / "in.glb").string(), "-o", (dir / "chain.glb").string(), "--ratios", "1,0.5,0.25", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)[flag].get<bool>());
  const Scene chain = read_scene(dir / "chain.glb");
  ASSERT_EQ(chain.primitives.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    EXPECT_LE(chain.primitives[i].mesh.triangle_count(), input.triangle_count() >> i);
    keeps(chain.primitives[i].mesh);
  }
  test::expect_valid_gltf({dir / "out.glb", dir / "chain.glb"});
}

// Flat shading (each triangle's corners carry its face normal, every vertex its own): the
// normals are set aside, the positions simplified, and each output triangle gets its face normal
// again; lodkit lod's levels too. Before, no vertex could move and nothing was simplified.
TEST(CliSimplify, FlatShadedMeshesStayFlatShaded) {
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  Mesh plain = torus;
  plain.normals.clear();
  expect_kept_through_simplify_and_lod(test::flat_shaded(torus), "flat_shaded", plain,
                                       [](const Mesh& m) { EXPECT_EQ(test::faceted_problem(m), ""); });
}

// Double-sided by duplication: a wavy sheet whose back faces reuse its positions, winding reversed
// and normals negated. Its edges have four triangles, which no collapse may touch; the fronts are
// simplified and the backs made again, in lodkit lod's levels too. Before, nothing simplified.
TEST(CliSimplify, DoubleSidedMeshesStayDoubleSided) {
  const test::TwoSided s = test::double_sided_sheet();
  expect_kept_through_simplify_and_lod(s.two, "double_sided", s.sheet,
                                       [](const Mesh& m) { EXPECT_EQ(test::double_sided_problem(m), ""); });
}

// `flat` (flat-shaded, two materials) as one glTF mesh of two primitives, simplified to a tenth: the
// run succeeds in the flat-shaded form and writes two faceted primitives in a valid file. Returns
// them (none when the run failed).
std::vector<Primitive> simplified_flat_pair(const test::TempDir& dir, const Mesh& flat) {
  const Scene in = scene_from_mesh(flat);
  EXPECT_EQ(in.primitives.size(), 2u);
  write_scene(in, dir / "in.glb");
  const test::RunResult r =
      test::run_cli({"simplify", (dir / "in.glb").string(), "-o", (dir / "out.glb").string(), "--ratio", "0.1", "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return {};
  EXPECT_TRUE(nlohmann::json::parse(r.out)["flat_shaded"].get<bool>());
  Scene out = read_scene(dir / "out.glb");
  EXPECT_EQ(out.primitives.size(), 2u);
  for (const Primitive& p : out.primitives) EXPECT_EQ(test::faceted_problem(p.mesh), "");
  test::expect_valid_gltf({dir / "out.glb"});
  return std::move(out.primitives);
}

// A glTF mesh whose two materials are two primitives, each with its own copy of the border's
// vertices: they are simplified as one mesh, so the border stays closed (welded by position, the
// result has no boundary edge, as the torus has none) and each primitive keeps its material. With
// --keep-vertices each primitive's vertices are its own input vertices.
// The same two primitives, flat-shaded: the group is simplified in its smooth form and each
// primitive faceted again. The result's vertices are then the restored form's, which the simplifier's
// vertex maps do not describe (reading them there once failed the run).
TEST(CliSimplify, FlatShadedPrimitivesOfOneMeshSimplifyTogether) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  torus.uvs[0].clear();
  torus.materials.resize(torus.triangle_count());
  for (size_t t = 0; t < torus.triangle_count(); ++t)
    torus.materials[t] = torus.positions[torus.indices[3 * t]].x + torus.positions[torus.indices[3 * t + 1]].x > 0 ? 1 : 0;
  Mesh flat = test::flat_shaded(torus);
  flat.material_names = {"left", "right"};
  size_t triangles = 0;
  for (const Primitive& p : simplified_flat_pair(dir, flat)) triangles += p.mesh.triangle_count();
  EXPECT_LE(triangles, torus.triangle_count() / 10 + 1);
}

// Two primitives of one mesh drawing the same flat-shaded torus: faceted again, the coincident
// corners of both, alike in every value, weld into vertices that both primitives use. Each input
// vertex still gets its own primitive's successor (the run once failed in vertex_blends: "output
// vertex 0 has no input vertex among its successors' sources"; fuzz/seeds/gltf/quad_nodes_strip.gltf).
TEST(CliSimplify, CoincidentFlatShadedPrimitivesShareFacetedVertices) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  torus.uvs[0].clear();
  const Mesh flat = test::flat_shaded(torus);
  Mesh twice = flat;
  for (const uint32_t i : flat.indices) twice.indices.push_back(uint32_t(flat.vertex_count()) + i);
  twice.positions.insert(twice.positions.end(), flat.positions.begin(), flat.positions.end());
  twice.normals.insert(twice.normals.end(), flat.normals.begin(), flat.normals.end());
  twice.materials.assign(flat.triangle_count(), 0);
  twice.materials.resize(2 * flat.triangle_count(), 1);
  twice.material_names = {"a", "b"};
  for (const Primitive& p : simplified_flat_pair(dir, twice))
    EXPECT_GT(p.mesh.triangle_count(), 0u);  // (coincident, every edge is non-manifold: few collapses)
}

// Also when one has streams the other lacks (UVs on the left only): each keeps its own.
TEST(CliSimplify, PrimitivesOfOneMeshKeepTheirBordersClosed) {
  test::TempDir dir;
  Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  torus.materials.resize(torus.triangle_count());
  for (size_t t = 0; t < torus.triangle_count(); ++t) {
    float x = 0;
    for (int c = 0; c < 3; ++c) x += torus.positions[torus.indices[3 * t + c]].x;
    torus.materials[t] = x > 0 ? 1 : 0;
  }
  torus.material_names = {"left", "right"};
  Scene in = scene_from_mesh(torus);
  ASSERT_EQ(in.primitives.size(), 2u);
  ASSERT_FALSE(torus.uvs[0].empty());
  write_scene(in, dir / "in.glb");
  in.primitives[1].mesh.uvs[0].clear();
  write_scene(in, dir / "mixed.glb");

  for (const bool subset : {false, true})
  for (const bool mixed : {false, true}) {
    SCOPED_TRACE(mixed);
    std::vector<std::string> args = {"simplify", (dir / (mixed ? "mixed.glb" : "in.glb")).string(), "-o",
                                     (dir / "out.glb").string(), "--ratio", "0.1", "--force"};
    if (subset) args.push_back("--keep-vertices");
    const test::RunResult r = test::run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Scene out = read_scene(dir / "out.glb");
    ASSERT_EQ(out.primitives.size(), 2u) << subset;
    Mesh welded;  // both primitives in one mesh: compute_stats joins them by position
    for (size_t p = 0; p < 2; ++p) {
      const Mesh& m = out.primitives[p].mesh;
      EXPECT_EQ(out.primitives[p].material, in.primitives[p].material) << subset;
      EXPECT_GT(m.triangle_count(), 0u) << subset;
      EXPECT_EQ(m.uvs[0].empty(), mixed && p == 1) << subset;
      EXPECT_FALSE(m.normals.empty()) << subset;
      if (subset) {
        const std::vector<float3>& own = in.primitives[p].mesh.positions;
        for (const float3& v : m.positions)
          ASSERT_NE(std::find(own.begin(), own.end(), v), own.end()) << "primitive " << p;
      }
      const uint32_t base = uint32_t(welded.positions.size());
      welded.positions.insert(welded.positions.end(), m.positions.begin(), m.positions.end());
      for (const uint32_t i : m.indices) welded.indices.push_back(base + i);
    }
    EXPECT_LE(welded.triangle_count(), torus.triangle_count() / 10 + 1) << subset;
    const MeshStats stats = compute_stats(welded);
    EXPECT_EQ(stats.boundary_edges, 0u) << subset;
    EXPECT_EQ(stats.non_manifold_edges, 0u) << subset;
    test::expect_valid_gltf({dir / "out.glb"});
  }
}

// --aggregate: two spheres 0.05 apart come out as one part, and the report counts the virtual pairs.
TEST(CliSimplify, AggregateJoinsParts) {
  test::TempDir dir;
  Mesh two = shapes::icosphere(2);
  const size_t n = two.positions.size();
  two.normals.clear();
  for (size_t v = 0; v < n; ++v) two.positions[v].x -= 1.025f;
  const Mesh other = two;
  for (size_t v = 0; v < n; ++v) two.positions.push_back({other.positions[v].x + 2.05f, other.positions[v].y, other.positions[v].z});
  for (const uint32_t i : other.indices) two.indices.push_back(uint32_t(n) + i);
  write_mesh(two, dir / "two.ply");
  for (const char* reach : {"0", "0.3"}) {
    const test::RunResult r = test::run_cli({"simplify", (dir / "two.ply").string(), "-o", (dir / "out.ply").string(),
                                             "--ratio", "0.1", "--aggregate", reach, "--force", "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const size_t parts = compute_stats(read_mesh(dir / "out.ply")).components.size();
    EXPECT_EQ(parts, std::string(reach) == "0" ? 2u : 1u) << reach;
    EXPECT_EQ(j["virtual_pairs"].get<uint64_t>() > 0, std::string(reach) != "0") << reach;
  }
}

// The search (SimplifyOptions::search_input_triangles) is on by default and reported; --no-search turns it
// off and gives the library's result for the options as set.
TEST(CliSimplify, ReportsTheSearchAndTurnsItOff) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  write_mesh(torus, dir / "torus.ply");
  for (const bool search : {true, false}) {
    std::vector<std::string> args{"simplify", (dir / "torus.ply").string(), "-o", (dir / "out.ply").string(),
                                  "--ratio", "0.05", "--force", "--json"};
    if (!search) args.push_back("--no-search");
    const test::RunResult r = test::run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["search_ways"].get<uint32_t>(), search ? 5u : 1u);
    ASSERT_EQ(j["kept"].size(), 1u);
    const SimplifyResult lib = simplify(torus, {.target_ratio = 0.05f, .search_input_triangles = search ? SimplifyOptions{}.search_input_triangles : 0});
    EXPECT_EQ(j["kept"][0]["metric"].get<std::string>(), metric_name(lib.metric));
    EXPECT_EQ(j["kept"][0]["distance_guard"].get<float>(), lib.distance_guard);
    EXPECT_EQ(j["kept"][0]["fit_flips"].get<bool>(), lib.fit_flips);
    EXPECT_EQ(j["kept"][0]["fit_edge_weight"].get<float>(), lib.fit_edge_weight);
    EXPECT_EQ(read_mesh(dir / "out.ply").indices, lib.mesh.indices);
  }
}

// --fit-edge-weight and --no-flips reach the library: a plain fit, as simplify() gives it; a negative
// weight is a usage error.
TEST(CliSimplify, FitOptionsReachTheLibrary) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  write_mesh(torus, dir / "torus.ply");
  const test::RunResult r = test::run_cli({"simplify", (dir / "torus.ply").string(), "-o", (dir / "out.ply").string(), "--ratio",
                                           "0.05", "--no-search", "--no-flips", "--fit-edge-weight", "0", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const SimplifyResult lib =
      simplify(torus, {.target_ratio = 0.05f, .fit_flips = false, .fit_edge_weight = 0, .search_input_triangles = 0});
  const Mesh out = read_mesh(dir / "out.ply");
  EXPECT_EQ(out.indices, lib.mesh.indices);
  EXPECT_EQ(out.positions, lib.mesh.positions);
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["kept"][0]["fit_flips"].get<bool>());
  EXPECT_EQ(j["kept"][0]["fit_edge_weight"].get<float>(), 0.0f);
  const test::RunResult bad = test::run_cli({"simplify", (dir / "torus.ply").string(), "-o", (dir / "bad.ply").string(),
                                             "--ratio", "0.05", "--fit-edge-weight", "-1"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("fit_edge_weight"), std::string::npos) << bad.err;
}

TEST(CliSimplify, NeedsATarget) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(1), dir / "s.ply");
  const test::RunResult r = test::run_cli({"simplify", (dir / "s.ply").string(), "-o", (dir / "o.ply").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("target"), std::string::npos) << r.err;
  const test::RunResult bad = test::run_cli(
      {"simplify", (dir / "s.ply").string(), "-o", (dir / "o.ply").string(), "--ratio", "0.5", "--metric", "nope"});
  EXPECT_EQ(bad.exit_code, 1);
}

// Targets given together stop at whichever is reached first: the larger triangle count. A torus of
// 40 x 20 quads has 1,600 triangles, so --ratio 0.5 means 800 and --ratio 0.01 means 16.
TEST(CliSimplify, TargetsStopAtWhicheverIsReachedFirst) {
  test::TempDir dir;
  const Mesh torus = shapes::torus(1.0f, 0.3f, 40, 20);
  ASSERT_EQ(torus.triangle_count(), 1600u);
  write_mesh(torus, dir / "torus.ply");
  const auto run = [&](std::vector<std::string> target) {
    std::vector<std::string> args = {"simplify", (dir / "torus.ply").string(), "-o", (dir / "out.ply").string(), "--json"};
    args.insert(args.end(), target.begin(), target.end());
    const test::RunResult r = test::run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_mesh(dir / "out.ply");
  };
  const Mesh half = run({"--ratio", "0.5", "--triangles", "10"});
  EXPECT_EQ(half.indices, simplify(torus, {.target_triangles = 800, .record = false}).mesh.indices);
  EXPECT_GE(half.triangle_count(), 799u);  // a collapse removes two triangles: one below at most
  const Mesh sixteen = run({"--triangles", "10", "--ratio", "0.01"});
  EXPECT_EQ(sixteen.indices, simplify(torus, {.target_triangles = 16, .record = false}).mesh.indices);
  // --triangles 0 is a target (as few as the mesh allows), the same as --ratio 0.
  EXPECT_EQ(run({"--triangles", "0"}).indices, run({"--ratio", "0"}).indices);
}

TEST(CliSimplify, RejectsTargetsThatAreNotNumbersInRange) {
  test::TempDir dir;
  write_mesh(shapes::icosphere(1), dir / "s.ply");
  for (const auto& [option, value, message] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"--ratio", "nan", "--ratio"}, {"--ratio", "1.5", "--ratio"}, {"--ratio", "-0.1", "--ratio"},
           {"--error", "nan", "--error"}, {"--error", "-1", "--error"}}) {
    const test::RunResult r =
        test::run_cli({"simplify", (dir / "s.ply").string(), "-o", (dir / "o.ply").string(), option, value});
    EXPECT_EQ(r.exit_code, 1) << option << " " << value;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "o.ply")) << option << " " << value;
  }
}

}  // namespace
}  // namespace lod
