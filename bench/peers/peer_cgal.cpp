// CGAL 5.5 (Debian libcgal-dev): Surface_mesh_simplification::edge_collapse on a Surface_mesh with
// double coordinates, stopped at the target face count.
//
//   peer_cgal gh|lt IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S]
//
//   gh  GarlandHeckbert_plane_policies (classic plane quadrics, optimal placement)
//   lt  LindstromTurk_cost + LindstromTurk_placement (memoryless, volume and boundary preserving)
//
// Both with CGAL's defaults otherwise (no normal-change filter or envelope). The Surface_mesh is built
// from the welded input before every run, untimed; the timed part is the policy's construction and
// edge_collapse. A triangle the halfedge structure refuses (non-manifold) is dropped and counted in
// "faces_dropped"; distances are still measured against the full input.
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <memory>

#include "harness.h"

namespace {

namespace SMS = CGAL::Surface_mesh_simplification;
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

// CGAL 5.5 has only an edge-count predicate; this one stops at the face count, like the other tools.
// Surface_mesh::number_of_faces() is O(1) and drops as edge_collapse removes faces.
struct FaceCountStop {
  const SurfaceMesh* mesh;
  size_t target;
  template <class Cost, class Profile>
  bool operator()(const Cost&, const Profile&, std::size_t, std::size_t) const {
    return mesh->number_of_faces() <= target;
  }
};

}  // namespace

int main(int argc, char** argv) {
  return bench::run_main("peer_cgal", "peer_cgal gh|lt IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S]", [&] {
    const bench::Args args = bench::parse_args(argc, argv, {"gh", "lt"});
    const lod::Mesh input = bench::load_positions(args.input);
    const bench::Welded welded = bench::weld(input);
    size_t dropped = 0;
    auto build = [&] {
      auto mesh = std::make_unique<SurfaceMesh>();
      mesh->reserve(welded.positions.size(), welded.indices.size() / 2 * 3, welded.indices.size() / 3);
      for (const lod::float3& p : welded.positions) mesh->add_vertex(Point(p.x, p.y, p.z));
      dropped = 0;
      for (size_t t = 0; t < welded.indices.size(); t += 3) {
        const auto f = mesh->add_face(SurfaceMesh::Vertex_index(welded.indices[t]), SurfaceMesh::Vertex_index(welded.indices[t + 1]),
                                      SurfaceMesh::Vertex_index(welded.indices[t + 2]));
        if (f == SurfaceMesh::null_face()) ++dropped;
      }
      return mesh;
    };
    const double rss = [&] { build(); return bench::peak_rss_mib(); }();
    std::vector<double> seconds;
    int collapses = 0;
    const auto mesh = bench::timed_runs(args, seconds, build, [&](std::unique_ptr<SurfaceMesh>& m) {
      const FaceCountStop stop{m.get(), size_t(args.target_triangles)};
      if (args.mode == "gh") {
        SMS::GarlandHeckbert_plane_policies<SurfaceMesh, Kernel> policies(*m);
        collapses = SMS::edge_collapse(*m, stop, CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
      } else {
        collapses = SMS::edge_collapse(*m, stop, CGAL::parameters::get_cost(SMS::LindstromTurk_cost<SurfaceMesh>())
                                                      .get_placement(SMS::LindstromTurk_placement<SurfaceMesh>()));
      }
    });
    // Untimed: the surviving faces over all vertex slots (removed ones are then not referenced).
    std::vector<lod::float3> positions(mesh->num_vertices());
    for (const auto v : mesh->vertices()) {
      const Point& p = mesh->point(v);
      positions[v.idx()] = {float(p.x()), float(p.y()), float(p.z())};
    }
    std::vector<uint32_t> indices;
    indices.reserve(mesh->number_of_faces() * 3);
    for (const auto f : mesh->faces())
      for (const auto v : mesh->vertices_around_face(mesh->halfedge(f))) indices.push_back(uint32_t(v.idx()));
    const lod::Mesh result = bench::compact(positions, indices);
    bench::finish("cgal", args, input, result, seconds, rss, {{"faces_dropped", dropped}, {"collapses", collapses}});
    return 0;
  });
}
