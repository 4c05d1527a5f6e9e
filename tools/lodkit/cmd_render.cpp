// lodkit render: pictures of a mesh (one view, a turntable) or a LOD chain's contact sheet, drawn
// with OpenGL 4.5 through headless EGL (Mesa llvmpipe without a GPU).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/render.h"
#include "lodkit/skin.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct RenderCommand {
  std::string input, output, view = "iso", size = "1024x768", legend_max = "max";
  bool wire = false, heatmap = false, flat = false, ortho = false, sheet = false, json = false;
  double fov_degrees = 40, elevation_degrees = 20;
  uint32_t samples = 4, turntable = 0, columns = 0;
  std::string clip;  // skinned levels: the animation (name or index) to pose them in
  std::string chain;  // --sheet: which chain (index or name)
  float time = 0;    // seconds into it
};

// The joint matrices of `skin` at `time` seconds into `clip` (a name, or an index).
std::vector<mat4> clip_pose(const Scene& scene, const std::string& clip, float time, uint32_t skin) {
  size_t index = scene.animations.size();
  for (size_t a = 0; a < scene.animations.size(); ++a)
    if (scene.animations[a].name == clip) index = a;
  if (index == scene.animations.size() && !clip.empty() && clip.find_first_not_of("0123456789") == std::string::npos)
    index = std::stoul(clip);
  if (index >= scene.animations.size()) throw_usage("--clip: the file has no animation '" + clip + "'");
  Pose pose = rest_pose(scene);
  sample_animation(scene, index, time, pose);
  return joint_matrices(scene, skin, world_matrices(scene, pose));
}

void parse_size(const std::string& text, uint32_t& width, uint32_t& height) {
  unsigned w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 16384 || h > 16384)
    throw_usage("--size: '" + text + "' is not WIDTHxHEIGHT in pixels (1 to 16384), like 1024x768");
  width = w;
  height = h;
}

std::string thousands(uint64_t n) {
  std::string digits = std::to_string(n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

struct ChainLevel {
  Mesh mesh;
  std::string label;
};

// The levels of a lodkit LOD chain: the node carrying MSFT_lod, then the nodes it lists, each with
// the triangles and error its extras state (lodkit lod writes them), and an instanced level drawn
// once, its instance count in the label.
// With `clip`, skinned levels are posed at `time` seconds into it (skinned by the CPU; a skinned
// mesh ignores its node's transform, as glTF says).
// `chain` picks one of several (a skinned character's, an instanced mesh's, the rest of the scene):
// its index in file order, or a name, the LOD0 node's or the node it stands for (a skinned node, or
// an instanced chain's LOD0's parent); empty: the first.
std::vector<ChainLevel> read_chain(const std::string& path, const std::string& chain, const std::string& clip, float time) {
  const FileFormat format = format_from_path(path);
  if (format != FileFormat::glb && format != FileFormat::gltf)
    throw_usage("--sheet reads a LOD chain written by lodkit lod (.glb or .gltf)");
  const Scene scene = read_scene(path);
  // The chosen node with MSFT_lod ids (the reader checked they name nodes), then the nodes it lists.
  std::vector<size_t> firsts;
  for (size_t n = 0; n < scene.nodes.size(); ++n)
    if (!scene.nodes[n].lod_ids.empty()) firsts.push_back(n);
  if (firsts.empty()) throw_bad_input(path, "no LOD chain: no node has the MSFT_lod extension (make one with lodkit lod)");
  const auto names = [&](size_t n) {
    std::vector<std::string> out = {scene.nodes[n].name};
    if (const int32_t parent = scene.nodes[n].parent; parent >= 0 && size_t(parent) < scene.nodes.size())
      out.push_back(scene.nodes[size_t(parent)].name);
    return out;
  };
  size_t first = firsts[0];
  if (!chain.empty()) {
    const bool index = std::all_of(chain.begin(), chain.end(), [](char c) { return c >= '0' && c <= '9'; }) && chain.size() < 9;
    const auto found = std::find_if(firsts.begin(), firsts.end(), [&](size_t n) {
      const std::vector<std::string> known = names(n);
      return std::find(known.begin(), known.end(), chain) != known.end();
    });
    if (index && std::stoul(chain) < firsts.size()) {
      first = firsts[std::stoul(chain)];
    } else if (found != firsts.end()) {
      first = *found;
    } else {
      std::string listed;
      for (size_t k = 0; k < firsts.size(); ++k) listed += fmt::format("{}{} ('{}')", k ? ", " : "", k, fmt::join(names(firsts[k]), "', '"));
      throw_usage(fmt::format("--chain {}: {} has {} chain{}: {}", chain, path, firsts.size(), firsts.size() == 1 ? "" : "s", listed));
    }
  }
  std::vector<int64_t> order = {int64_t(first)};
  order.insert(order.end(), scene.nodes[first].lod_ids.begin(), scene.nodes[first].lod_ids.end());

  std::vector<ChainLevel> levels;
  for (size_t i = 0; i < order.size(); ++i) {
    const Node& node = scene.nodes[size_t(order[i])];
    if (node.mesh < 0) throw_bad_input(path, fmt::format("LOD node {} has no mesh", order[i]));
    // A one-node scene of this level alone (its transform applied, its children left out).
    Scene level;
    level.nodes.push_back(node);
    level.nodes[0].children.clear();
    level.nodes[0].parent = -1;
    level.nodes[0].gpu_instances.clear();  // an instanced level: one instance, which shows the level best
    level.roots = {0};
    for (const Primitive& prim : scene.primitives)
      if (int32_t(prim.gltf_mesh) == node.mesh) level.primitives.push_back(prim);
    ChainLevel out{flatten(level), ""};
    if (!clip.empty()) {
      if (node.skin < 0) throw_usage(fmt::format("--clip: LOD node {} is not skinned", order[i]));
      // Each primitive (material) posed; skinned, they are in the skeleton's space, where glTF
      // ignores the node's transform.
      const std::vector<mat4> pose = clip_pose(scene, clip, time, uint32_t(node.skin));
      for (Primitive& prim : level.primitives) {
        SkinnedVertices posed;
        skin_vertices(prim.mesh, pose, posed);
        prim.mesh.positions = std::move(posed.positions);
        prim.mesh.normals = std::move(posed.normals);
      }
      Node& at = level.nodes[0];
      at.skin = -1, at.has_matrix = false, at.translation = {}, at.rotation = {0, 0, 0, 1}, at.scale = {1, 1, 1};
      out.mesh = flatten(level);
    }
    const nlohmann::json extras = nlohmann::json::parse(node.extras_json.empty() ? "{}" : node.extras_json);
    const nlohmann::json lodkit = extras.is_object() ? extras.value("lodkit", nlohmann::json::object()) : nlohmann::json();
    out.label = fmt::format("LOD{}: {} triangles", i, thousands(out.mesh.triangle_count()));
    if (!node.gpu_instances.empty()) out.label += fmt::format(" x {} instances", thousands(node.gpu_instances.size()));
    if (lodkit.is_object() && lodkit.contains("error") && lodkit["error"].is_number()) {
      out.label += fmt::format(", error {:.3g}", lodkit["error"].get<double>());
      if (lodkit.contains("relative_error") && lodkit["relative_error"].is_number())
        out.label += fmt::format(" ({:.2g}%)", 100 * lodkit["relative_error"].get<double>());
    }
    levels.push_back(std::move(out));
  }
  return levels;
}

// The bounding sphere of several meshes (for one camera over a whole chain).
BoundingSphere union_sphere(const std::vector<ChainLevel>& levels) {
  float3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const ChainLevel& level : levels) {
    if (level.mesh.positions.empty()) continue;
    float3 a, b;
    bounding_box(level.mesh, a, b);
    lo = {std::min(lo.x, a.x), std::min(lo.y, a.y), std::min(lo.z, a.z)};
    hi = {std::max(hi.x, b.x), std::max(hi.y, b.y), std::max(hi.z, b.z)};
  }
  if (!(lo.x <= hi.x)) return {};
  Mesh corners;
  corners.positions = {lo, hi};
  return bounding_sphere(corners);
}

}  // namespace

Command register_render(CLI::App& root) {
  auto o = std::make_shared<RenderCommand>();
  CLI::App* app = root.add_subcommand("render", "Pictures of a mesh, a turntable or a LOD chain's contact sheet (OpenGL, headless)");
  app->add_option("input", o->input, "Input mesh (any format; a LOD chain .glb with --sheet)")->required();
  app->add_option("-o,--output", o->output, "Output .png (a folder with --turntable)")->required();
  app->add_option("--view", o->view, "iso (default), front, back, left, right, top, bottom, iso-front-left, "
                                     "iso-back-right, iso-back-left, iso-...-below, or a direction x,y,z");
  app->add_option("--size", o->size, "Image size WIDTHxHEIGHT in pixels (default 1024x768; the whole sheet with --sheet)");
  app->add_flag("--wire", o->wire, "Draw the triangle edges over the shading");
  app->add_flag("--heatmap", o->heatmap, "Show the vertex colours of lodkit compare --heatmap, with a legend");
  app->add_option("--legend-max", o->legend_max, "With --heatmap: the label at the red end of the legend (default 'max')");
  app->add_flag("--flat", o->flat, "Flat shading (one normal per triangle) instead of smooth");
  app->add_flag("--ortho", o->ortho, "Orthographic projection instead of perspective");
  app->add_option("--fov", o->fov_degrees, "Vertical field of view in degrees (default 40)");
  app->add_option("--samples", o->samples, "MSAA samples per pixel (default 4; 1 for none)");
  app->add_flag("--sheet", o->sheet, "Contact sheet of a LOD chain (lodkit lod's .glb): one labelled panel per level");
  app->add_option("--columns", o->columns, "With --sheet: panels per row (default: the most square grid)");
  app->add_option("--turntable", o->turntable, "Write N frames around the model into the output folder (frame-000.png ...)");
  app->add_option("--elevation", o->elevation_degrees, "With --turntable: camera height above the horizon, degrees (default 20)");
  app->add_option("--chain", o->chain,
                  "With --sheet: which chain of a file with several (its index, or the name of its skinned or instanced "
                  "node or LOD0 node; default the first)");
  app->add_option("--clip", o->clip, "With --sheet: pose skinned levels in this animation (name or index)");
  app->add_option("--time", o->time, "With --clip: seconds into the animation (default 0)");
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o] {
            const auto start = std::chrono::steady_clock::now();
            uint32_t width = 0, height = 0;
            parse_size(o->size, width, height);
            if (o->sheet && o->turntable) throw_usage("--sheet and --turntable do not go together");
            if (!o->clip.empty() && !o->sheet) throw_usage("--clip poses the skinned levels of a --sheet");
            if (!o->chain.empty() && !o->sheet) throw_usage("--chain picks the chain of a --sheet");
            if (!(o->fov_degrees > 0 && o->fov_degrees < 180)) throw_usage("--fov must be in (0, 180) degrees");
            if (!(std::abs(o->elevation_degrees) < 90)) throw_usage("--elevation must be within (-90, 90) degrees");
            if (o->samples == 0) throw_usage("--samples must be at least 1");
            if (!o->turntable && std::filesystem::path(o->output).extension() != ".png")
              throw_usage(o->output + ": lodkit render writes PNG: give an output ending in .png");
            if (!o->turntable) check_output_folder(o->output);  // (a turntable's folder is made)
            const float3 direction = view_direction(o->view);
            const double fov = o->fov_degrees * M_PI / 180;
            const RenderOptions options{.width = width,
                                        .height = height,
                                        .samples = o->samples,
                                        .shading = o->flat ? Shading::flat : Shading::smooth,
                                        .heatmap = o->heatmap,
                                        .wireframe = o->wire};

            // Inputs first: a bad file is reported before any GL work.
            std::vector<ChainLevel> levels;
            {
              ProgressBar bar("loading");
              if (o->sheet) {
                levels = read_chain(o->input, o->chain, o->clip, o->time);
              } else {
                levels.push_back({read_mesh(o->input, bar.read_options()), ""});
              }
            }
            for (const ChainLevel& level : levels) validate(level.mesh, o->input);
            const double load_seconds = seconds_since(start);

            auto step = std::chrono::steady_clock::now();
            RenderContext gl;
            const double context_seconds = seconds_since(step);
            std::unique_ptr<Font> font;
            if (o->sheet || o->heatmap) font = std::make_unique<Font>();

            double upload_seconds = 0, render_seconds = 0, write_seconds = 0;
            std::vector<std::string> written;
            uint64_t triangles = 0;
            auto draw = [&](const Mesh& mesh, auto&& camera_for, uint32_t count, uint32_t w, uint32_t h) {
              step = std::chrono::steady_clock::now();
              const GpuMesh uploaded(gl, mesh, o->input);
              upload_seconds += seconds_since(step);
              step = std::chrono::steady_clock::now();
              std::vector<Image> images;
              RenderOptions each = options;
              each.width = w;
              each.height = h;
              each.read_depth = false;
              for (uint32_t k = 0; k < count; ++k) images.push_back(render(gl, uploaded, camera_for(k), each));
              render_seconds += seconds_since(step);
              triangles += mesh.triangle_count();
              return images;
            };
            auto legend = [&](Image& image) {
              if (o->heatmap) draw_heat_legend(image, *font, "0", o->legend_max);
            };
            auto write = [&](const Image& image, const std::filesystem::path& path) {
              step = std::chrono::steady_clock::now();
              write_png(image, path);
              write_seconds += seconds_since(step);
              written.push_back(path.string());
            };

            const double aspect = double(width) / height;
            if (o->sheet) {
              const SheetOptions sheet_options{.width = width, .height = height, .columns = o->columns};
              const SheetLayout layout = sheet_layout(uint32_t(levels.size()), sheet_options);
              // One camera for every level, so their sizes compare.
              const RenderCamera camera = fit_camera(union_sphere(levels), direction,
                                                     double(layout.panel_width) / layout.panel_height, fov, o->ortho);
              std::vector<Image> panels;
              std::vector<std::string> labels;
              for (const ChainLevel& level : levels) {
                std::vector<Image> image = draw(
                    level.mesh, [&](uint32_t) { return camera; }, 1, layout.panel_width, layout.panel_height);
                legend(image[0]);
                panels.push_back(std::move(image[0]));
                labels.push_back(level.label);
              }
              write(contact_sheet(panels, labels, sheet_options, *font), o->output);
            } else if (o->turntable) {
              const Mesh& mesh = levels[0].mesh;
              const BoundingSphere sphere = bounding_sphere(mesh);
              std::error_code ec;
              std::filesystem::create_directories(o->output, ec);
              if (!std::filesystem::is_directory(o->output))
                throw_bad_input(o->output, "cannot make the output folder for the turntable frames");
              const double elevation = o->elevation_degrees * M_PI / 180;
              std::vector<Image> frames = draw(
                  mesh,
                  [&](uint32_t k) {
                    RenderCamera c = turntable_camera(sphere, k, o->turntable, aspect, elevation, fov);
                    if (o->ortho) {
                      const RenderCamera fitted = fit_camera(sphere, {c.eye.x - c.target.x, c.eye.y - c.target.y,
                                                                      c.eye.z - c.target.z}, aspect, fov, true);
                      c.ortho_height = fitted.ortho_height;
                    }
                    return c;
                  },
                  o->turntable, width, height);
              const int digits = std::max<int>(3, int(std::to_string(o->turntable - 1).size()));
              for (uint32_t k = 0; k < frames.size(); ++k) {
                legend(frames[k]);
                write(frames[k], std::filesystem::path(o->output) / fmt::format("frame-{:0{}}.png", k, digits));
              }
            } else {
              const Mesh& mesh = levels[0].mesh;
              const RenderCamera camera = fit_camera(bounding_sphere(mesh), direction, aspect, fov, o->ortho);
              std::vector<Image> image = draw(mesh, [&](uint32_t) { return camera; }, 1, width, height);
              legend(image[0]);
              write(image[0], o->output);
            }
            const double total_seconds = seconds_since(start);

            if (o->json) {
              nlohmann::json j = {{"input", o->input},
                                  {"output", o->output},
                                  {"files", written},
                                  {"triangles", triangles},
                                  {"width", width},
                                  {"height", height},
                                  {"samples", std::min(o->samples, gl.max_samples())},
                                  {"renderer", gl.renderer()},
                                  {"gl_version", gl.version()},
                                  {"load_seconds", load_seconds},
                                  {"context_seconds", context_seconds},
                                  {"upload_seconds", upload_seconds},
                                  {"render_seconds", render_seconds},
                                  {"write_seconds", write_seconds},
                                  {"total_seconds", total_seconds}};
              if (o->sheet) {
                nlohmann::json panels = nlohmann::json::array();
                for (const ChainLevel& level : levels)
                  panels.push_back({{"triangles", level.mesh.triangle_count()}, {"label", level.label}});
                j["panels"] = panels;
              }
              fmt::print("{}\n", j.dump(2));
              return 0;
            }
            fmt::print("{:<10}{:>12}{:>10}{:>10}{:>10}{:>10}{:>10}\n", "render", "triangles", "load", "context",
                       "upload", "draw", "write");
            fmt::print("{:<10}{:>12}{:>9.3f}s{:>9.3f}s{:>9.3f}s{:>9.3f}s{:>9.3f}s\n",
                       o->sheet ? "sheet" : o->turntable ? "turntable" : "image", triangles, load_seconds,
                       context_seconds, upload_seconds, render_seconds, write_seconds);
            fmt::print("{} file{} ({}x{}, {}) on {} in {:.3f}s: {}\n", written.size(), written.size() == 1 ? "" : "s",
                       width, height, o->sheet ? fmt::format("{} panels", levels.size()) : o->view, gl.renderer(),
                       total_seconds, written.size() == 1 ? written[0] : o->output);
            return 0;
          }};
}

}  // namespace lod::cli
