// scripts/bench.sh morphs: how well a simplification carries a morph target (a glTF blend shape)
// when its vertices move, and what that costs.
//
// Each corpus mesh gets a smooth morph field: offsets of 2% of the bounding-box diagonal, a few
// waves across it. It is simplified to 10% and 1% of its triangles (the default options), and the
// result's offsets are made two ways: interpolated on the input by lod::vertex_blends (what lodkit
// simplify writes), and, for comparison, each vertex's survivor's own offset (vertex_origin: what a
// subset simplifier such as meshoptimizer keeps). The morphed result is measured against the morphed
// input with lod::compare (symmetric Hausdorff and RMS over the diagonal), next to the rest pose's
// distances. Also the time of vertex_blends against the simplify call (medians of RUNS). Prints a
// markdown table.
//
// A second table takes the first FORM_MESHES meshes through the forms lodkit simplify changes and
// gives back (lod::surface_form, lod::restore_form): flat-shaded (a soup whose corners carry their
// face's normal) and double-sided (each triangle twice, the back on copies with negated smooth
// normals). The same field, the same measures, next to the plain mesh's interpolated distances: the
// forms should carry a blend shape as well as the plain mesh does.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/vec3d.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "lodkit/simplify.h"
#include "median.h"

using namespace lod;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// The morph field: waves of a few periods across the bounding box, amplitude 2% of its diagonal.
struct Field {
  float3 lo;
  float diagonal = 1;
  float3 operator()(const float3& p) const {
    const float x = (p.x - lo.x) / diagonal, y = (p.y - lo.y) / diagonal, z = (p.z - lo.z) / diagonal, a = 0.02f * diagonal;
    return {a * std::sin(12 * y), a * std::cos(10 * z), a * std::sin(11 * x + 4 * y)};
  }
};

Mesh displaced(Mesh m, const std::vector<float3>& offsets) {
  for (size_t v = 0; v < m.vertex_count(); ++v)
    m.positions[v] = {m.positions[v].x + offsets[v].x, m.positions[v].y + offsets[v].y, m.positions[v].z + offsets[v].z};
  return m;
}

// Offsets at blends of the input's vertices.
std::vector<float3> interpolated(const std::vector<float3>& offsets, const std::vector<VertexBlend>& blends) {
  std::vector<float3> out(blends.size());
  for (size_t v = 0; v < blends.size(); ++v)
    for (int k = 0; k < 3; ++k) {
      const float3& o = offsets[blends[v].vertex[k]];
      const float w = blends[v].weight[k];
      out[v] = {out[v].x + w * o.x, out[v].y + w * o.y, out[v].z + w * o.z};
    }
  return out;
}

// A soup whose corners carry their triangle's normal.
Mesh flat_shaded(const Mesh& mesh) {
  Mesh flat;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float3 unit = core::unit_float3(core::triangle_cross(mesh, t), {0, 0, 1});
    for (int k = 0; k < 3; ++k) {
      flat.indices.push_back(uint32_t(flat.positions.size()));
      flat.positions.push_back(mesh.positions[mesh.indices[3 * t + k]]);
      flat.normals.push_back(unit);
    }
  }
  return flat;
}

// Each triangle and its reversed twin; fronts with smooth normals, backs on copies with them negated.
Mesh double_sided(const Mesh& mesh) {
  Mesh two = mesh;
  two.normals = smooth_normals(mesh);
  const uint32_t n = uint32_t(mesh.vertex_count());
  for (uint32_t v = 0; v < n; ++v) {
    two.positions.push_back(mesh.positions[v]);
    two.normals.push_back({-two.normals[v].x, -two.normals[v].y, -two.normals[v].z});
  }
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    two.indices.insert(two.indices.end(), {n + mesh.indices[3 * t], n + mesh.indices[3 * t + 2], n + mesh.indices[3 * t + 1]});
  return two;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: lodkit_bench_morph_transfer RUNS MESH...\n");
    return 2;
  }
  const int runs = std::max(1, std::atoi(argv[1]));
  std::printf("| mesh | ratio | rest H | rest RMS | interpolated H | interpolated RMS | survivor's H | survivor's RMS | simplify (s) | vertex_blends (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  int interpolated_rms_better = 0, interpolated_h_better = 0, cases = 0;
  const int form_meshes = std::min(argc - 2, 4);
  std::vector<Deviation> plain_blends;  // per mesh and ratio, in order
  for (int a = 2; a < argc; ++a) {
    const Mesh input = read_mesh(argv[a]);
    Field field;
    float3 hi;
    bounding_box(input, field.lo, hi);
    field.diagonal = std::hypot(hi.x - field.lo.x, hi.y - field.lo.y, hi.z - field.lo.z);
    std::vector<float3> offsets;
    for (const float3& p : input.positions) offsets.push_back(field(p));
    const Mesh morphed_input = displaced(input, offsets);
    for (const float ratio : {0.1f, 0.01f}) {
      std::vector<double> simplify_times, blend_times;
      SimplifyResult r;
      std::vector<VertexBlend> blends;
      for (int run = 0; run < runs; ++run) {
        double t = now();
        r = simplify(input, {.target_ratio = ratio, .record = false});
        simplify_times.push_back(now() - t);
        t = now();
        blends = vertex_blends(input, r.vertex_successor, r.mesh);
        blend_times.push_back(now() - t);
      }
      std::vector<float3> own(r.mesh.vertex_count());
      for (size_t v = 0; v < r.mesh.vertex_count(); ++v) own[v] = offsets[r.vertex_origin[v]];
      const Deviation rest = compare(input, r.mesh);
      const Deviation with_blends = compare(morphed_input, displaced(r.mesh, interpolated(offsets, blends)));
      plain_blends.push_back(with_blends);
      const Deviation with_own = compare(morphed_input, displaced(r.mesh, own));
      const double d = field.diagonal;
      std::string name = argv[a];
      name = name.substr(name.find_last_of('/') + 1);
      std::printf("| %s | %g%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.3f | %.4f |\n", name.c_str(), 100.0 * ratio,
                  100 * rest.hausdorff / d, 100 * rest.rms / d, 100 * with_blends.hausdorff / d, 100 * with_blends.rms / d,
                  100 * with_own.hausdorff / d, 100 * with_own.rms / d, bench::median(simplify_times), bench::median(blend_times));
      ++cases;
      interpolated_rms_better += with_blends.rms < with_own.rms;
      interpolated_h_better += with_blends.hausdorff < with_own.hausdorff;
    }
  }
  std::printf("\ninterpolated offsets nearer the morphed input than the survivors' own: RMS in %d of %d cases, Hausdorff in %d of %d\n",
              interpolated_rms_better, cases, interpolated_h_better, cases);

  std::printf("\n| mesh | form | ratio | rest H | rest RMS | interpolated H | interpolated RMS | plain's interpolated H | plain's interpolated RMS | forms (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  double worst_h = 0, worst_rms = 0;  // interpolated through a form over the plain mesh's
  for (int a = 2; a < 2 + form_meshes; ++a) {
    const Mesh plain = read_mesh(argv[a]);
    Field field;
    float3 hi;
    bounding_box(plain, field.lo, hi);
    field.diagonal = std::hypot(hi.x - field.lo.x, hi.y - field.lo.y, hi.z - field.lo.z);
    for (const bool flat : {true, false}) {
      const Mesh input = flat ? flat_shaded(plain) : double_sided(plain);
      std::vector<float3> offsets;
      for (const float3& p : input.positions) offsets.push_back(field(p));
      const Mesh morphed_input = displaced(input, offsets);
      for (size_t k = 0; k < 2; ++k) {
        const float ratio = k == 0 ? 0.1f : 0.01f;
        std::vector<double> form_times;
        SimplifyResult r;
        for (int run = 0; run < runs; ++run) {
          double t = now();
          const SurfaceForm form = surface_form(input);
          double form_seconds = now() - t;
          r = simplify(form.to_simplify(input), {.target_ratio = ratio, .record = false});
          t = now();
          restore_form(form, r.mesh, r.vertex_successor);
          form_times.push_back(form_seconds + now() - t);
        }
        const std::vector<VertexBlend> blends = vertex_blends(input, r.vertex_successor, r.mesh);
        const Deviation rest = compare(input, r.mesh);
        const Deviation with_blends = compare(morphed_input, displaced(r.mesh, interpolated(offsets, blends)));
        const Deviation& base = plain_blends[size_t(a - 2) * 2 + k];
        const double d = field.diagonal;
        worst_h = std::max(worst_h, with_blends.hausdorff / base.hausdorff);
        worst_rms = std::max(worst_rms, with_blends.rms / base.rms);
        std::string name = argv[a];
        name = name.substr(name.find_last_of('/') + 1);
        std::printf("| %s | %s | %g%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f%% | %.4f |\n", name.c_str(),
                    flat ? "flat-shaded" : "double-sided", 100.0 * ratio, 100 * rest.hausdorff / d, 100 * rest.rms / d,
                    100 * with_blends.hausdorff / d, 100 * with_blends.rms / d, 100 * base.hausdorff / d, 100 * base.rms / d,
                    bench::median(form_times));
      }
    }
  }
  std::printf("\nthrough the forms, interpolated distances at most %.2fx (Hausdorff) and %.2fx (RMS) the plain mesh's\n", worst_h, worst_rms);
  return 0;
}
