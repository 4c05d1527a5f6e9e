// OpenMesh 9 (Debian libopenmesh-dev): DecimaterT with ModQuadricT as the priority module (no error
// limit), decimate_to_faces to the target.
//
//   peer_openmesh IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S]
//
// The TriMesh (float coordinates, OpenMesh's default) is built from the welded input before every
// run, untimed. The timed part is the decimater's construction (it requests the status attributes),
// initialize() (the quadrics) and decimate_to_faces; garbage collection and output are not.
// A triangle the halfedge structure refuses (non-manifold) is dropped and counted in "faces_dropped".
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <memory>

#include "harness.h"

namespace {
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;
using Decimater = OpenMesh::Decimater::DecimaterT<TriMesh>;
using ModQuadric = OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle;
}  // namespace

int main(int argc, char** argv) {
  return bench::run_main("peer_openmesh", "peer_openmesh IN OUT TARGET_TRIANGLES RUNS [--json] [--budget S]", [&] {
    const bench::Args args = bench::parse_args(argc, argv, {});
    const lod::Mesh input = bench::load_positions(args.input);
    const bench::Welded welded = bench::weld(input);
    omerr().disable();  // add_face reports each refused (complex) face; they are counted instead
    size_t dropped = 0;
    auto build = [&] {
      auto mesh = std::make_unique<TriMesh>();
      // The decimater requests the status flags and releases them when it goes; holding them here keeps
      // the "deleted" marks until garbage_collection() (without them, deleted faces would be output).
      mesh->request_vertex_status();
      mesh->request_edge_status();
      mesh->request_face_status();
      mesh->reserve(welded.positions.size(), welded.indices.size() / 2, welded.indices.size() / 3);
      std::vector<TriMesh::VertexHandle> handles;
      handles.reserve(welded.positions.size());
      for (const lod::float3& p : welded.positions) handles.push_back(mesh->add_vertex(TriMesh::Point(p.x, p.y, p.z)));
      dropped = 0;
      for (size_t t = 0; t < welded.indices.size(); t += 3) {
        const auto f = mesh->add_face(handles[welded.indices[t]], handles[welded.indices[t + 1]], handles[welded.indices[t + 2]]);
        if (!f.is_valid()) ++dropped;
      }
      return mesh;
    };
    const double rss = [&] { build(); return bench::peak_rss_mib(); }();
    std::vector<double> seconds;
    size_t removed = 0;
    const auto mesh = bench::timed_runs(args, seconds, build, [&](std::unique_ptr<TriMesh>& m) {
      Decimater decimater(*m);
      ModQuadric quadric;
      decimater.add(quadric);
      decimater.module(quadric).unset_max_err();
      decimater.initialize();
      removed = decimater.decimate_to_faces(0, size_t(args.target_triangles));
    });
    mesh->garbage_collection();
    std::vector<lod::float3> positions;
    positions.reserve(mesh->n_vertices());
    for (const auto v : mesh->vertices()) {
      const TriMesh::Point& p = mesh->point(v);
      positions.push_back({p[0], p[1], p[2]});
    }
    std::vector<uint32_t> indices;
    indices.reserve(mesh->n_faces() * 3);
    for (const auto f : mesh->faces())
      for (const auto v : mesh->fv_range(f)) indices.push_back(uint32_t(v.idx()));
    const lod::Mesh result = bench::compact(positions, indices);
    bench::finish("openmesh", args, input, result, seconds, rss, {{"faces_dropped", dropped}, {"collapses", removed}});
    return 0;
  });
}
