// lodkit compare A B: Hausdorff, mean and RMS distances between two surfaces, both ways, with an
// optional heat map of where A is far from B.
#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/measure.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct CompareCommand {
  std::string a, b, heatmap;
  uint64_t samples = 0, seed = 1;
  bool refine = false, json = false;
  float tolerance = 1e-4f;
  unsigned threads = 0;
};

nlohmann::json to_json(const float3& p) { return {p.x, p.y, p.z}; }

nlohmann::json to_json(const OneSidedDeviation& r) {
  nlohmann::json j = {{"hausdorff", r.max},
                      {"mean", r.mean},
                      {"rms", r.rms},
                      {"relative_hausdorff", r.relative_max},
                      {"relative_mean", r.relative_mean},
                      {"relative_rms", r.relative_rms},
                      {"max_point", to_json(r.max_location.point)},
                      {"max_closest", to_json(r.max_location.closest)},
                      {"max_triangle", r.max_location.triangle},
                      {"max_closest_triangle", r.max_location.closest_triangle},
                      {"area", r.area},
                      {"samples",
                       {{"area", r.area_samples},
                        {"vertex", r.vertex_samples},
                        {"edge", r.edge_samples},
                        {"refine", r.refine_samples},
                        {"total", r.samples()}}}};
  if (r.refined) {
    j["hausdorff_bound"] = r.max_bound;
    j["relative_hausdorff_bound"] = r.relative_max_bound;
  }
  nlohmann::json at = nlohmann::json::object();
  if (r.attributes.normals)
    at["normal_angle_degrees"] = {{"max", r.attributes.max_normal_angle}, {"mean", r.attributes.mean_normal_angle}};
  if (r.attributes.uvs) at["uv"] = {{"max", r.attributes.max_uv}, {"mean", r.attributes.mean_uv}};
  if (r.attributes.colors) at["color"] = {{"max", r.attributes.max_color}, {"mean", r.attributes.mean_color}};
  j["attributes"] = at;
  return j;
}

void print_attributes(const char* name, const AttributeDeviation& at) {
  if (at.normals)
    fmt::print("{:<12}normal angle max {:.4g} deg, mean {:.4g} deg\n", name, at.max_normal_angle, at.mean_normal_angle);
  if (at.uvs) fmt::print("{:<12}UV distance max {:.4g}, mean {:.4g}\n", name, at.max_uv, at.mean_uv);
  if (at.colors) fmt::print("{:<12}colour distance max {:.4g}, mean {:.4g}\n", name, at.max_color, at.mean_color);
}

}  // namespace

Command register_compare(CLI::App& root) {
  auto o = std::make_shared<CompareCommand>();
  CLI::App* app = root.add_subcommand("compare", "Distance between two surfaces: Hausdorff, mean and RMS (Metro-style)");
  app->add_option("a", o->a, "First mesh (distances are also relative to its bounding-box diagonal)")->required();
  app->add_option("b", o->b, "Second mesh")->required();
  app->add_option("--samples", o->samples,
                  "Area samples on each surface (default: 10 per triangle of the larger mesh, 10k to 2M)");
  app->add_option("--seed", o->seed, "Seed of the random sample positions");
  app->add_flag("--refine", o->refine, "Refine around the worst samples and report an upper bound on Hausdorff");
  app->add_option("--tolerance", o->tolerance, "With --refine: stop when the bound is this close (fraction of the diagonal)");
  app->add_option("--heatmap", o->heatmap, "Write A coloured by its distance to B (.ply, .gltf, .glb, .obj, .off)");
  app->add_option("--threads", o->threads, "Worker threads (0: all); the result does not depend on it");
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o] {
            if (!(o->tolerance >= 0)) throw_usage("--tolerance must be >= 0");
            if (!o->heatmap.empty()) {
              if (format_from_path(o->heatmap) == FileFormat::stl)
                throw_usage(o->heatmap + ": STL has no vertex colours; use .ply, .gltf, .glb, .obj or .off");
              std::error_code ec;
              for (const std::string& input : {o->a, o->b})
                if (std::filesystem::exists(o->heatmap, ec) && std::filesystem::equivalent(input, o->heatmap, ec))
                  throw_usage(o->heatmap + ": refusing to write the heat map over an input file");
              check_output_folder(o->heatmap);
            }
            auto start = std::chrono::steady_clock::now();
            Mesh a, b;
            {
              ProgressBar bar("loading");
              // (A glTF through its scene, flattened as read_mesh does, to check the heat map against
              // the files it reads.)
              const auto load = [&](const std::string& path) {
                const FileFormat format = format_from_path(path);
                if (format != FileFormat::gltf && format != FileFormat::glb) return read_mesh(path, bar.read_options());
                const Scene scene = read_scene(path, bar.read_options());
                if (!o->heatmap.empty()) check_not_source(scene, o->heatmap, false);
                return flatten(scene);
              };
              a = load(o->a);
              b = load(o->b);
            }
            for (const auto& [mesh, name] : {std::pair<const Mesh&, const std::string&>{a, o->a}, {b, o->b}}) {
              validate(mesh, name);
              if (mesh.triangle_count() == 0) throw_bad_input(name, "has no triangles to measure");
            }
            const double load_seconds = seconds_since(start);

            start = std::chrono::steady_clock::now();
            Deviation d;
            {
              ProgressBar bar("comparing");
              d = compare(a, b,
                          {.samples = o->samples,
                           .seed = o->seed,
                           .refine = o->refine,
                           .refine_tolerance = o->tolerance,
                           .threads = o->threads,
                           .progress = [&](double f) { bar.update(f); }});
            }
            const double compare_seconds = seconds_since(start);

            const float scale = float(d.a_to_b.max);
            double write_seconds = 0;
            if (!o->heatmap.empty()) {
              start = std::chrono::steady_clock::now();
              write_mesh(heatmap_mesh(a, d.vertex_error, scale), o->heatmap);
              write_seconds = seconds_since(start);
            }
            const double queries_per_second = d.query_seconds > 0 ? double(d.queries) / d.query_seconds : 0;

            if (o->json) {
              nlohmann::json j = {
                  {"a", o->a},
                  {"b", o->b},
                  {"a_triangles", a.triangle_count()},
                  {"b_triangles", b.triangle_count()},
                  {"a_vertices", a.vertex_count()},
                  {"b_vertices", b.vertex_count()},
                  {"diagonal", d.diagonal},
                  {"seed", o->seed},
                  {"a_to_b", to_json(d.a_to_b)},
                  {"b_to_a", to_json(d.b_to_a)},
                  {"symmetric",
                   {{"hausdorff", d.hausdorff},
                    {"mean", d.mean},
                    {"rms", d.rms},
                    {"relative_hausdorff", d.relative_hausdorff},
                    {"relative_mean", d.relative_mean},
                    {"relative_rms", d.relative_rms}}},
                  {"queries", d.queries},
                  {"queries_per_second", queries_per_second},
                  {"load_seconds", load_seconds},
                  {"build_seconds", d.build_seconds},
                  {"query_seconds", d.query_seconds},
                  {"compare_seconds", compare_seconds}};
              if (o->refine) {
                j["symmetric"]["hausdorff_bound"] = d.hausdorff_bound;
                j["symmetric"]["relative_hausdorff_bound"] = d.relative_hausdorff_bound;
              }
              if (!o->heatmap.empty())
                j["heatmap"] = {{"path", o->heatmap},
                                {"field", "largest distance to b in each vertex's region of a"},
                                {"scale", scale},
                                {"relative_scale", d.diagonal > 0 ? scale / d.diagonal : 0.0},
                                {"ramp", heat_ramp_names},
                                {"write_seconds", write_seconds}};
              fmt::print("{}\n", j.dump(2));
              return 0;
            }
            fmt::print("a: {} ({} triangles), b: {} ({} triangles), diagonal of a {:.6g}\n", o->a, a.triangle_count(),
                       o->b, b.triangle_count(), d.diagonal);
            fmt::print("{:<12}{:>14}{:>14}{:>14}{:>12}{:>12}{:>12}{:>12}\n", "", "Hausdorff", "mean", "RMS", "Hausdorff%",
                       "mean%", "RMS%", "samples");
            auto row = [](const char* name, double h, double mean, double rms, double diagonal, uint64_t samples) {
              const double s = diagonal > 0 ? 100.0 / diagonal : 0.0;
              fmt::print("{:<12}{:>14.6g}{:>14.6g}{:>14.6g}{:>11.4f}%{:>11.4f}%{:>11.4f}%{:>12}\n", name, h, mean, rms, h * s,
                         mean * s, rms * s, samples);
            };
            row("a -> b", d.a_to_b.max, d.a_to_b.mean, d.a_to_b.rms, d.diagonal, d.a_to_b.samples());
            row("b -> a", d.b_to_a.max, d.b_to_a.mean, d.b_to_a.rms, d.diagonal, d.b_to_a.samples());
            row("symmetric", d.hausdorff, d.mean, d.rms, d.diagonal, d.a_to_b.samples() + d.b_to_a.samples());
            if (o->refine)
              fmt::print("{:<12}Hausdorff <= {:.6g} ({:.4f}%); a -> b <= {:.6g}, b -> a <= {:.6g}\n", "bound",
                         d.hausdorff_bound, 100.0 * d.relative_hausdorff_bound, d.a_to_b.max_bound, d.b_to_a.max_bound);
            const OneSidedDeviation& worst = d.a_to_b.max >= d.b_to_a.max ? d.a_to_b : d.b_to_a;
            const MaxLocation& at = worst.max_location;
            fmt::print("{:<12}({:.6g}, {:.6g}, {:.6g}) on {} -> ({:.6g}, {:.6g}, {:.6g}) on {}\n", "max at", at.point.x,
                       at.point.y, at.point.z, &worst == &d.a_to_b ? "a" : "b", at.closest.x, at.closest.y,
                       at.closest.z, &worst == &d.a_to_b ? "b" : "a");
            print_attributes("a -> b", d.a_to_b.attributes);
            print_attributes("b -> a", d.b_to_a.attributes);
            if (!o->heatmap.empty())
              fmt::print("{:<12}{} (blue 0 -> red {:.6g} = {:.4f}% of the diagonal)\n", "heat map", o->heatmap, scale,
                         d.diagonal > 0 ? 100.0 * scale / d.diagonal : 0.0);
            fmt::print("{:<12}load {:.3f}s, BVH {:.3f}s, {} queries in {:.3f}s ({:.3g}/s)\n", "time", load_seconds,
                       d.build_seconds, d.queries, d.query_seconds, queries_per_second);
            return 0;
          }};
}

}  // namespace lod::cli
