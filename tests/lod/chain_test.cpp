// LOD chains and geomorphs: level sizes and error bounds, the geomorph invariants at t = 0 and 1
// and linearity between, composition, and the shared vertex buffer.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"
#include "lodkit/measure.h"
#include "lodkit/optimize.h"

namespace lod {
namespace {

// A corner's full vertex data, and a triangle as three of them rotated to start at the smallest
// (winding kept), so triangles compare as values.
using Corner = std::tuple<float, float, float, float, float, float, float, float>;
using Triangle = std::array<Corner, 3>;

Corner corner(const Mesh& m, uint32_t v) {
  const float3& p = m.positions[v];
  const float3 n = m.normals.empty() ? float3{} : m.normals[v];
  const float2 uv = m.uvs[0].empty() ? float2{} : m.uvs[0][v];
  return {p.x, p.y, p.z, n.x, n.y, n.z, uv.x, uv.y};
}

// Triangles whose three corners sit at distinct positions, as a sorted multiset.
std::vector<Triangle> proper_triangles(const Mesh& m) {
  std::vector<Triangle> out;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const uint32_t* i = &m.indices[3 * t];
    const float3 &a = m.positions[i[0]], &b = m.positions[i[1]], &c = m.positions[i[2]];
    if (a == b || b == c || c == a) continue;
    Triangle tri = {corner(m, i[0]), corner(m, i[1]), corner(m, i[2])};
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

LodChain morph_chain(const Mesh& mesh) {
  return build_lod_chain(mesh, {.ratios = {1.0f, 0.5f, 0.2f, 0.05f},
                                .morph = true,
                                .measure = false,
                                .simplify = {.normal_weight = 0.5f, .uv_weight = 0.5f}});
}

TEST(LodChain, LevelsFollowTheRatios) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 48, 24);
  const LodChain chain = build_lod_chain(mesh, {.levels = 5});
  ASSERT_EQ(chain.levels.size(), 5u);
  // Level 0 is the input, reordered for the vertex cache: the same triangles.
  EXPECT_EQ(proper_triangles(chain.levels[0].mesh), proper_triangles(mesh));
  EXPECT_EQ(chain.levels[0].error, 0.0f);
  for (size_t i = 1; i < chain.levels.size(); ++i) {
    const size_t expected = size_t(std::llround(double(mesh.triangle_count()) / double(1u << i)));
    EXPECT_LE(chain.levels[i].mesh.triangle_count(), expected);
    EXPECT_GE(chain.levels[i].mesh.triangle_count() + 2, expected);  // a collapse removes at most 2
    EXPECT_GE(chain.levels[i].engine_error, chain.levels[i - 1].engine_error);
    EXPECT_GT(chain.levels[i].error, 0.0f);
  }
}

// The stored bound covers what an independent, denser measurement finds, and the stored error agrees with it.
TEST(LodChain, ErrorBoundCoversAFinerMeasurement) {
  const Mesh mesh = shapes::icosphere(3);
  const LodChain chain = build_lod_chain(mesh, {.ratios = {1.0f, 0.3f, 0.1f}});
  for (size_t i = 1; i < chain.levels.size(); ++i) {
    const Deviation d = compare(mesh, chain.levels[i].mesh, {.samples = 200'000, .seed = 99});
    EXPECT_GE(chain.levels[i].error_bound, float(d.hausdorff) * (1 - 1e-5f)) << "level " << i;
    EXPECT_GE(chain.levels[i].error_bound, chain.levels[i].error) << "level " << i;
    // And it is tight enough to drive the runtime: within the refinement's 1e-5 of the diagonal.
    EXPECT_LE(chain.levels[i].error_bound, chain.levels[i].error + 1.01e-5f * float(chain.diagonal)) << "level " << i;
    // The lighter measurement stored finds nearly the same maximum as the dense one.
    EXPECT_NEAR(chain.levels[i].error, float(d.hausdorff), 0.05f * float(d.hausdorff)) << "level " << i;
  }
}

// Levels by error are held to the distance measured, not to the simplifier's own estimate (which
// the measured distance runs past): each level's certified bound, and an independent dense
// measurement, stay within its limit, and the search does not settle far finer than it needs.
TEST(LodChain, LevelsByErrorStayWithinTheirLimitsAsMeasured) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 48, 24);
  const std::vector<float> limits = {0.0f, 0.002f, 0.01f};
  for (const bool from_previous : {false, true}) {
    SCOPED_TRACE(from_previous ? "from the previous level" : "from the input");
    const LodChain chain = build_lod_chain(mesh, {.errors = limits, .from_previous = from_previous});
    ASSERT_EQ(chain.levels.size(), 3u);
    EXPECT_EQ(proper_triangles(chain.levels[0].mesh), proper_triangles(mesh));
    EXPECT_LT(chain.levels[2].mesh.triangle_count(), chain.levels[1].mesh.triangle_count());
    EXPECT_LT(chain.levels[1].mesh.triangle_count(), mesh.triangle_count());
    for (size_t i = 1; i < 3; ++i) {
      SCOPED_TRACE("level " + std::to_string(i));
      const double limit = double(limits[i]) * chain.diagonal;
      EXPECT_LE(chain.levels[i].error_bound, limit);
      EXPECT_LE(chain.levels[i].error, chain.levels[i].error_bound);
      const Deviation dense = compare(mesh, chain.levels[i].mesh, {.samples = 200'000, .seed = 7, .refine = true});
      EXPECT_LE(dense.hausdorff, limit);
      EXPECT_GE(chain.levels[i].error_bound, 0.5 * limit);
    }
  }
}

// The search's tries and measurements do not depend on the thread count, so neither do its levels.
TEST(LodChain, LevelsByErrorAreTheSameOnAnyThreadCount) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 48, 24);
  const auto chain_on = [&](unsigned threads) {
    return build_lod_chain(mesh, {.errors = {0.0f, 0.003f, 0.02f}, .simplify = {.threads = threads}});
  };
  const LodChain one = chain_on(1);
  for (const unsigned threads : {2u, 8u}) {
    const LodChain other = chain_on(threads);
    ASSERT_EQ(other.levels.size(), one.levels.size());
    for (size_t i = 0; i < one.levels.size(); ++i) {
      EXPECT_EQ(other.levels[i].mesh, one.levels[i].mesh) << threads << " threads, level " << i;
      EXPECT_EQ(other.levels[i].error_bound, one.levels[i].error_bound) << threads << " threads, level " << i;
    }
  }
}

// A simplifier that overshoots every target (it always goes down to 8 triangles) leaves the search
// nothing within the limit: the level then keeps its source's triangles, still within the limit.
TEST(LodChain, LevelByErrorKeepsItsSourceWhenNoTryIsWithinTheLimit) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 24, 12);
  LodOptions options{.errors = {0.0f, 0.001f}};
  int calls = 0;
  options.simplifier = [&](const Mesh& source, const SimplifyOptions& so) {
    ++calls;
    SimplifyOptions coarse = so;
    if (so.target_triangles != source.triangle_count()) coarse.target_triangles = 8, coarse.max_error = -1;
    return simplify(source, coarse);
  };
  const LodChain chain = build_lod_chain(mesh, options);
  ASSERT_EQ(chain.levels.size(), 2u);
  EXPECT_GE(calls, 2);  // the search tried, then kept the source
  EXPECT_EQ(chain.levels[1].mesh.triangle_count(), mesh.triangle_count());
  EXPECT_LE(chain.levels[1].error_bound, 0.001 * chain.diagonal);
}

// When the first try (the simplifier's own error stop) lands far past the limit, the power law from
// it alone asks for more triangles than the source has: the search still tries between the two and
// finds a level, rather than keeping the source.
TEST(LodChain, LevelByErrorSearchesBetweenAFarFirstTryAndTheSource) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 48, 24);
  LodOptions options{.errors = {0.0f, 0.002f}};
  options.simplifier = [](const Mesh& source, const SimplifyOptions& so) {
    SimplifyOptions s = so;
    if (so.max_error >= 0) s.target_triangles = 8, s.max_error = -1;  // an error stop far too loose
    return simplify(source, s);
  };
  const LodChain chain = build_lod_chain(mesh, options);
  ASSERT_EQ(chain.levels.size(), 2u);
  const double limit = 0.002 * chain.diagonal;
  EXPECT_LT(chain.levels[1].mesh.triangle_count(), mesh.triangle_count() * 3 / 4);
  EXPECT_LE(chain.levels[1].error_bound, limit);
  EXPECT_GE(chain.levels[1].error_bound, 0.3 * limit);
}

TEST(Geomorph, EndsAreExactAndTheMiddleIsLinear) {
  for (const Mesh& mesh : {shapes::torus(1.0f, 0.3f, 32, 16), shapes::cylinder(24, 2.0f)}) {
    const LodChain chain = morph_chain(mesh);
    ASSERT_EQ(chain.morphs.size(), chain.levels.size() - 1);
    for (size_t i = 0; i + 1 < chain.levels.size(); ++i) {
      SCOPED_TRACE("level " + std::to_string(i));
      const Mesh &fine = chain.levels[i].mesh, &coarse = chain.levels[i + 1].mesh;
      const Geomorph& g = chain.morphs[i];
      EXPECT_EQ(morph(fine, coarse, g, 0.0f), fine);
      // t = 1: the proper triangles are exactly the coarser level's, attributes included.
      const Mesh end = morph(fine, coarse, g, 1.0f);
      EXPECT_EQ(proper_triangles(end), proper_triangles(coarse));
      EXPECT_EQ(proper_triangles(coarse).size(), coarse.triangle_count());
      // In between, every position is the linear blend.
      const Mesh half = morph(fine, coarse, g, 0.25f);
      for (size_t v = 0; v < fine.vertex_count(); ++v) {
        const float3 &a = fine.positions[v], &b = coarse.positions[g.target[v]], &m = half.positions[v];
        ASSERT_NEAR(m.x, 0.75f * a.x + 0.25f * b.x, 1e-6f);
        ASSERT_NEAR(m.y, 0.75f * a.y + 0.25f * b.y, 1e-6f);
        ASSERT_NEAR(m.z, 0.75f * a.z + 0.25f * b.z, 1e-6f);
      }
    }
  }
}

TEST(Geomorph, ChainsComposeAndEveryTargetExists) {
  const LodChain chain = morph_chain(shapes::torus(1.0f, 0.3f, 32, 16));
  Geomorph total = chain.morphs[0];
  for (size_t i = 0; i < chain.morphs.size(); ++i) {
    for (const uint32_t t : chain.morphs[i].target) ASSERT_LT(t, chain.levels[i + 1].mesh.vertex_count());
    if (i) total = compose(total, chain.morphs[i]);
    // Level 0 morphed straight to level i + 1 ends exactly on it.
    const Mesh& coarse = chain.levels[i + 1].mesh;
    EXPECT_EQ(proper_triangles(morph(chain.levels[0].mesh, coarse, total, 1.0f)), proper_triangles(coarse))
        << "0 -> " << i + 1;
  }
  EXPECT_THROW(compose(chain.morphs[0], chain.morphs[2]), Error);  // level 1 targets past level 2's table
}

// Every level is ordered for the vertex cache: fewer misses per triangle than the simplifier's order.
TEST(LodChain, LevelsAreVertexCacheOptimised) {
  const Mesh mesh = subdivide_midpoint(shapes::torus(1.0f, 0.3f, 48, 24));
  const LodChain plain = build_lod_chain(mesh, {.ratios = {1.0f, 0.3f}, .measure = false, .optimize = false});
  const LodChain tuned = build_lod_chain(mesh, {.ratios = {1.0f, 0.3f}, .measure = false});
  for (size_t i = 0; i < 2; ++i) {
    const Mesh &a = plain.levels[i].mesh, &b = tuned.levels[i].mesh;
    EXPECT_EQ(proper_triangles(a), proper_triangles(b));
    EXPECT_LT(analyze_vertex_cache(b.indices, b.vertex_count()).acmr, analyze_vertex_cache(a.indices, a.vertex_count()).acmr);
  }
}

TEST(LodChain, SharedVerticesArePrefixes) {
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 32, 16);
  const LodChain chain = build_lod_chain(mesh, {.ratios = {1.0f, 0.4f, 0.1f}, .shared_vertices = true});
  const SharedVertices& s = chain.shared;
  ASSERT_EQ(s.indices.size(), 3u);
  EXPECT_EQ(s.prefix[0], s.vertices.vertex_count());
  for (size_t i = 0; i < 3; ++i) {
    if (i) {
      EXPECT_LT(s.prefix[i], s.prefix[i - 1]);
    }
    for (const uint32_t v : s.indices[i]) ASSERT_LT(v, s.prefix[i]);
    // The level drawn from the shared buffer is the level (positions: subset placement keeps them).
    ASSERT_EQ(s.indices[i].size(), chain.levels[i].mesh.indices.size());
    for (size_t k = 0; k < s.indices[i].size(); ++k)
      ASSERT_EQ(s.vertices.positions[s.indices[i][k]], chain.levels[i].mesh.positions[chain.levels[i].mesh.indices[k]]);
  }
}

// A batch gives each mesh the chain build_lod_chain gives it alone, whichever of its meshes are
// built side by side (the small ones) and on how many threads; progress rises to 1.
TEST(LodChain, ABatchBuildsEachMeshsOwnChain) {
  const Mesh large = shapes::torus(1.0f, 0.3f, 200, 90);  // 36,000 triangles: built alone
  ASSERT_GE(large.triangle_count(), 32768u);
  const std::vector<Mesh> meshes = {shapes::icosphere(3), large, shapes::torus(1.0f, 0.4f, 24, 12),
                                    shapes::cylinder(20, 1.5f), shapes::cube()};
  const std::vector<const Mesh*> pointers = {&meshes[0], &meshes[1], &meshes[2], &meshes[3], &meshes[4]};
  std::vector<LodChain> alone;
  for (const Mesh& mesh : meshes) alone.push_back(build_lod_chain(mesh, {.levels = 3, .simplify = {.threads = 1}}));
  for (const unsigned threads : {1u, 2u}) {
    std::vector<double> progress;
    LodOptions options{.levels = 3, .simplify = {.threads = threads}};
    options.progress = [&](double f) { progress.push_back(f); };
    const std::vector<LodChain> chains = build_lod_chains(pointers, options);
    ASSERT_EQ(chains.size(), meshes.size());
    for (size_t i = 0; i < meshes.size(); ++i) {
      ASSERT_EQ(chains[i].levels.size(), alone[i].levels.size()) << "mesh " << i << ", " << threads << " threads";
      for (size_t l = 0; l < alone[i].levels.size(); ++l) {
        EXPECT_EQ(chains[i].levels[l].mesh, alone[i].levels[l].mesh) << "mesh " << i << " level " << l;
        EXPECT_EQ(chains[i].levels[l].error_bound, alone[i].levels[l].error_bound) << "mesh " << i << " level " << l;
        EXPECT_EQ(chains[i].levels[l].vertex_successor, alone[i].levels[l].vertex_successor);
      }
    }
    ASSERT_FALSE(progress.empty());
    EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
    EXPECT_EQ(progress.back(), 1.0);
  }
  EXPECT_TRUE(build_lod_chains({}, {}).empty());
  const std::vector<const Mesh*> with_null = {&meshes[0], nullptr};
  EXPECT_THROW(build_lod_chains(with_null, {}), Error);
}

TEST(LodChain, BadOptionsAreUsageErrors) {
  const Mesh mesh = shapes::icosphere(1);
  EXPECT_THROW(build_lod_chain(mesh, {.ratios = {0.5f, 0.7f}}), Error);
  EXPECT_THROW(build_lod_chain(mesh, {.ratios = {1.0f}, .errors = {0.0f}}), Error);
  EXPECT_THROW(build_lod_chain(mesh, {.from_previous = false, .morph = true}), Error);
  EXPECT_DOUBLE_EQ(switch_distance(0.01, 1.0, 1080.0, M_PI / 2), 0.01 * 1080.0 / 2.0);
}

}  // namespace
}  // namespace lod
