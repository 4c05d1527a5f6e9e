// Reference surface distance with CGAL 5.5's Polygon Mesh Processing, for the simplification bench
// (when `lodkit compare` is not available) and to check `lodkit compare` against (issue 4).
//
//   cgal_distance A B [--samples N] [--seed S] [--no-vertices] [--json]
//
// In each direction (A to B, then B to A) the source surface is sampled the way
// PMP::approximate_Hausdorff_distance samples it: PMP::sample_triangle_soup with random uniform
// sampling, N points on the faces (default 100000, seeded), plus every referenced vertex unless
// --no-vertices. Each sample's closest point on the other surface comes from an AABB tree
// (closest_point with the previous answer as hint over spatially sorted samples, as
// max_distance_to_triangle_mesh does), single-threaded.
//   hausdorff  max over every sample (faces and vertices) of the distance;
//   mean, rms  over the area-uniform face samples only (vertices would over-weight small triangles).
// Symmetric: Hausdorff is the larger direction; mean and RMS are over both surfaces together, each
// direction weighted by its surface's area (as lod::compare defines them). Everything is also
// divided by A's bounding-box diagonal. Zero-area triangles are skipped (they have no surface to sample or hit).
// "seconds" covers sampling, tree building and queries, not loading.
//
// --pmp also times the function the issue names, PMP::approximate_Hausdorff_distance, in both
// directions on a Surface_mesh (Epick, CGAL's usual kernel), with the same number of face samples
// plus every vertex (do_sample_edges(false): the face and vertex scheme above): "pmp_seconds", and
// "pmp_parallel_seconds" with Parallel_tag (TBB, all hardware threads). Only its Hausdorff value
// exists; mean and RMS come from the emulation above.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Polygon_mesh_processing/distance.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/spatial_sort.h>

#include <array>
#include <chrono>
#include <cmath>

#include "harness.h"

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

struct Soup {
  std::vector<Point> points;
  std::vector<std::array<size_t, 3>> faces;  // non-degenerate only
  std::vector<Triangle> triangles;           // the same faces, for the tree
  std::vector<char> referenced;
  double diagonal = 0, area = 0;
};

Soup make_soup(const lod::Mesh& mesh) {
  Soup s;
  s.points.reserve(mesh.vertex_count());
  for (const lod::float3& p : mesh.positions) s.points.emplace_back(p.x, p.y, p.z);
  s.referenced.assign(mesh.vertex_count(), 0);
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::array<size_t, 3> f = {mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]};
    if (CGAL::collinear(s.points[f[0]], s.points[f[1]], s.points[f[2]])) continue;
    s.faces.push_back(f);
    s.triangles.emplace_back(s.points[f[0]], s.points[f[1]], s.points[f[2]]);
    s.area += std::sqrt(s.triangles.back().squared_area());
    for (const size_t v : f) s.referenced[v] = 1;
  }
  lod::float3 lo, hi;
  lod::bounding_box(mesh, lo, hi);
  s.diagonal = std::sqrt(double(hi.x - lo.x) * (hi.x - lo.x) + double(hi.y - lo.y) * (hi.y - lo.y) + double(hi.z - lo.z) * (hi.z - lo.z));
  return s;
}

struct Direction {
  double hausdorff = 0, mean = 0, rms = 0;
  Point worst;
  size_t face_samples = 0, vertex_samples = 0;
};

// Largest squared distance from `points` to the tree; adds distances and squares to the sums.
double max_squared_distance(std::vector<Point>& points, const Tree& tree, double& sum, double& sum_squared, Point& worst) {
  CGAL::spatial_sort(points.begin(), points.end());
  Point hint = tree.closest_point(points.front());
  double largest = 0;
  for (const Point& p : points) {
    hint = tree.closest_point(p, hint);
    const double d2 = CGAL::squared_distance(p, hint);
    sum += std::sqrt(d2), sum_squared += d2;
    if (d2 > largest) largest = d2, worst = p;
  }
  return largest;
}

Direction one_way(const Soup& from, const Soup& to, size_t samples, unsigned seed, bool vertices) {
  std::vector<Point> on_faces;
  PMP::sample_triangle_soup(from.points, from.faces, std::back_inserter(on_faces),
                            CGAL::parameters::number_of_points_on_faces(samples).random_seed(seed).do_sample_vertices(false));
  Tree tree(to.triangles.begin(), to.triangles.end());
  tree.accelerate_distance_queries();
  Direction d;
  d.face_samples = on_faces.size();
  double sum = 0, sum_squared = 0;
  double largest = max_squared_distance(on_faces, tree, sum, sum_squared, d.worst);
  d.mean = sum / double(on_faces.size());
  d.rms = std::sqrt(sum_squared / double(on_faces.size()));
  if (vertices) {
    std::vector<Point> corners;
    for (size_t v = 0; v < from.points.size(); ++v)
      if (from.referenced[v]) corners.push_back(from.points[v]);
    d.vertex_samples = corners.size();
    double unused = 0, unused_squared = 0;
    Point worst;
    const double at_vertices = max_squared_distance(corners, tree, unused, unused_squared, worst);
    if (at_vertices > largest) largest = at_vertices, d.worst = worst;
  }
  d.hausdorff = std::sqrt(largest);
  return d;
}

using PmpPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
using PmpMesh = CGAL::Surface_mesh<PmpPoint>;

// The soup's non-degenerate faces as a Surface_mesh (unreferenced points are left out, so that
// vertex sampling sees the same vertices as the emulation).
PmpMesh make_surface_mesh(const Soup& s) {
  PmpMesh m;
  std::vector<PmpMesh::Vertex_index> index(s.points.size());
  for (size_t v = 0; v < s.points.size(); ++v)
    if (s.referenced[v]) index[v] = m.add_vertex(PmpPoint(s.points[v].x(), s.points[v].y(), s.points[v].z()));
  for (const auto& f : s.faces) {
    // Faces that are not manifold as a Surface_mesh go in as their own triangle (same surface).
    if (m.add_face(index[f[0]], index[f[1]], index[f[2]]) == PmpMesh::null_face()) {
      PmpMesh::Vertex_index c[3];
      for (int k = 0; k < 3; ++k) c[k] = m.add_vertex(m.point(index[f[k]]));
      m.add_face(c[0], c[1], c[2]);
    }
  }
  return m;
}

template <class Tag>
double pmp_symmetric(const PmpMesh& a, const PmpMesh& b, size_t samples, unsigned seed) {
  return std::max(PMP::approximate_Hausdorff_distance<Tag>(
                      a, b, CGAL::parameters::number_of_points_on_faces(samples).random_seed(seed).do_sample_edges(false)),
                  PMP::approximate_Hausdorff_distance<Tag>(
                      b, a, CGAL::parameters::number_of_points_on_faces(samples).random_seed(seed + 1).do_sample_edges(false)));
}

}  // namespace

int main(int argc, char** argv) {
  return bench::run_main("cgal_distance", "cgal_distance A B [--samples N] [--seed S] [--no-vertices] [--json]", [&] {
    std::vector<std::string> a(argv + 1, argv + argc);
    std::vector<std::string> files;
    size_t samples = 100000;
    unsigned seed = 1;
    bool vertices = true, json = false, pmp = false;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == "--samples" && i + 1 < a.size()) samples = std::stoull(a[++i]);
      else if (a[i] == "--seed" && i + 1 < a.size()) seed = unsigned(std::stoul(a[++i]));
      else if (a[i] == "--no-vertices") vertices = false;
      else if (a[i] == "--json") json = true;
      else if (a[i] == "--pmp") pmp = true;
      else if (a[i].rfind("--", 0) == 0) throw std::invalid_argument("unknown option " + a[i]);
      else files.push_back(a[i]);
    }
    if (files.size() != 2 || samples < 1) throw std::invalid_argument("expected two meshes and --samples >= 1");
    const Soup mesh_a = make_soup(bench::load_positions(files[0]));
    const Soup mesh_b = make_soup(bench::load_positions(files[1]));
    if (mesh_a.faces.empty() || mesh_b.faces.empty()) throw std::runtime_error("a mesh has no non-degenerate triangle");
    const auto start = std::chrono::steady_clock::now();
    const Direction ab = one_way(mesh_a, mesh_b, samples, seed, vertices);
    const Direction ba = one_way(mesh_b, mesh_a, samples, seed + 1, vertices);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double diag = mesh_a.diagonal > 0 ? mesh_a.diagonal : 1.0;
    const double hausdorff = std::max(ab.hausdorff, ba.hausdorff);
    const double wa = mesh_a.area / (mesh_a.area + mesh_b.area), wb = 1.0 - wa;
    const double rms = std::sqrt(wa * ab.rms * ab.rms + wb * ba.rms * ba.rms), mean = wa * ab.mean + wb * ba.mean;
    const Point& worst = ab.hausdorff >= ba.hausdorff ? ab.worst : ba.worst;
    nlohmann::json j = {{"tool", "cgal_distance"},
                        {"a", files[0]},
                        {"b", files[1]},
                        {"samples_per_direction", samples},
                        {"vertex_samples", {ab.vertex_samples, ba.vertex_samples}},
                        {"diagonal", mesh_a.diagonal},
                        {"hausdorff", hausdorff},
                        {"rms", rms},
                        {"mean", mean},
                        {"hausdorff_relative", hausdorff / diag},
                        {"rms_relative", rms / diag},
                        {"mean_relative", mean / diag},
                        {"a_to_b", {{"hausdorff", ab.hausdorff}, {"mean", ab.mean}, {"rms", ab.rms}, {"area", mesh_a.area},
                                    {"samples", ab.face_samples + ab.vertex_samples}}},
                        {"b_to_a", {{"hausdorff", ba.hausdorff}, {"mean", ba.mean}, {"rms", ba.rms}, {"area", mesh_b.area},
                                    {"samples", ba.face_samples + ba.vertex_samples}}},
                        {"worst", {worst.x(), worst.y(), worst.z()}},
                        {"seconds", seconds}};
    if (pmp) {
      const PmpMesh pa = make_surface_mesh(mesh_a), pb = make_surface_mesh(mesh_b);
      auto timed = [&](auto tag) {
        const auto t0 = std::chrono::steady_clock::now();
        const double h = pmp_symmetric<decltype(tag)>(pa, pb, samples, seed);
        return std::pair{h, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
      };
      const auto [h, t] = timed(CGAL::Sequential_tag{});
      j["pmp_hausdorff_relative"] = h / diag;
      j["pmp_seconds"] = t;
#if defined(CGAL_LINKED_WITH_TBB)
      const auto [hp, tp] = timed(CGAL::Parallel_tag{});
      j["pmp_parallel_hausdorff_relative"] = hp / diag;
      j["pmp_parallel_seconds"] = tp;
#endif
    }
    if (json) {
      std::printf("%s\n", j.dump().c_str());
    } else {
      std::printf("hausdorff %.6g (%.6g of diag), rms %.6g (%.6g), mean %.6g; A->B %.6g, B->A %.6g; %.3f s\n", hausdorff,
                  hausdorff / diag, rms, rms / diag, mean, ab.hausdorff, ba.hausdorff, seconds);
    }
    return 0;
  });
}
