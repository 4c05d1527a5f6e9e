// Statistics against hand-derived values on procedural shapes, and against an independent,
// deliberately naive recomputation (ordered containers, BFS) on every corpus mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <queue>
#include <set>
#include <tuple>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/mesh.h"
#include "test_support.h"

namespace lod {
namespace {

TEST(Stats, IcosphereIsClosedGenusZero) {
  for (uint32_t n : {0u, 1u, 3u}) {
    Mesh m = shapes::icosphere(n);
    MeshStats s = compute_stats(m);
    const uint64_t faces = 20ull << (2 * n);  // 20 * 4^n
    EXPECT_EQ(s.triangles, faces);
    EXPECT_EQ(s.vertices, faces / 2 + 2);  // V = F/2 + 2 for a closed triangulated sphere
    EXPECT_EQ(s.edges, faces * 3 / 2);
    EXPECT_EQ(s.euler_characteristic, 2);
    ASSERT_EQ(s.components.size(), 1u);
    EXPECT_TRUE(s.components[0].closed);
    EXPECT_TRUE(s.components[0].manifold);
    EXPECT_TRUE(s.components[0].orientable);
    EXPECT_EQ(s.components[0].genus, 0);
    EXPECT_EQ(s.boundary_loops, 0u);
    EXPECT_EQ(s.seam_edges, 0u);
    EXPECT_NEAR(s.diagonal, 2.0 * std::sqrt(3.0), 0.6);  // bbox of a unit sphere: up to [-1,1]^3
  }
}

TEST(Stats, IcosphereFacesPointOutward) {
  Mesh m = shapes::icosphere(2);
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const float3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]], &c = m.positions[m.indices[3 * t + 2]];
    float3 u{b.x - a.x, b.y - a.y, b.z - a.z}, v{c.x - a.x, c.y - a.y, c.z - a.z};
    float3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    EXPECT_GT(n.x * (a.x + b.x + c.x) + n.y * (a.y + b.y + c.y) + n.z * (a.z + b.z + c.z), 0) << "triangle " << t;
  }
}

TEST(Stats, TorusHasGenusOneAndSeamsAlongBothCuts) {
  const uint32_t segments = 24, sides = 12;
  Mesh m = shapes::torus(1.0f, 0.25f, segments, sides);
  MeshStats s = compute_stats(m);
  EXPECT_EQ(s.vertices, (segments + 1) * (sides + 1));
  EXPECT_EQ(s.unique_positions, segments * sides);
  EXPECT_EQ(s.triangles, 2 * segments * sides);
  EXPECT_EQ(s.euler_characteristic, 0);
  ASSERT_EQ(s.components.size(), 1u);
  EXPECT_EQ(s.components[0].genus, 1);
  EXPECT_TRUE(s.components[0].closed);
  // The duplicated uv rows cut along one ring of `sides` edges and one of `segments` edges.
  EXPECT_EQ(s.seam_edges, segments + sides);
}

TEST(Stats, GridIsADiskWithOneBoundaryLoop) {
  const uint32_t nx = 7, ny = 5;
  MeshStats s = compute_stats(shapes::grid(nx, ny));
  EXPECT_EQ(s.vertices, (nx + 1) * (ny + 1));
  EXPECT_EQ(s.triangles, 2 * nx * ny);
  EXPECT_EQ(s.boundary_edges, 2 * (nx + ny));
  EXPECT_EQ(s.boundary_loops, 1u);
  EXPECT_EQ(s.euler_characteristic, 1);
  ASSERT_EQ(s.components.size(), 1u);
  EXPECT_FALSE(s.components[0].closed);
  EXPECT_EQ(s.components[0].genus, 0);
}

TEST(Stats, CubeHas24VerticesOn8PositionsAndHardEdgeSeams) {
  Mesh m = shapes::cube();
  MeshStats s = compute_stats(m);
  EXPECT_EQ(s.vertices, 24u);
  EXPECT_EQ(s.unique_positions, 8u);
  EXPECT_EQ(s.triangles, 12u);
  EXPECT_EQ(s.edges, 18u);       // 12 cube edges + 6 face diagonals
  EXPECT_EQ(s.seam_edges, 12u);  // every cube edge separates two faces' own vertices
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_EQ(s.components.at(0).genus, 0);
  EXPECT_EQ(position_ids(m).count, 8u);
}

TEST(Stats, CylinderIsClosedWithRimAndSideSeams) {
  const uint32_t segments = 10;
  MeshStats s = compute_stats(shapes::cylinder(segments, 2.0f));
  EXPECT_EQ(s.unique_positions, 2 * segments + 2);
  EXPECT_EQ(s.triangles, 4 * segments);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_EQ(s.components.at(0).genus, 0);
  EXPECT_EQ(s.seam_edges, 2 * segments + 1);  // two rims, one vertical uv cut
}

TEST(Stats, FinIsNonManifold) {
  MeshStats s = compute_stats(shapes::fin());
  EXPECT_EQ(s.non_manifold_edges, 1u);
  EXPECT_EQ(s.non_manifold_vertices, 2u);  // both ends of the shared edge have three fans
  EXPECT_EQ(s.boundary_edges, 6u);
  EXPECT_EQ(s.boundary_loops, 3u);  // each flap's open path
  ASSERT_EQ(s.components.size(), 1u);
  EXPECT_FALSE(s.components[0].manifold);
  EXPECT_EQ(s.components[0].genus, -1);
}

TEST(Stats, BowtieHasOneNonManifoldVertexAndTwoLoops) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  m.indices = {0, 1, 2, 0, 3, 4};
  MeshStats s = compute_stats(m);
  EXPECT_EQ(s.non_manifold_vertices, 1u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.boundary_loops, 2u);
  EXPECT_EQ(s.connected_components, 1u);
}

TEST(Stats, MoebiusStripIsNotOrientable) {
  // A strip of n quads whose ends are glued with a half twist.
  const int n = 8;
  Mesh m;
  for (int i = 0; i < n; ++i) {
    float a = 2.0f * 3.14159265f * float(i) / float(n), h = a / 2;
    float r = 2.0f;
    for (int side : {-1, 1}) {
      float w = 0.5f * float(side);
      m.positions.push_back({(r + w * std::cos(h)) * std::cos(a), (r + w * std::cos(h)) * std::sin(a), w * std::sin(h)});
    }
  }
  for (int i = 0; i < n; ++i) {
    uint32_t a0 = 2 * i, a1 = 2 * i + 1;
    uint32_t b0 = 2 * ((i + 1) % n), b1 = 2 * ((i + 1) % n) + 1;
    if (i == n - 1) std::swap(b0, b1);  // the half twist
    m.indices.insert(m.indices.end(), {a0, b0, b1, a0, b1, a1});
  }
  MeshStats s = compute_stats(m);
  ASSERT_EQ(s.components.size(), 1u);
  EXPECT_TRUE(s.components[0].manifold);
  EXPECT_FALSE(s.components[0].orientable);
  EXPECT_EQ(s.components[0].genus, -1);
  EXPECT_EQ(s.boundary_loops, 1u);  // a Moebius strip has a single boundary curve
  EXPECT_EQ(s.euler_characteristic, 0);
}

TEST(Stats, DegenerateZeroAreaAndDuplicateTriangles) {
  Mesh m = shapes::icosphere(1);
  const uint32_t a = m.indices[0], b = m.indices[1], c = m.indices[2];
  m.indices.insert(m.indices.end(), {c, b, a});  // duplicate with the opposite winding
  m.indices.insert(m.indices.end(), {a, a, b});  // degenerate
  m.positions.push_back({5, 0, 0});
  m.positions.push_back({6, 0, 0});
  m.positions.push_back({7, 0, 0});
  m.normals.resize(m.positions.size());
  const uint32_t n = uint32_t(m.positions.size());
  m.indices.insert(m.indices.end(), {n - 3, n - 2, n - 1});  // collinear: zero area
  MeshStats s = compute_stats(m);
  EXPECT_EQ(s.duplicate_triangles, 1u);
  EXPECT_EQ(s.degenerate_triangles, 1u);
  EXPECT_EQ(s.zero_area_triangles, 1u);
  EXPECT_EQ(s.non_manifold_edges, 3u);  // the duplicated triangle's edges now have three triangles
  EXPECT_EQ(s.connected_components, 2u);
}

TEST(Stats, SignedZeroWeldsAndTwoComponentsCount) {
  Mesh m = shapes::grid(2, 2);
  for (float3& p : m.positions)
    if (p.x == 0) p.x = -0.0f;
  Mesh two = m;
  for (float3& p : m.positions) two.positions.push_back({p.x + 5, p.y, p.z});
  two.normals.insert(two.normals.end(), m.normals.begin(), m.normals.end());
  two.uvs[0].insert(two.uvs[0].end(), m.uvs[0].begin(), m.uvs[0].end());
  const uint32_t offset = uint32_t(m.positions.size());
  for (uint32_t i : m.indices) two.indices.push_back(i + offset);
  // A third copy whose x = 0 column is +0.0: it must weld onto the first copy's -0.0 column.
  two.positions.push_back({0.0f, 0.0f, 0.0f});
  two.normals.push_back({0, 0, 1});
  two.uvs[0].push_back({0, 0});
  EXPECT_EQ(position_ids(two).count, 2 * offset);
  MeshStats s = compute_stats(two);
  EXPECT_EQ(s.connected_components, 2u);
  EXPECT_EQ(s.boundary_loops, 2u);
}

// ---- independent recomputation on the corpus -------------------------------------------------

struct NaiveTopology {
  uint64_t vertices = 0, edges = 0, faces = 0, boundary_edges = 0, components = 0, boundary_components = 0;
  bool boundary_vertices_have_degree_two = true;
};

NaiveTopology naive_topology(const Mesh& m) {
  using Key = std::tuple<float, float, float>;
  std::map<Key, uint32_t> ids;
  std::vector<uint32_t> id(m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    Key k{m.positions[v].x + 0.0f, m.positions[v].y + 0.0f, m.positions[v].z + 0.0f};  // + 0.0f folds -0
    id[v] = ids.emplace(k, uint32_t(ids.size())).first->second;
  }
  std::map<std::pair<uint32_t, uint32_t>, int> edge_count;
  std::set<uint32_t> used;
  NaiveTopology r;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    uint32_t c[3] = {id[m.indices[3 * t]], id[m.indices[3 * t + 1]], id[m.indices[3 * t + 2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    ++r.faces;
    for (int k = 0; k < 3; ++k) {
      used.insert(c[k]);
      edge_count[{std::min(c[k], c[(k + 1) % 3]), std::max(c[k], c[(k + 1) % 3])}]++;
    }
  }
  r.vertices = used.size();
  r.edges = edge_count.size();
  std::map<uint32_t, std::vector<uint32_t>> graph, boundary_graph;
  for (auto& [e, count] : edge_count) {
    graph[e.first].push_back(e.second);
    graph[e.second].push_back(e.first);
    if (count == 1) {
      ++r.boundary_edges;
      boundary_graph[e.first].push_back(e.second);
      boundary_graph[e.second].push_back(e.first);
    }
  }
  auto count_components = [](const std::map<uint32_t, std::vector<uint32_t>>& g) {
    std::set<uint32_t> seen;
    uint64_t n = 0;
    for (auto& [start, _] : g) {
      if (seen.count(start)) continue;
      ++n;
      std::queue<uint32_t> q;
      q.push(start);
      seen.insert(start);
      while (!q.empty()) {
        uint32_t v = q.front();
        q.pop();
        for (uint32_t w : g.at(v))
          if (seen.insert(w).second) q.push(w);
      }
    }
    return n;
  };
  r.components = count_components(graph);
  r.boundary_components = count_components(boundary_graph);
  for (auto& [v, neighbours] : boundary_graph)
    if (neighbours.size() != 2) r.boundary_vertices_have_degree_two = false;
  return r;
}

TEST(Stats, MatchesNaiveRecomputationOnCorpus) {
  auto files = test::corpus_files();
  if (files.empty()) GTEST_SKIP() << "corpus absent: run scripts/fetch-corpus.sh";
  int checked = 0;
  for (const auto& file : files) {
    if (file.extension() == ".gltf" || file.extension() == ".glb" || file.filename() == "SOURCE") continue;
    Mesh m;
    try {
      m = read_mesh(file);
    } catch (const Error& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    if (m.vertex_count() > 60000) continue;  // keep the ordered-container check quick
    SCOPED_TRACE(file.filename().string());
    MeshStats s = compute_stats(m);
    NaiveTopology n = naive_topology(m);
    EXPECT_EQ(s.unique_positions - s.unreferenced_positions, n.vertices);
    EXPECT_EQ(s.edges, n.edges);
    EXPECT_EQ(s.triangles - s.degenerate_triangles, n.faces);
    EXPECT_EQ(s.boundary_edges, n.boundary_edges);
    EXPECT_EQ(s.connected_components, n.components);
    EXPECT_EQ(s.euler_characteristic, int64_t(n.vertices) - int64_t(n.edges) + int64_t(n.faces));
    // Where the boundary is a set of simple cycles, loops are the boundary graph's components.
    if (n.boundary_vertices_have_degree_two && s.non_manifold_vertices == 0) {
      EXPECT_EQ(s.boundary_loops, n.boundary_components);
    }
    // Per component, V - E + F = 2 - 2g - b for every orientable manifold one.
    for (const ComponentStats& c : s.components)
      if (c.genus >= 0) {
        EXPECT_EQ(c.euler_characteristic, 2 - 2 * c.genus - int64_t(c.boundary_loops));
      }
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(Stats, SharkHasFourHolesAndGenusZero) {
  auto dir = test::corpus_dir();
  if (dir.empty()) GTEST_SKIP() << "corpus absent: run scripts/fetch-corpus.sh";
  Mesh m = read_mesh(dir / "mech-holes-shark.off");
  MeshStats s = compute_stats(m);
  NaiveTopology n = naive_topology(m);
  ASSERT_TRUE(n.boundary_vertices_have_degree_two);
  EXPECT_EQ(s.boundary_loops, n.boundary_components);
  EXPECT_EQ(s.boundary_loops, 4u);
  EXPECT_EQ(s.components.at(0).genus, 0);
}

}  // namespace
}  // namespace lod
