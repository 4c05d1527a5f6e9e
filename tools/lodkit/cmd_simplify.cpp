// lodkit simplify IN -o OUT: one simplification to a target ratio, triangle count or error.
// A glTF written from a glTF keeps everything else (nodes, skins, animations, materials). The
// primitives of one glTF mesh are simplified together (join_members), their material borders kept
// closed like seams, each with its own streams; a skinned one keeps its survivors' joints and
// weights. Morph targets and other streams lodkit does not model are kept: exact with
// --keep-vertices, else interpolated (lod::vertex_blends).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/simplify.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct SimplifyCommand {
  std::string input, output;
  float ratio = 0, error = 0, aggregate = 0;
  uint64_t triangles = 0;
  std::string metric = "cqem", attributes;
  bool keep_vertices = false, lock_border = false, prune = false, json = false, force = false;
  WriteOptions gltf;  // -c, -q
  unsigned threads = 0;
  uint32_t fit = SimplifyOptions{}.fit_iterations;
  bool no_flips = false, no_search = false;
  float fit_edge_weight = SimplifyOptions{}.fit_edge_weight;
  float guard = SimplifyOptions{}.distance_guard;
};

}  // namespace

Metric parse_metric(const std::string& name) {
  for (const Metric m : {Metric::edge_length, Metric::qem, Metric::constrained_qem, Metric::memoryless,
                         Metric::constrained_memoryless})
    if (name == metric_name(m)) return m;
  throw_usage("--metric must be one of edge, qem, cqem, memoryless, cmemoryless (got '" + name + "')");
}

// "normal=1,uv=0.5,color=1"
void parse_attributes(const std::string& text, SimplifyOptions& options) {
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find(',', begin);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(begin, end - begin);
    const size_t eq = item.find('=');
    const std::string name = item.substr(0, eq);
    float weight = 1.0f;
    if (eq != std::string::npos) {
      try {
        size_t used = 0;
        weight = std::stof(item.substr(eq + 1), &used);
        if (used != item.size() - eq - 1 || !(weight >= 0)) throw std::invalid_argument(item);
      } catch (const std::exception&) {
        throw_usage("--attributes: '" + item + "' needs a weight >= 0, like normal=1");
      }
    }
    if (name == "normal") options.normal_weight = weight;
    else if (name == "uv") options.uv_weight = weight;
    else if (name == "color") options.color_weight = weight;
    else throw_usage("--attributes: unknown attribute '" + name + "' (normal, uv or color)");
    begin = end + 1;
  }
}

Command register_simplify(CLI::App& root) {
  auto o = std::make_shared<SimplifyCommand>();
  CLI::App* app = root.add_subcommand("simplify", "Simplify a mesh by edge collapses (quadric error metrics)");
  app->add_option("input", o->input, "Input mesh file")->required();
  app->add_option("-o,--output", o->output, "Output mesh file; the format follows the extension")->required();
  // Given together, the targets stop the simplification at whichever is reached first.
  app->add_option("--ratio", o->ratio, "Fraction of the triangles to keep, in [0, 1]");
  app->add_option("--triangles", o->triangles, "Number of triangles to keep (0: as few as the mesh allows)");
  app->add_option("--error", o->error,
                  "Stop before the simplifier's own error (the square root of its quadric cost: an estimate the measured "
                  "distance can exceed; lod --errors holds levels to the measured one) exceeds this fraction of the "
                  "bounding-box diagonal; with --ratio or --triangles, whichever is reached first");
  app->add_option("--metric", o->metric, "edge, qem, cqem (default), memoryless or cmemoryless");
  app->add_option("--attributes", o->attributes, "Attribute weights, e.g. normal=1,uv=1,color=1");
  app->add_flag("--keep-vertices", o->keep_vertices, "Use only input vertices (LODs can share one vertex buffer)");
  app->add_flag("--lock-border", o->lock_border, "Never move border vertices");
  app->add_option("--aggregate", o->aggregate, "Also merge positions closer than this distance (object space)");
  app->add_flag("--prune", o->prune, "Drop components smaller than the error reached");
  app->add_option("--fit", o->fit, "Most iterations fitting the result's vertices to the input after the collapses; it stops once they barely move (0: no fit)")
      ->capture_default_str();
  app->add_flag("--no-flips", o->no_flips, "Keep the collapses' triangles: no edge flips in the fit");
  app->add_option("--fit-edge-weight", o->fit_edge_weight,
                  "Weight of the fit's pull on the result's edge midpoints, farthest first (0: a plain least-squares fit)")
      ->capture_default_str();
  app->add_option("--distance-guard", o->guard,
                  "Hold back collapses that would leave an input point farther from the result than G times (in "
                  "squared distance) the error the other collapses reach: keeps thin parts (qem and cqem; 0: off)")
      ->capture_default_str();
  app->add_flag("--no-search", o->no_search,
                "Use exactly the options given: no search over distance guards, the memoryless metric and a plain fit on inputs "
                "up to 32,768 triangles simplified to 1,024 or fewer (qem and cqem; keeps the result nearest the input)");
  app->add_option("--threads", o->threads, "Worker threads (0: all); the output does not depend on it");
  app->add_flag("--force", o->force, "Allow writing over the input file");
  add_gltf_output_flags(app, o->gltf);
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o, app] {
            // Which targets were given (every value is meaningful, so no sentinel tells).
            const bool has_ratio = app->count("--ratio") > 0, has_triangles = app->count("--triangles") > 0,
                       has_error = app->count("--error") > 0;
            if (!has_ratio && !has_triangles && !has_error)
              throw_usage("simplify needs a target: --ratio R, --triangles N or --error E");
            if (has_ratio && !(o->ratio >= 0 && o->ratio <= 1)) throw_usage("--ratio must be in [0, 1]");
            if (has_error && !(o->error >= 0)) throw_usage("--error must be >= 0 (a fraction of the bounding-box diagonal)");
            check_output(o->input, o->output, o->force);
            check_gltf_output_flags(o->gltf, o->output);
            SimplifyOptions options{
                // Only --error: as far as the error allows.
                .target_ratio = has_ratio ? o->ratio : 0.0f,
                .max_relative_error = has_error ? o->error : -1.0f,
                .metric = parse_metric(o->metric),
                .keep_vertices = o->keep_vertices,
                .distance_guard = o->guard,
                .lock_border = o->lock_border,
                .aggregate_distance = o->aggregate,
                .prune = o->prune,
                .fit_iterations = o->fit,
                .fit_flips = !o->no_flips,
                .fit_edge_weight = o->fit_edge_weight,
                .search_input_triangles = o->no_search ? 0 : SimplifyOptions{}.search_input_triangles,
                .record = false,
                .threads = o->threads,
            };
            if (!o->attributes.empty()) parse_attributes(o->attributes, options);

            auto start = std::chrono::steady_clock::now();
            GeometryFile file(o->input, o->output, o->force);
            std::vector<Mesh*>& meshes = file.meshes;
            require_triangles(meshes, o->input, "nothing to simplify; lodkit works on triangle meshes");
            const double load_seconds = seconds_since(start);
            start = std::chrono::steady_clock::now();

            uint64_t total = 0, in_vertices = 0, welded_vertices = 0;
            for (size_t i = 0; i < meshes.size(); ++i) {
              validate(*meshes[i], o->input);
              total += meshes[i]->triangle_count(), in_vertices += meshes[i]->vertex_count();
              const std::vector<uint32_t> first = weld_duplicates(*meshes[i], file.vertex_classes(i));
              if (!first.empty()) file.renumbered(i, first);
              welded_vertices += meshes[i]->vertex_count();
            }
            const double weld_seconds = seconds_since(start);
            start = std::chrono::steady_clock::now();
            bool any_faceted = false;  // some group was flat-shaded: simplified without normals, faceted again
            bool any_two_sided = false;  // some group was double-sided: its fronts simplified, backs made again
            uint64_t in_triangles = 0, out_triangles = 0, out_vertices = 0;
            float error = 0, relative_error = 0;
            uint64_t passes = 0, collapses = 0, virtual_pairs = 0, pruned = 0, fitted = 0, flipped = 0, deferred = 0, rejected[4] = {};
            uint32_t fit_iterations = 0;  // the most any group's fit ran
            double fit_seconds = 0;  // the final fit's share of simplify_seconds
            SimplifyResult::CollapseSteps steps;  // the collapses' share, by step
            uint32_t search_ways = 1;  // the most any group's search tried
            nlohmann::json kept = nlohmann::json::array();  // per joint group: the way its result was made
            std::vector<bool> changed;  // per primitive: its geometry is not the input's
            {
              ProgressBar bar("simplifying");
              changed.assign(meshes.size(), false);
              // Each joint group joined and in the form it is simplified in; then all of them in one
              // batch (small ones side by side, one thread each); then each result back in its members.
              const std::vector<std::vector<size_t>> groups = file.joint_groups();
              std::vector<Joined> joined;
              std::vector<SurfaceForm> forms;
              joined.reserve(groups.size()), forms.reserve(groups.size());
              for (const std::vector<size_t>& group : groups) {
                std::vector<const Mesh*> members;
                for (const size_t i : group) members.push_back(meshes[i]);
                joined.push_back(join_members(members));
                // Double-sided: the fronts simplified, the backs made again. Flat-shaded: simplified
                // without its normals, then faceted again. Neither with input vertices only (the
                // new backs and face normals make new vertices).
                forms.push_back(o->keep_vertices ? SurfaceForm{} : surface_form(joined.back().mesh()));
                any_faceted = any_faceted || forms.back().flat_shaded, any_two_sided = any_two_sided || forms.back().double_sided;
              }
              std::vector<const Mesh*> inputs;
              std::vector<SimplifyOptions> each(groups.size(), options);
              for (size_t g = 0; g < groups.size(); ++g) {
                inputs.push_back(&forms[g].to_simplify(joined[g].mesh()));
                const uint64_t size = inputs.back()->triangle_count();
                // A triangle budget is shared in proportion to each group's size. With a ratio
                // too, the larger target is reached first and stops the group.
                if (has_triangles) {
                  // (At least one each: a share of 0 would mean "no count" to the library.)
                  const uint64_t share = o->triangles == 0 || total == 0
                                             ? 0
                                             : std::max<uint64_t>(1, uint64_t(double(o->triangles) * double(size) / double(total)));
                  const uint64_t by_ratio = has_ratio ? uint64_t(std::llround(double(o->ratio) * double(size))) : 0;
                  // 0 (--triangles 0): the library falls back on target_ratio, which gives 0 too.
                  each[g].target_triangles = std::max(share, by_ratio);
                }
              }
              std::vector<SimplifyResult> results = simplify_batch(inputs, each, o->threads, [&](double f) { bar.update(f); });
              for (size_t g = 0; g < groups.size(); ++g) {
                const std::vector<size_t>& group = groups[g];
                const SurfaceForm& form = forms[g];
                SimplifyResult& r = results[g];
                // Restored, the result's vertices are new: no input vertex is one's origin; the
                // successors are mapped to them.
                restore_form(form, r.mesh, r.vertex_successor);
                if (form.changed()) r.vertex_origin.clear();
                in_triangles += r.input_triangles, out_triangles += r.output_triangles, out_vertices += r.mesh.vertex_count();
                error = std::max(error, r.error);
                passes += r.passes, collapses += r.collapses, virtual_pairs += r.virtual_pairs, pruned += r.pruned_triangles;
                fitted += r.fitted_positions, flipped += r.flipped_edges, fit_seconds += r.seconds_fit;
                steps += r.seconds_steps;
                fit_iterations = std::max(fit_iterations, r.fit_iterations);
                search_ways = std::max(search_ways, r.search_ways);
                kept.push_back({{"metric", metric_name(r.metric)}, {"distance_guard", r.distance_guard},
                                {"fit_flips", r.fit_flips}, {"fit_edge_weight", r.fit_edge_weight},
                                {"ways", r.search_ways}, {"relative_hausdorff", r.search_hausdorff}});
                rejected[0] += r.rejected_topology, rejected[1] += r.rejected_seam;
                rejected[2] += r.rejected_flip, rejected[3] += r.rejected_shape, deferred += r.deferred_distance;
                relative_error = std::max(relative_error, r.relative_error);
                // Input vertices, unmoved: with --keep-vertices, or when nothing collapsed.
                const bool unmoved = o->keep_vertices || (r.collapses == 0 && !form.changed());
                std::vector<Member> parts =
                    split_members(joined[g], std::move(r.mesh), std::move(r.vertex_origin), std::move(r.vertex_successor));
                for (size_t k = 0; k < group.size(); ++k) {
                  const size_t i = group[k];
                  Member& out = parts[k];
                  changed[i] = out.mesh.positions != meshes[i]->positions || out.mesh.indices != meshes[i]->indices;
                  // The glTF streams lodkit does not model (morph targets, other attributes). Unmoved:
                  // each survivor is its origin, so they stay exact for it. Moved, or a restored form's
                  // new vertices: interpolated at each vertex's point on the patch of the input it
                  // replaces.
                  if (unmoved) file.renumbered(i, out.origin);
                  else file.renumbered(i, vertex_blends(*meshes[i], out.successor, out.mesh));
                  *meshes[i] = std::move(out.mesh);
                }
              }
            }
            file.forget_lod_facts(changed);
            const double simplify_seconds = seconds_since(start);
            start = std::chrono::steady_clock::now();
            const WriteReport written = file.write(o->output, o->gltf);
            const double write_seconds = seconds_since(start);

            if (o->json) {
              nlohmann::json j = {{"input", o->input}, {"output", o->output}, {"metric", o->metric},
                                  {"input_triangles", in_triangles}, {"output_triangles", out_triangles},
                                  {"input_vertices", in_vertices}, {"output_vertices", out_vertices},
                                  {"error", error}, {"relative_error", relative_error},
                                  {"passes", passes}, {"collapses", collapses}, {"virtual_pairs", virtual_pairs}, {"pruned_triangles", pruned},
                                  {"fit_iterations", fit_iterations}, {"fitted_positions", fitted}, {"flipped_edges", flipped},
                                  {"rejected", {{"topology", rejected[0]}, {"seam", rejected[1]},
                                                {"flip", rejected[2]}, {"shape", rejected[3]}}},
                                  {"deferred_distance", deferred}, {"search_ways", search_ways}, {"kept", kept},
                                  {"welded_vertices", welded_vertices}, {"flat_shaded", any_faceted}, {"double_sided", any_two_sided},
                                  {"load_seconds", load_seconds}, {"weld_seconds", weld_seconds}, {"simplify_seconds", simplify_seconds},
                                  {"fit_seconds", fit_seconds},
                                  {"write_seconds", write_seconds}};
              for (const auto& [name, value] : steps.named()) j["collapse_step_seconds"][name] = value;
              add_write_report(j, written, o->gltf);
              fmt::print("{}\n", j.dump(2));
            } else {
              fmt::print("{:<10}{:>12}{:>12}{:>14}{:>10}  {}\n", "step", "triangles", "vertices", "error", "time", "");
              fmt::print("{:<10}{:>12}{:>12}{:>14}{:>9.3f}s  {}\n", "read", in_triangles, in_vertices, "", load_seconds,
                         o->input);
              // Bitwise-identical copies merged first (a triangle soup, a non-indexed glTF).
              if (welded_vertices != in_vertices)
                fmt::print("{:<10}{:>12}{:>12}{:>14}{:>9.3f}s  {}\n", "weld", in_triangles, welded_vertices, "", weld_seconds,
                           "identical vertices merged");
              // With a search, the way kept (one group) or how many ways were tried.
              std::string way = o->metric;
              if (search_ways > 1 && kept.size() == 1)
                way = fmt::format("{}, guard {}{}: best of {} ways, Hausdorff {:.4f}%", kept[0]["metric"].get<std::string>(),
                                  kept[0]["distance_guard"].get<float>(),
                                  // "plain fit": the search's fifth way (no flips, no edge term), not
                                  // merely --no-flips, which every way keeps.
                                  !kept[0]["fit_flips"].get<bool>() && kept[0]["fit_edge_weight"].get<float>() == 0 ? ", plain fit" : "",
                                  search_ways,
                                  100.0 * kept[0]["relative_hausdorff"].get<double>());
              else if (search_ways > 1)
                way = fmt::format("{}, best of up to {} ways per mesh", o->metric, search_ways);
              if (any_faceted) way += ", flat-shaded: faceted again";
              if (any_two_sided) way += ", double-sided: fronts simplified, backs made again";
              fmt::print("{:<10}{:>12}{:>12}{:>13.4f}%{:>9.3f}s  {} ({} = {:.6g}, final fit {:.3f}s)\n", "simplify", out_triangles,
                         out_vertices, 100.0 * relative_error, simplify_seconds, way, "error", error, fit_seconds);
              fmt::print("{:<10}{:>12}{:>12}{:>14}{:>9.3f}s  {} ({} bytes)\n", "write", out_triangles, out_vertices, "",
                         write_seconds, o->output, written.bytes);
              fmt::print("{}", draco_line(written, o->gltf));
            }
            return 0;
          }};
}

}  // namespace lod::cli
