// lodkit info FILE [--json]: what a mesh file holds, and its topology.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct InfoOptions {
  std::string input;
  bool json = false;
};

nlohmann::json stats_json(const MeshStats& s) {
  nlohmann::json components = nlohmann::json::array();
  for (const ComponentStats& c : s.components)
    components.push_back({{"vertices", c.vertices},
                          {"edges", c.edges},
                          {"triangles", c.triangles},
                          {"boundary_loops", c.boundary_loops},
                          {"euler_characteristic", c.euler_characteristic},
                          {"closed", c.closed},
                          {"manifold", c.manifold},
                          {"orientable", c.orientable},
                          {"genus", c.genus}});
  return {{"vertices", s.vertices},
          {"triangles", s.triangles},
          {"unique_positions", s.unique_positions},
          {"unreferenced_positions", s.unreferenced_positions},
          {"edges", s.edges},
          {"connected_components", s.connected_components},
          {"boundary_edges", s.boundary_edges},
          {"boundary_loops", s.boundary_loops},
          {"non_manifold_edges", s.non_manifold_edges},
          {"non_manifold_vertices", s.non_manifold_vertices},
          {"degenerate_triangles", s.degenerate_triangles},
          {"zero_area_triangles", s.zero_area_triangles},
          {"duplicate_triangles", s.duplicate_triangles},
          {"seam_edges", s.seam_edges},
          {"materials", s.materials},
          {"euler_characteristic", s.euler_characteristic},
          {"bbox_min", {s.bbox_min.x, s.bbox_min.y, s.bbox_min.z}},
          {"bbox_max", {s.bbox_max.x, s.bbox_max.y, s.bbox_max.z}},
          {"diagonal", s.diagonal},
          {"components", components}};
}

std::string streams_text(const Mesh& m) {
  std::string s = "position";
  if (!m.normals.empty()) s += " normal";
  if (!m.tangents.empty()) s += " tangent";
  for (size_t k = 0; k < m.uv_set_count(); ++k) s += fmt::format(" uv{}", k);
  if (!m.colors.empty()) s += " color";
  if (!m.joints.empty()) s += " joints weights";
  return s;
}

// The texture files an OBJ's MTL library or a PLY's TextureFile lines give its materials, each
// once, in material order (a glTF's own textures are counted from the document instead).
std::vector<std::string> look_textures(const Mesh& m) {
  std::vector<std::string> files;
  for (const MaterialLook& look : m.material_looks)
    for (const std::string* t : look.textures())
      if (!t->empty() && std::find(files.begin(), files.end(), *t) == files.end()) files.push_back(*t);
  return files;
}

// Morph targets (blend shapes): how many, over how many primitives.
std::pair<size_t, size_t> morph_target_counts(const Scene& scene) {
  size_t targets = 0, primitives = 0;
  for (size_t p = 0; p < scene.primitives.size(); ++p) {
    const size_t n = source_morph_targets(scene, p).size();
    targets += n, primitives += n != 0;
  }
  return {targets, primitives};
}

// EXT_mesh_gpu_instancing: how many instances, over how many nodes.
std::pair<size_t, size_t> gpu_instance_counts(const Scene& scene) {
  size_t instances = 0, nodes = 0;
  for (const Node& node : scene.nodes) {
    instances += node.gpu_instances.size();
    nodes += !node.gpu_instances.empty();
  }
  return {instances, nodes};
}

// MSFT_lod chains (lodkit lod writes them): per node that lists coarser levels, its name, each
// level's triangles (its mesh drawn once) and the instances each level is drawn with.
struct LodChainInfo {
  std::string node;
  std::vector<uint64_t> triangles;
  size_t instances = 0;
};

std::vector<LodChainInfo> lod_chains(const Scene& scene) {
  const auto triangles = [&](int32_t mesh) {
    uint64_t t = 0;
    for (const Primitive& p : scene.primitives)
      if (int32_t(p.gltf_mesh) == mesh) t += p.mesh.triangle_count();
    return t;
  };
  std::vector<LodChainInfo> out;
  for (const Node& node : scene.nodes) {
    if (node.lod_ids.empty()) continue;
    LodChainInfo& c = out.emplace_back(LodChainInfo{node.name, {triangles(node.mesh)}, std::max<size_t>(1, node.gpu_instances.size())});
    for (const int32_t id : node.lod_ids)
      c.triangles.push_back(id >= 0 && size_t(id) < scene.nodes.size() ? triangles(scene.nodes[size_t(id)].mesh) : 0);
  }
  return out;
}

// A progressive mesh (.lpm): its record's span, from the input down to its base mesh.
struct ProgressiveInfo {
  size_t collapses = 0;
  uint32_t max_positions = 0, min_positions = 0;
  uint64_t max_triangles = 0, min_triangles = 0;
  bool influence_changes = false;  // a skinned multi-pose record: survivors' joints and weights
};

ProgressiveInfo progressive_info(ProgressiveMesh& pm) {
  ProgressiveInfo p{pm.collapse_count(), pm.max_positions(), pm.min_positions(), pm.input().triangle_count(), 0,
                    !pm.record().influences.empty()};
  pm.set_collapses(pm.collapse_count());
  p.min_triangles = pm.mesh().triangle_count();
  pm.set_collapses(0);
  return p;
}

void print_table(const InfoOptions& o, const std::string& format, const Scene& scene, const Mesh& mesh,
                 const MeshStats& s, const ProgressiveInfo* pm, double load_seconds) {
  auto row = [](const char* key, const std::string& value) { fmt::print("{:<24}{}\n", key, value); };
  row("file", fmt::format("{} ({})", o.input, format));
  row("load time", fmt::format("{:.3f} s", load_seconds));
  row("streams", streams_text(mesh));
  if (pm) {
    row("progressive mesh", fmt::format("{} collapses: {} > {} positions, {} > {} triangles", pm->collapses,
                                        pm->max_positions, pm->min_positions, pm->max_triangles, pm->min_triangles));
    if (pm->influence_changes) row("influence changes", "yes (skinned, multi-pose: the survivors' joints and weights)");
    fmt::print("(the statistics below are the input's, the progressive mesh fully refined)\n");
  }
  if (scene.source) {
    row("glTF primitives", std::to_string(scene.primitives.size()));
    row("glTF nodes", std::to_string(scene.nodes.size()));
    row("glTF materials", std::to_string(scene.material_names.size()));
    row("glTF textures / images", fmt::format("{} / {}", scene.texture_count, scene.image_count));
    row("glTF skins", std::to_string(scene.skins.size()));
    row("glTF animations", std::to_string(scene.animations.size()));
    row("glTF extensions", scene.extensions_used.empty() ? "none" : fmt::format("{}", fmt::join(scene.extensions_used, " ")));
    if (const auto [targets, primitives] = morph_target_counts(scene); targets != 0)
      row("glTF morph targets", fmt::format("{} on {} primitive{}", targets, primitives, primitives == 1 ? "" : "s"));
    if (const auto [instances, nodes] = gpu_instance_counts(scene); instances != 0)
      row("glTF GPU instances", fmt::format("{} on {} node{}", instances, nodes, nodes == 1 ? "" : "s"));
    for (const LodChainInfo& c : lod_chains(scene))
      row("glTF LOD chain", fmt::format("'{}': {} triangles{}", c.node, fmt::join(c.triangles, " > "),
                                        c.instances > 1 ? fmt::format(" (x {} instances)", c.instances) : ""));
  }
  row("vertices", std::to_string(s.vertices));
  row("triangles", std::to_string(s.triangles));
  row("unique positions", std::to_string(s.unique_positions));
  row("unreferenced positions", std::to_string(s.unreferenced_positions));
  row("edges", std::to_string(s.edges));
  row("connected components", std::to_string(s.connected_components));
  row("boundary edges", std::to_string(s.boundary_edges));
  row("boundary loops", std::to_string(s.boundary_loops));
  row("non-manifold edges", std::to_string(s.non_manifold_edges));
  row("non-manifold vertices", std::to_string(s.non_manifold_vertices));
  row("degenerate triangles", std::to_string(s.degenerate_triangles));
  row("zero-area triangles", std::to_string(s.zero_area_triangles));
  row("duplicate triangles", std::to_string(s.duplicate_triangles));
  row("seam edges", std::to_string(s.seam_edges));
  row("materials", std::to_string(s.materials));
  if (!scene.source && !mesh.material_looks.empty()) {
    std::vector<std::string> shown;
    for (const std::string& file : look_textures(mesh)) {
      std::error_code ec;
      shown.push_back(std::filesystem::is_regular_file(file, ec) ? file : file + " (missing)");
    }
    row("material textures", shown.empty() ? "none" : fmt::format("{}", fmt::join(shown, ", ")));
  }
  row("Euler characteristic", std::to_string(s.euler_characteristic));
  row("bounding box min", fmt::format("{:g} {:g} {:g}", s.bbox_min.x, s.bbox_min.y, s.bbox_min.z));
  row("bounding box max", fmt::format("{:g} {:g} {:g}", s.bbox_max.x, s.bbox_max.y, s.bbox_max.z));
  row("diagonal", fmt::format("{:g}", s.diagonal));
  if (s.components.empty()) return;
  constexpr size_t max_rows = 20;
  fmt::print("\n{:>6} {:>9} {:>9} {:>9} {:>7} {:>8} {:>6} {:>8} {:>6}\n", "comp", "V", "E", "F", "V-E+F", "borders",
             "closed", "manifold", "genus");
  for (size_t i = 0; i < s.components.size() && i < max_rows; ++i) {
    const ComponentStats& c = s.components[i];
    fmt::print("{:>6} {:>9} {:>9} {:>9} {:>7} {:>8} {:>6} {:>8} {:>6}\n", i, c.vertices, c.edges, c.triangles,
               c.euler_characteristic, c.boundary_loops, c.closed ? "yes" : "no",
               c.manifold ? (c.orientable ? "yes" : "non-or.") : "no", c.genus >= 0 ? std::to_string(c.genus) : "-");
  }
  if (s.components.size() > max_rows) fmt::print("{:>6} (+{} more; --json lists all)\n", "...", s.components.size() - max_rows);
}

}  // namespace

Command register_info(CLI::App& root) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* app = root.add_subcommand("info", "Print the statistics and topology of a mesh file");
  app->add_option("input", options->input, "Mesh file (.obj .ply .off .stl .gltf .glb), or a progressive mesh (.lpm)")
      ->required();
  app->add_flag("--json", options->json, "Print a machine-readable report on stdout");
  return {app, [options] {
            const InfoOptions& o = *options;
            // A progressive mesh is described by its record and its input mesh.
            const bool lpm = std::filesystem::path(o.input).extension() == ".lpm";
            const FileFormat format = lpm ? FileFormat::ply : format_from_path(o.input);
            const std::string format_label = lpm ? "lpm" : format_name(format);
            auto start = std::chrono::steady_clock::now();
            Scene scene;
            Mesh mesh;
            std::optional<ProgressiveInfo> progressive;
            {
              // glTF keeps its scene for the summary; the statistics are over the flattened mesh.
              ProgressBar bar("loading");
              if (lpm) {
                ProgressiveMesh pm = read_progressive_mesh(o.input);
                progressive = progressive_info(pm);
                mesh = pm.input();
              } else if (format == FileFormat::gltf || format == FileFormat::glb) {
                scene = read_scene(o.input, bar.read_options());
                mesh = flatten(scene);
              } else {
                mesh = read_mesh(o.input, bar.read_options());
              }
            }
            double load_seconds = seconds_since(start);
            validate(mesh, o.input);
            MeshStats s = compute_stats(mesh);
            if (o.json) {
              nlohmann::json j = {{"file", o.input}, {"format", format_label}, {"load_seconds", load_seconds},
                                  {"streams", streams_text(mesh)}, {"stats", stats_json(s)}};
              if (progressive)
                j["progressive"] = {{"collapses", progressive->collapses},
                                    {"max_positions", progressive->max_positions},
                                    {"min_positions", progressive->min_positions},
                                    {"max_triangles", progressive->max_triangles},
                                    {"min_triangles", progressive->min_triangles},
                                    {"influence_changes", progressive->influence_changes}};
              const auto [instances, instanced_nodes] = gpu_instance_counts(scene);
              const auto [morph_targets, morphing_primitives] = morph_target_counts(scene);
              if (scene.source)
                j["gltf"] = {{"primitives", scene.primitives.size()}, {"nodes", scene.nodes.size()},
                             {"materials", scene.material_names.size()}, {"textures", scene.texture_count},
                             {"images", scene.image_count}, {"skins", scene.skins.size()},
                             {"animations", scene.animations.size()},
                             {"extensions_used", scene.extensions_used},
                             {"morph_targets", morph_targets},
                             {"morphing_primitives", morphing_primitives},
                             {"gpu_instances", instances},
                             {"instanced_nodes", instanced_nodes}};
              if (!scene.source && !mesh.material_looks.empty()) j["material_textures"] = look_textures(mesh);
              if (scene.source) {
                nlohmann::json chains = nlohmann::json::array();
                for (const LodChainInfo& c : lod_chains(scene))
                  chains.push_back({{"node", c.node}, {"triangles", c.triangles}, {"instances", c.instances}});
                j["gltf"]["lod_chains"] = chains;
              }
              fmt::print("{}\n", j.dump(2));
            } else {
              print_table(o, format_label, scene, mesh, s, progressive ? &*progressive : nullptr, load_seconds);
            }
            return 0;
          }};
}

}  // namespace lod::cli
