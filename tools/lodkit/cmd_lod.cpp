// lodkit lod IN -o OUT.glb: the main job. A chain of LODs with certified error bounds, written as a
// glTF whose first node carries the MSFT_lod extension (the coarser levels' nodes) and
// MSFT_screencoverage in its extras, so three.js / Babylon-style loaders switch levels by
// themselves; every level's error and switch distance are in its node's extras.
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct LodCommand {
  std::string input, output, ratios, errors, metric = "cqem", attributes, lpm;
  uint32_t levels = 0;
  float error_px = 1.0f, screen_height = 1080.0f, fov_degrees = 60.0f;
  bool from_input = false, morph = false, shared = false, json = false, force = false;
  unsigned threads = 0;
};

std::vector<float> parse_list(const std::string& text, const char* option) {
  std::vector<float> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      values.push_back(std::stof(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw_usage(std::string(option) + ": '" + item + "' is not a number");
    }
  }
  if (values.empty()) throw_usage(std::string(option) + " needs a comma-separated list, like 1,0.5,0.25");
  return values;
}

// The glTF: one mesh and one node per level; node 0 is the scene's root and lists the others.
Scene chain_scene(const LodChain& chain, const std::vector<double>& distances, const std::vector<double>& coverage) {
  Scene scene;
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    Primitive prim;
    if (!chain.shared.indices.empty()) {
      // One vertex buffer for the chain; level i's indices use only its first prefix[i] vertices.
      prim.mesh = chain.shared.vertices;
      prim.mesh.indices = chain.shared.indices[i];
      if (i > 0) prim.shares_vertices_with = 0;
    } else {
      prim.mesh = chain.levels[i].mesh;
    }
    prim.mesh.materials.clear();
    prim.gltf_mesh = uint32_t(i);
    scene.primitives.push_back(std::move(prim));
    Node node;
    node.name = fmt::format("LOD{}", i);
    node.mesh = int32_t(i);
    const LodLevel& level = chain.levels[i];
    if (i < chain.morphs.size()) {
      // The geomorph as a glTF morph target: weight t gives (1 - t) P + t P_target, positions and
      // normals, in any viewer; LODKIT_geomorph in the extras says where it leads.
      const Mesh& fine = chain.levels[i].mesh;
      const Mesh& coarse = chain.levels[i + 1].mesh;
      MorphTarget target;
      for (size_t v = 0; v < fine.vertex_count(); ++v) {
        const uint32_t to = chain.morphs[i].target[v];
        const float3 &a = fine.positions[v], &b = coarse.positions[to];
        target.positions.push_back({b.x - a.x, b.y - a.y, b.z - a.z});
        if (!fine.normals.empty() && !coarse.normals.empty()) {
          const float3 &n = fine.normals[v], &m = coarse.normals[to];
          target.normals.push_back({m.x - n.x, m.y - n.y, m.z - n.z});
        }
      }
      scene.primitives.back().targets.push_back(std::move(target));
    }
    nlohmann::json extras = {{"lodkit", {{"level", i},
                                         {"triangles", level.mesh.triangle_count()},
                                         {"error", level.error},
                                         {"error_bound", level.error_bound},
                                         {"relative_error", level.relative_error},
                                         {"switch_distance", distances[i]}}}};
    if (i < chain.morphs.size()) extras["LODKIT_geomorph"] = {{"target", 0}, {"to_node", i + 1}};
    if (!chain.shared.prefix.empty()) extras["lodkit"]["vertex_prefix"] = chain.shared.prefix[i];
    if (i == 0) {
      for (size_t k = 1; k < chain.levels.size(); ++k) node.lod_ids.push_back(int32_t(k));
      extras["MSFT_screencoverage"] = coverage;
    }
    node.extras_json = extras.dump();
    scene.nodes.push_back(std::move(node));
  }
  scene.roots = {0};
  return scene;
}

}  // namespace

Command register_lod(CLI::App& root) {
  auto o = std::make_shared<LodCommand>();
  CLI::App* app = root.add_subcommand("lod", "Build a LOD chain with error bounds and write it as glTF (MSFT_lod)");
  app->add_option("input", o->input, "Input mesh file")->required();
  app->add_option("-o,--output", o->output, "Output glTF (.glb or .gltf)")->required();
  app->add_option("--levels", o->levels, "Number of levels, halving the triangles each time (default 4)");
  app->add_option("--ratios", o->ratios, "Fractions of the triangles per level, finest first, e.g. 1,0.5,0.25");
  app->add_option("--errors", o->errors, "Error limit per level (fraction of the diagonal), finest first, e.g. 0,0.001,0.01");
  app->add_option("--error-px", o->error_px, "Pixels of error allowed on screen when switching (default 1)");
  app->add_option("--screen-height", o->screen_height, "Screen height in pixels (default 1080)");
  app->add_option("--fov", o->fov_degrees, "Vertical field of view in degrees (default 60)");
  app->add_flag("--from-input", o->from_input, "Simplify every level from the input, not from the previous level");
  app->add_flag("--morph", o->morph, "Write geomorphs: each level's morph target 0 moves it onto the next level");
  app->add_flag("--shared-vertices", o->shared,
                "Subset placement and one vertex buffer for all levels (coarser levels use a prefix of it)");
  app->add_option("--metric", o->metric, "edge, qem, cqem (default), memoryless or cmemoryless");
  app->add_option("--attributes", o->attributes, "Attribute weights, e.g. normal=1,uv=1,color=1");
  app->add_option("--lpm", o->lpm, "Also write a progressive mesh (.lpm) down to the coarsest level");
  app->add_option("--threads", o->threads, "Worker threads (0: all); the output does not depend on it");
  app->add_flag("--force", o->force, "Allow writing over the input file");
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o] {
            const FileFormat format = format_from_path(o->output);
            if (format != FileFormat::glb && format != FileFormat::gltf)
              throw_usage("lod writes glTF: give an output ending in .glb or .gltf");
            if (!(o->error_px > 0) || !(o->screen_height > 0) || !(o->fov_degrees > 0 && o->fov_degrees < 180))
              throw_usage("--error-px and --screen-height must be > 0 and --fov in (0, 180)");
            check_not_input(o->input, o->output, o->force);
            if (!o->lpm.empty()) check_not_input(o->input, o->lpm, o->force);
            LodOptions options;
            if (!o->ratios.empty()) options.ratios = parse_list(o->ratios, "--ratios");
            if (!o->errors.empty()) options.errors = parse_list(o->errors, "--errors");
            if (o->levels) options.levels = o->levels;
            options.from_previous = !o->from_input;
            if (o->morph && o->from_input) throw_usage("--morph needs each level simplified from the previous one (drop --from-input)");
            options.morph = o->morph;
            if (o->morph && o->shared) throw_usage("--morph and --shared-vertices cannot be combined yet");
            options.shared_vertices = o->shared;
            options.simplify.metric = parse_metric(o->metric);
            options.simplify.threads = o->threads;
            if (!o->attributes.empty()) parse_attributes(o->attributes, options.simplify);

            auto start = std::chrono::steady_clock::now();
            Mesh mesh;
            {
              ProgressBar bar("loading");
              mesh = read_mesh(o->input, bar.read_options());
            }
            validate(mesh, o->input);
            const double load_seconds = seconds_since(start);
            start = std::chrono::steady_clock::now();
            LodChain chain;
            {
              ProgressBar bar("building LODs");
              options.progress = [&](double f) { bar.update(f); };
              chain = build_lod_chain(mesh, options);
            }
            const double build_seconds = seconds_since(start);

            // Switch distances: where a level's error shrinks to error_px on screen. Screen coverage
            // (MSFT_screencoverage): the bounding sphere's projected height over the screen height at
            // the distance where the next level takes over; 0 after the last (never culled).
            const double fov = o->fov_degrees * M_PI / 180.0;
            const double radius = 0.5 * chain.diagonal;
            std::vector<double> distances, coverage;
            for (const LodLevel& level : chain.levels)
              distances.push_back(switch_distance(level.error_bound, o->error_px, o->screen_height, fov));
            for (size_t i = 0; i < chain.levels.size(); ++i) {
              const double d = i + 1 < chain.levels.size() ? distances[i + 1] : 0.0;
              coverage.push_back(d > 0 ? std::min(1.0, radius / (d * std::tan(fov / 2))) : 0.0);
            }
            start = std::chrono::steady_clock::now();
            write_scene(chain_scene(chain, distances, coverage), o->output);
            if (!o->lpm.empty()) {
              // The progressive mesh spans the input down to the coarsest level's size.
              SimplifyOptions so = options.simplify;
              so.target_triangles = std::max<uint64_t>(1, chain.levels.back().mesh.triangle_count());
              SimplifyResult r = simplify(mesh, so);
              write_progressive_mesh(ProgressiveMesh(mesh, std::move(r.record)), o->lpm);
            }
            const double write_seconds = seconds_since(start);

            if (o->json) {
              nlohmann::json levels = nlohmann::json::array();
              for (size_t i = 0; i < chain.levels.size(); ++i) {
                const LodLevel& l = chain.levels[i];
                levels.push_back({{"level", i}, {"triangles", l.mesh.triangle_count()}, {"vertices", l.mesh.vertex_count()},
                                  {"error", l.error}, {"error_bound", l.error_bound}, {"relative_error", l.relative_error},
                                  {"engine_error", l.engine_error},
                                  {"switch_distance", distances[i]}, {"screen_coverage", coverage[i]}});
              }
              const nlohmann::json j = {{"input", o->input}, {"output", o->output}, {"diagonal", chain.diagonal},
                                        {"levels", levels}, {"load_seconds", load_seconds},
                                        {"build_seconds", build_seconds}, {"write_seconds", write_seconds}};
              fmt::print("{}\n", j.dump(2));
            } else {
              fmt::print("{:<6}{:>12}{:>12}{:>14}{:>11}{:>14}{:>14}\n", "level", "triangles", "vertices", "error", "% diag",
                         "bound", "switch at");
              for (size_t i = 0; i < chain.levels.size(); ++i) {
                const LodLevel& l = chain.levels[i];
                fmt::print("{:<6}{:>12}{:>12}{:>14.6g}{:>10.4f}%{:>14.6g}{:>14.6g}\n", i, l.mesh.triangle_count(),
                           l.mesh.vertex_count(), l.error, 100.0 * l.relative_error, l.error_bound, distances[i]);
              }
              fmt::print("error: Hausdorff distance to the input (measured); bound: certified upper bound; switch at: the "
                         "distance where the bound is {} px ({} px screen, {} deg fov)\n",
                         o->error_px, o->screen_height, o->fov_degrees);
              fmt::print("loaded in {:.3f}s, built in {:.3f}s, wrote {} in {:.3f}s\n", load_seconds, build_seconds,
                         o->output, write_seconds);
            }
            return 0;
          }};
}

}  // namespace lod::cli
