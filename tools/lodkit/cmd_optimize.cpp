// lodkit optimize IN -o OUT: consolidate a mesh for the GPU. Optionally weld duplicate vertices and
// repair the winding; always order triangles for the vertex cache (or as strips), optionally then for
// overdraw, and vertices by first use. A glTF written from a glTF keeps everything else; each primitive is optimized on its own.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/optimize.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct OptimizeCommand {
  std::string input, output, strips, strip_indices;
  std::string weld_word, overdraw_word;  // as given; read by optional_number
  float weld = -1;  // -1: no weld; 0: exact; > 0: tolerance (object space)
  double overdraw = -1;  // -1: no overdraw pass; else its threshold (misses relative to the cache order)
  float attribute_tolerance = 0;
  bool weld_positions = false, orient = false, lru = false, restart = false, no_fetch = false, json = false, force = false;
  WriteOptions gltf;  // -c, -q
  uint32_t cache = 16;
};

// Little-endian uint32, as a GPU index buffer.
void write_indices(const std::string& path, const std::vector<uint32_t>& indices) {
  std::string bytes(indices.size() * 4, '\0');
  for (size_t k = 0; k < indices.size(); ++k)
    for (int b = 0; b < 4; ++b) bytes[4 * k + size_t(b)] = char((indices[k] >> (8 * b)) & 0xFF);
  write_file_atomic(path, bytes);
}

}  // namespace

Command register_optimize(CLI::App& root) {
  auto o = std::make_shared<OptimizeCommand>();
  CLI::App* app = root.add_subcommand(
      "optimize", "Consolidate for the GPU: weld, orient, vertex-cache order or strips, vertex-fetch order");
  // Not required() here: `--weld IN` hands IN back to it after the parse (optional_number).
  app->add_option("input", o->input, "Input mesh file (required)");
  app->add_option("-o,--output", o->output, "Output mesh file; the format follows the extension")->required();
  app->add_option("--weld", o->weld_word,
                  "Weld duplicate vertices: bitwise equal, or with --weld=EPS positions closer than EPS (object space)")
      ->expected(0, 1)
      ->type_name("[=EPS]");
  app->add_flag("--weld-positions", o->weld_positions, "Weld by position alone (drops UV seams and hard normals)");
  app->add_option("--attribute-tolerance", o->attribute_tolerance,
                  "With --weld: normals, UVs, colours, tangents and weights may differ by this much per component");
  app->add_flag("--orient", o->orient, "Make the winding consistent per part, closed parts facing outward");
  app->add_option("--strips", o->strips, "Also build triangle strips: sgi (the course's baseline) or best");
  app->add_flag("--restart", o->restart, "Join strips with a restart index (0xFFFFFFFF) instead of degenerate triangles");
  app->add_option("--strip-indices", o->strip_indices, "With --strips: write the strip index buffer here (little-endian uint32)");
  app->add_option("--overdraw", o->overdraw_word,
                  "After the cache order, order for overdraw: --overdraw=T allows T times the cache order's FIFO misses "
                  "(default 1.05)")
      ->expected(0, 1)
      ->type_name("[=T]");
  app->add_option("--cache", o->cache, "Vertex cache entries to optimize for (default 16)");
  app->add_flag("--lru", o->lru, "Optimize for an LRU cache (default FIFO)");
  app->add_flag("--no-fetch", o->no_fetch, "Keep the vertex order (no renumbering by first use)");
  app->add_flag("--force", o->force, "Allow writing over the input file");
  add_gltf_output_flags(app, o->gltf);
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o, app] {
            const bool weld_given = app->count("--weld") > 0;
            const bool overdraw = app->count("--overdraw") > 0;
            if (weld_given) o->weld = float(optional_number("--weld", o->weld_word, 0.0, o->input));
            if (overdraw) o->overdraw = optional_number("--overdraw", o->overdraw_word, 1.05, o->input);
            if (o->input.empty()) throw_usage("input is required");
            if (weld_given && !(o->weld >= 0)) throw_usage("--weld=EPS needs EPS >= 0");
            if (overdraw && !(o->overdraw >= 1)) throw_usage("--overdraw=T needs T >= 1");
            if (overdraw && !o->strips.empty()) throw_usage("--overdraw and --strips exclude each other (both set the triangle order)");
            if (o->strips != "" && o->strips != "sgi" && o->strips != "best")
              throw_usage("--strips must be sgi or best (got '" + o->strips + "')");
            if (!o->strip_indices.empty() && o->strips.empty()) throw_usage("--strip-indices needs --strips");
            if (o->cache < 3 || o->cache > 64) throw_usage("--cache must be in [3, 64]");
            if (!(o->attribute_tolerance >= 0)) throw_usage("--attribute-tolerance must be >= 0");
            if ((o->weld_positions || o->attribute_tolerance > 0) && o->weld < 0) o->weld = 0;
            check_output(o->input, o->output, o->force);
            if (!o->strip_indices.empty()) check_output(o->input, o->strip_indices, o->force);
            check_gltf_output_flags(o->gltf, o->output);
            const float t = o->attribute_tolerance;
            OptimizeOptions options{
                .weld = o->weld >= 0,
                .weld_options = {.position_tolerance = std::max(0.0f, o->weld), .normal_tolerance = t, .tangent_tolerance = t,
                                 .uv_tolerance = t, .color_tolerance = t, .weight_tolerance = t,
                                 .ignore_attributes = o->weld_positions, .remove_degenerate = o->weld > 0},
                .orient = o->orient,
                .cache = {.cache_size = o->cache,
                          .policy = o->lru ? CachePolicy::lru : CachePolicy::fifo,
                          .index_codec = o->gltf.meshopt_compression},
                .strips = !o->strips.empty(),
                .strip_options = {.method = o->strips == "sgi" ? StripMethod::sgi : StripMethod::best, .use_restart = o->restart},
                .overdraw = overdraw,
                .overdraw_threshold = overdraw ? float(o->overdraw) : 1.05f,
                .vertex_fetch = !o->no_fetch,
            };
            // Overdraw (shaded / covered pixels, lod::analyze_overdraw's 14 views), summed over primitives.
            OverdrawStats overdraw_before, overdraw_after;
            auto add_overdraw = [](OverdrawStats& total, const Mesh& m) {
              const OverdrawStats s = analyze_overdraw(m.indices, m.positions);
              total.pixels_covered += s.pixels_covered, total.pixels_shaded += s.pixels_shaded;
              total.overdraw = total.pixels_covered ? double(total.pixels_shaded) / double(total.pixels_covered) : 0;
            };

            auto start = std::chrono::steady_clock::now();
            GeometryFile file(o->input, o->output, o->force);
            if (!o->strip_indices.empty()) file.check_not_source(o->strip_indices, o->force);
            std::vector<Mesh*>& meshes = file.meshes;
            require_triangles(meshes, o->input, "nothing to optimize; lodkit works on triangle meshes");
            const double load_seconds = seconds_since(start);
            if (!o->strip_indices.empty() && meshes.size() != 1)
              throw_usage("--strip-indices needs a single mesh (the input has " + std::to_string(meshes.size()) + " primitives)");

            // Totals over the primitives.
            uint64_t in_triangles = 0, in_vertices = 0, out_triangles = 0, out_vertices = 0, welded_vertices = 0;
            uint64_t degenerate = 0, flipped = 0, parts = 0, closed = 0, outward = 0, non_orientable = 0, non_manifold = 0;
            VertexCacheStats before, after;
            StripStats strip_stats;
            double seconds[5] = {};
            std::vector<uint32_t> strip_buffer;
            for (size_t i = 0; i < meshes.size(); ++i) {
              Mesh* m = meshes[i];
              validate(*m, o->input);
              in_triangles += m->triangle_count(), in_vertices += m->vertex_count();
              if (overdraw) add_overdraw(overdraw_before, *m);
              // Vertices whose morph targets (or other glTF streams) differ stay apart.
              const std::vector<uint32_t> classes = options.weld ? file.vertex_classes(i) : std::vector<uint32_t>{};
              OptimizeOptions each = options;
              each.weld_options.vertex_classes = classes;
              OptimizeResult r = optimize(*m, each);
              welded_vertices += options.weld ? r.weld.output_vertices : m->vertex_count();
              degenerate += r.weld.degenerate_triangles;
              flipped += r.orient.flipped_triangles, parts += r.orient.components, closed += r.orient.closed_components;
              outward += r.orient.turned_outward, non_orientable += r.orient.non_orientable_components;
              non_manifold += r.orient.non_manifold_edges;
              before.triangles += r.cache_before.triangles, before.misses += r.cache_before.misses;
              before.referenced_vertices += r.cache_before.referenced_vertices;
              after.triangles += r.cache_after.triangles, after.misses += r.cache_after.misses;
              after.referenced_vertices += r.cache_after.referenced_vertices;
              if (options.strips) {
                const StripStats s = analyze_strips(r.strips.indices, r.strips.use_restart, r.strips.restart_index);
                strip_stats.indices += s.indices, strip_stats.strips += s.strips, strip_stats.triangles += s.triangles;
                strip_stats.degenerate_triangles += s.degenerate_triangles;
                strip_buffer = std::move(r.strips.indices);
              }
              seconds[0] += r.weld_seconds, seconds[1] += r.orient_seconds, seconds[2] += r.order_seconds - r.overdraw_seconds;
              seconds[3] += r.fetch_seconds, seconds[4] += r.overdraw_seconds;
              *m = std::move(r.mesh);
              file.renumbered(i, r.source_vertices);
              if (overdraw) add_overdraw(overdraw_after, *m);
              out_triangles += m->triangle_count(), out_vertices += m->vertex_count();
            }
            for (VertexCacheStats* s : {&before, &after}) {
              s->acmr = s->triangles ? double(s->misses) / double(s->triangles) : 0;
              s->atvr = s->referenced_vertices ? double(s->misses) / double(s->referenced_vertices) : 0;
            }
            strip_stats.indices_per_triangle = strip_stats.triangles ? double(strip_stats.indices) / double(strip_stats.triangles) : 0;
            if (non_orientable)
              std::fprintf(stderr,
                           "lodkit: warning: %llu non-orientable part(s) (Moebius-like): their winding cannot be made "
                           "consistent\n",
                           static_cast<unsigned long long>(non_orientable));

            start = std::chrono::steady_clock::now();
            const WriteReport written = file.write(o->output, o->gltf);
            if (!o->strip_indices.empty()) write_indices(o->strip_indices, strip_buffer);
            const double write_seconds = seconds_since(start);

            const std::string cache_name = fmt::format("{} {}", o->lru ? "LRU" : "FIFO", o->cache);
            if (o->json) {
              nlohmann::json j = {{"input", o->input}, {"output", o->output},
                                  {"input_triangles", in_triangles}, {"output_triangles", out_triangles},
                                  {"input_vertices", in_vertices}, {"output_vertices", out_vertices},
                                  {"cache", {{"size", o->cache}, {"policy", o->lru ? "lru" : "fifo"}}},
                                  {"acmr_before", before.acmr}, {"acmr_after", after.acmr},
                                  {"atvr_before", before.atvr}, {"atvr_after", after.atvr},
                                  {"load_seconds", load_seconds}, {"write_seconds", write_seconds},
                                  {"order_seconds", seconds[2]}, {"fetch_seconds", seconds[3]}};
              if (overdraw)
                j["overdraw"] = {{"threshold", o->overdraw}, {"before", overdraw_before.overdraw}, {"after", overdraw_after.overdraw},
                                 {"seconds", seconds[4]}};
              if (options.weld)
                j["weld"] = {{"tolerance", options.weld_options.position_tolerance}, {"positions_only", o->weld_positions},
                             {"vertices", welded_vertices}, {"degenerate_triangles", degenerate}, {"seconds", seconds[0]}};
              if (options.orient)
                j["orient"] = {{"flipped_triangles", flipped}, {"components", parts}, {"closed_components", closed},
                               {"turned_outward", outward}, {"non_orientable_components", non_orientable},
                               {"non_manifold_edges", non_manifold}, {"seconds", seconds[1]}};
              if (options.strips)
                j["strips"] = {{"method", o->strips}, {"restart", o->restart}, {"indices", strip_stats.indices},
                               {"strips", strip_stats.strips}, {"triangles", strip_stats.triangles},
                               {"indices_per_triangle", strip_stats.indices_per_triangle}};
              add_write_report(j, written, o->gltf);
              fmt::print("{}\n", j.dump(2));
            } else {
              fmt::print("{:<10}{:>12}{:>12}{:>10}{:>10}  {}\n", "step", "triangles", "vertices", "ACMR", "time", "");
              fmt::print("{:<10}{:>12}{:>12}{:>10.3f}{:>9.3f}s  {} ({})\n", "read", in_triangles, in_vertices, before.acmr,
                         load_seconds, o->input, cache_name);
              if (options.weld)
                fmt::print("{:<10}{:>12}{:>12}{:>10}{:>9.3f}s  {}{}\n", "weld", in_triangles - (o->weld > 0 ? degenerate : 0),
                           welded_vertices, "", seconds[0],
                           o->weld > 0 ? fmt::format("within {:g}", o->weld) : std::string("exact"),
                           degenerate ? fmt::format(", {} degenerate triangle(s){}", degenerate, o->weld > 0 ? " removed" : "") : "");
              if (options.orient)
                fmt::print("{:<10}{:>12}{:>12}{:>10}{:>9.3f}s  {} flipped, {} part(s), {} closed, {} turned outward{}\n", "orient",
                           out_triangles, welded_vertices, "", seconds[1], flipped, parts, closed, outward,
                           non_orientable ? fmt::format(", {} NON-ORIENTABLE", non_orientable) : "");
              if (options.strips)
                fmt::print("{:<10}{:>12}{:>12}{:>10.3f}{:>9.3f}s  {} strips, {} indices, {:.3f} per triangle ({})\n",
                           "strips", out_triangles, welded_vertices, after.acmr, seconds[2], strip_stats.strips,
                           strip_stats.indices, strip_stats.indices_per_triangle,
                           fmt::format("{}, {}", o->strips, o->restart ? "restart index" : "degenerate joins"));
              else if (overdraw)
                fmt::print("{:<10}{:>12}{:>12}{:>10}{:>9.3f}s  {}\n", "cache", out_triangles, welded_vertices, "", seconds[2],
                           "(ACMR after the overdraw order below)");
              else
                fmt::print("{:<10}{:>12}{:>12}{:>10.3f}{:>9.3f}s  ATVR {:.3f} -> {:.3f}\n", "cache", out_triangles,
                           welded_vertices, after.acmr, seconds[2], before.atvr, after.atvr);
              if (overdraw)
                fmt::print("{:<10}{:>12}{:>12}{:>10.3f}{:>9.3f}s  overdraw {:.3f} -> {:.3f} (threshold {:g}), ATVR {:.3f} -> {:.3f}\n",
                           "overdraw", out_triangles, welded_vertices, after.acmr, seconds[4], overdraw_before.overdraw,
                           overdraw_after.overdraw, o->overdraw, before.atvr, after.atvr);
              if (options.vertex_fetch)
                fmt::print("{:<10}{:>12}{:>12}{:>10.3f}{:>9.3f}s  vertices by first use\n", "fetch", out_triangles,
                           out_vertices, after.acmr, seconds[3]);
              fmt::print("{:<10}{:>12}{:>12}{:>10}{:>9.3f}s  {} ({} bytes)\n", "write", out_triangles, out_vertices, "",
                         write_seconds, o->output, written.bytes);
              fmt::print("{}", draco_line(written, o->gltf));
            }
            return 0;
          }};
}

}  // namespace lod::cli
