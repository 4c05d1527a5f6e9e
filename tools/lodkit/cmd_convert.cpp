// lodkit convert IN OUT: any supported format to any other. A glTF written from a glTF keeps
// everything but the geometry as it was.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <numeric>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/optimize.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct ConvertOptions {
  std::string input, output, output_flag;
  bool ascii = false;
  WriteOptions gltf;  // -c, -q (binary comes from --ascii)
  bool force = false;
  bool json = false;
};


// Refuses (usage) to write any of `written`, the files writing `output` makes, over any of
// `sources`, files an input reads.
void refuse_writing_over(const std::vector<std::filesystem::path>& sources, const std::vector<std::filesystem::path>& written,
                         const std::string& output) {
  for (const std::filesystem::path& read : sources)
    for (const std::filesystem::path& w : written) {
      std::error_code ec;
      if (std::filesystem::exists(w, ec) && std::filesystem::equivalent(read, w, ec))
        throw_usage(output + ": refusing to write " + w.string() + " over " + read.string() +
                    ", which the input reads (choose another output name)");
    }
}
}  // namespace

void check_output(const std::string& input, const std::string& output, bool force) {
  std::error_code ec;
  if (!force && std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec))
    throw_usage(output + ": refusing to overwrite the input file (use --force)");
  check_output_folder(output);
  // An .obj output writes its MTL library beside it, which may be the one an OBJ input reads.
  const std::filesystem::path library = obj_library_path(output);
  if (!force && !library.empty() && std::filesystem::exists(library, ec) && format_from_path(input) == FileFormat::obj)
    refuse_writing_over(obj_material_libraries(input), {library}, output);
}

void check_output_folder(const std::string& output) {
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::path(output).parent_path();
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
    throw_bad_input(output, "the folder " + folder.string() + " does not exist");
}

void check_not_source(const Scene& scene, const std::string& output, bool force) {
  if (force || output.empty()) return;
  std::vector<std::filesystem::path> written = {output};
  if (std::filesystem::path bin = gltf_buffer_path(output); !bin.empty()) written.push_back(std::move(bin));
  refuse_writing_over(source_files(scene), written, output);
}

void require_triangles(std::span<const Mesh* const> meshes, const std::string& input, const std::string& why) {
  uint64_t vertices = 0;
  for (const Mesh* m : meshes) {
    if (m->triangle_count()) return;
    vertices += m->vertex_count();
  }
  throw_bad_input(input, "has no triangles (" + std::to_string(vertices) + " vertices): " + why);
}

double optional_number(const std::string& flag, const std::string& word, double fallback, std::string& input) {
  if (word.empty()) return fallback;
  const char* begin = word.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end != begin && *end == '\0') return value;
  if (!input.empty()) throw_usage(flag + "=" + word + ": not a number");
  input = word;  // `--weld IN`: the flag without a value, then the input
  return fallback;
}

namespace {
bool is_gltf(const std::string& path) {
  const FileFormat format = format_from_path(path);
  return format == FileFormat::gltf || format == FileFormat::glb;
}
}  // namespace

GeometryFile::GeometryFile(const std::string& input, const std::string& output, bool force)
    : as_scene_(is_gltf(input) && is_gltf(output)) {
  {
    ProgressBar bar("loading");
    if (as_scene_) scene_ = read_scene(input, bar.read_options());
    else mesh_ = read_mesh(input, bar.read_options());
  }
  check_not_source(output, force);
  if (as_scene_)
    for (Primitive& p : scene_.primitives) meshes.push_back(&p.mesh);
  else
    meshes.push_back(&mesh_);
}

void GeometryFile::check_not_source(const std::string& path, bool force) const {
  if (as_scene_) cli::check_not_source(scene_, path, force);
}

WriteReport GeometryFile::write(const std::string& output, const WriteOptions& options) const {
  return as_scene_ ? write_scene(scene_, output, options) : write_mesh(mesh_, output, options);
}

void check_gltf_output_flags(const WriteOptions& options, const std::string& output) {
  if ((options.meshopt_compression || options.quantize || options.draco) && !is_gltf(output))
    throw_usage(output + ": -c, -q, --cc and --draco apply to glTF output (.gltf, .glb) only");
  if (options.meshopt_khr && !options.meshopt_compression) throw_usage("--meshopt-khr: it chooses -c's extension; add -c");
}

namespace {
// Each command reports once, as JSON or as text: both warn.
void warn_plain(const WriteReport& report) {
  if (report.draco_plain)
    std::fprintf(stderr, "lodkit: warning: %u primitive(s) written without Draco: libdraco could not round-trip them\n",
                 report.draco_plain);
}
}  // namespace

void add_write_report(nlohmann::json& json, const WriteReport& report, const WriteOptions& options) {
  warn_plain(report);
  json["output_bytes"] = report.bytes;
  if (options.draco)
    json["draco"] = {{"edgebreaker", report.draco_edgebreaker}, {"sequential", report.draco_sequential},
                     {"plain", report.draco_plain}};
}

std::string draco_line(const WriteReport& report, const WriteOptions& options) {
  warn_plain(report);
  if (!options.draco) return {};
  std::string line = fmt::format("draco: {} primitive(s) by Edgebreaker", report.draco_edgebreaker);
  if (report.draco_sequential)
    line += fmt::format(", {} sequentially (vertices that decode alike, or Edgebreaker refused them)", report.draco_sequential);
  if (report.draco_plain) line += fmt::format(", {} plain (libdraco could not round-trip them)", report.draco_plain);
  return line + "\n";
}

void add_gltf_output_flags(CLI::App* app, WriteOptions& options) {
  app->add_flag("-c,--compress", options.meshopt_compression,
                "glTF output: compress geometry and animation with EXT_meshopt_compression (lossless; "
                "the extension becomes required)");
  app->add_flag("--meshopt-khr", options.meshopt_khr,
                "With -c: KHR_meshopt_compression instead, vertex streams in the codec's version 1 (smaller; for "
                "loaders that implement the KHR extension)");
  app->add_flag("-q,--quantize", options.quantize,
                "glTF output: vertex streams in fewer bits (KHR_mesh_quantization, then required): positions on a "
                "grid of --position-bits, normals and tangents in --normal-bits (bytes by default), UVs in --uv-bits (16 by default; outside [0,1] or below 16 bits: on a box, with KHR_texture_transform), colours and "
                "weights in bytes");
  app->add_flag_callback(
      "--cc",
      [&options] { options.compress_more = options.meshopt_compression = options.quantize = true; },
      "glTF output: -c -q, and normals and tangents through meshopt's octahedral filter (8 bits, within 1.35 "
      "degrees of the input; or --normal-bits), as gltfpack -cc");
  app->add_flag("--draco", options.draco,
                "glTF output: each triangle primitive's geometry as a Draco stream (KHR_draco_mesh_compression, then "
                "required): positions in --position-bits, normals in --normal-bits (default 10), UVs in --uv-bits (default 12), colours 8, weights and tangents 12");
  app->add_option("--position-bits", options.position_bits, "With -q or --draco: bits per position coordinate (default 14)")
      ->check(CLI::Range(1, 16));
  app->add_option("--normal-bits", options.normal_bits,
                  "With -q, --cc or --draco: bits per normal and tangent component, 8 to 16, as gltfpack -vn (default 8; "
                  "10 in Draco). Above 8, -q stores shorts: 12 bits are within 0.03 degrees, against the bytes' 0.4")
      ->check(CLI::Range(8, 16));
  app->add_option("--uv-bits", options.uv_bits,
                  "With -q or --draco: bits per UV component, 1 to 16, as gltfpack -vt (default 16; 12 in Draco). Below 16, -q "
                  "puts every textured UV set on a box (KHR_texture_transform): fewer bytes under -c")
      ->check(CLI::Range(1, 16));
  app->add_option("--anim-error", options.animation_error,
                  "With -q: how far a reduced animation curve may move what it animates, as a fraction of the scene's "
                  "extent (default 2^-12 = 0.000244; 0 keeps every key a curve needs exactly)")
      ->check(CLI::Range(0.0, 1.0));
}

void GeometryFile::forget_lod_facts(const std::vector<bool>& changed) {
  if (!as_scene_) return;
  std::vector<bool> stale;  // per glTF mesh
  for (size_t i = 0; i < scene_.primitives.size(); ++i) {
    const uint32_t m = scene_.primitives[i].gltf_mesh;
    if (m >= stale.size()) stale.resize(size_t(m) + 1, false);
    if (changed[i]) stale[m] = true;
  }
  const auto draws_stale = [&](const Node& node) { return node.mesh >= 0 && size_t(node.mesh) < stale.size() && stale[size_t(node.mesh)]; };
  for (Node& node : scene_.nodes)
    if (draws_stale(node)) erase_extras(node, {"lodkit"});
  drop_geomorphs(scene_, draws_stale);
}

void drop_geomorphs(Scene& scene, const std::function<bool(const Node&)>& which) {
  // Per glTF mesh: the index of lod's geomorph among its morph targets (after the source's blend
  // shapes).
  std::map<uint32_t, uint32_t> geomorph;
  for (Node& node : scene.nodes) {
    if (node.mesh < 0 || !which(node)) continue;
    int64_t target = 0;  // (a malformed entry: no target survives)
    if (!node.extras_json.empty()) {
      const nlohmann::json extras = nlohmann::json::parse(node.extras_json);
      if (extras.is_object() && extras.contains("LODKIT_geomorph") && extras["LODKIT_geomorph"].is_object()) {
        const nlohmann::json& index = extras["LODKIT_geomorph"].value("target", nlohmann::json());
        if (index.is_number_unsigned() && index.get<uint64_t>() < UINT32_MAX) target = index.get<int64_t>();
      }
    }
    if (erase_extras(node, {"LODKIT_geomorph"})) geomorph[uint32_t(node.mesh)] = uint32_t(target);
  }
  for (Primitive& p : scene.primitives)
    if (const auto it = geomorph.find(p.gltf_mesh); it != geomorph.end()) p.source_target_count = it->second;
}

std::vector<uint32_t> weld_duplicates(Mesh& mesh, std::span<const uint32_t> classes) {
  WeldResult r = weld(mesh, {.vertex_classes = classes});
  if (r.output_vertices == r.input_vertices) return {};
  std::vector<uint32_t> first(r.output_vertices, UINT32_MAX);
  for (uint32_t v = 0; v < r.remap.size(); ++v)
    if (first[r.remap[v]] == UINT32_MAX) first[r.remap[v]] = v;
  mesh = std::move(r.mesh);
  return first;
}

bool erase_extras(Node& node, std::initializer_list<const char*> members) {
  if (node.extras_json.empty()) return false;
  nlohmann::json extras = nlohmann::json::parse(node.extras_json);
  if (!extras.is_object()) return false;
  bool erased = false;
  for (const char* member : members) erased = extras.erase(member) > 0 || erased;
  node.extras_json = extras.dump();  // "{}", not "": an empty text would keep the source's extras
  return erased;
}

void GeometryFile::renumbered(size_t i, const std::vector<uint32_t>& source) {
  if (!as_scene_) return;
  std::vector<uint32_t>& map = scene_.primitives[i].source_vertices;
  std::vector<std::array<float, 3>>& weights = scene_.primitives[i].source_weights;
  if (map.empty() || source.empty()) {
    map = source;
    weights.clear();
  } else if (!weights.empty()) {  // blends, renumbered
    std::vector<uint32_t> composed(3 * source.size());
    std::vector<std::array<float, 3>> reweighed(source.size());
    for (size_t v = 0; v < source.size(); ++v) {
      for (size_t k = 0; k < 3; ++k) composed[3 * v + k] = map[3 * size_t(source[v]) + k];
      reweighed[v] = weights[source[v]];
    }
    map = std::move(composed), weights = std::move(reweighed);
  } else {
    std::vector<uint32_t> composed(source.size());
    for (size_t v = 0; v < source.size(); ++v) composed[v] = map[source[v]];
    map = std::move(composed);
  }
}

void blend_sources(Primitive& p, const std::vector<VertexBlend>& blends) {
  if (!p.source_weights.empty()) throw_internal("blend_sources: blends of blends");
  std::vector<uint32_t> map;
  map.reserve(3 * blends.size());
  for (const VertexBlend& b : blends) {
    for (const uint32_t v : b.vertex) map.push_back(p.source_vertices.empty() ? v : p.source_vertices[v]);
    p.source_weights.push_back(b.weight);
  }
  p.source_vertices = std::move(map);
}

void GeometryFile::renumbered(size_t i, const std::vector<VertexBlend>& blends) {
  if (as_scene_) blend_sources(scene_.primitives[i], blends);
}

std::vector<uint32_t> GeometryFile::vertex_classes(size_t i) const {
  return as_scene_ ? source_vertex_classes(scene_, i) : std::vector<uint32_t>{};
}

std::vector<std::vector<size_t>> GeometryFile::joint_groups() const {
  if (!as_scene_) return {{0}};
  // Primitives with and without influences stay apart: a join would make some up (join_members).
  std::vector<std::vector<size_t>> groups;
  std::map<std::pair<uint32_t, uint32_t>, size_t> group_of;  // (glTF mesh, first influence set) -> group
  for (size_t i = 0; i < scene_.primitives.size(); ++i) {
    const Primitive& p = scene_.primitives[i];
    const uint32_t influences = p.mesh.joints.empty() && p.mesh.weights.empty() ? 0 : 1;
    const auto [it, added] = group_of.try_emplace({p.gltf_mesh, influences}, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(i);
  }
  return groups;
}

Joined join_members(std::span<const Mesh* const> members) {
  Joined j;
  j.offsets = {0};
  for (const Mesh* m : members) j.layouts.push_back(stream_layout(*m));
  if (members.size() == 1) {
    j.alone = members[0];
    j.offsets.push_back(uint32_t(members[0]->vertex_count()));
    return j;
  }
  Scene scene;  // no nodes: flatten takes each primitive once, untransformed, in order
  for (size_t k = 0; k < members.size(); ++k) {
    Primitive p;
    p.mesh = *members[k];
    p.material = int32_t(k);
    j.offsets.push_back(j.offsets.back() + uint32_t(p.mesh.vertex_count()));
    scene.primitives.push_back(std::move(p));
  }
  j.joined = flatten(scene, {.fill_streams = true});
  return j;
}

std::vector<Member> split_members(const Joined& j, Mesh mesh, std::vector<uint32_t> origin, std::vector<uint32_t> successor) {
  const std::vector<uint32_t>& offsets = j.offsets;
  if (offsets.size() < 2) throw_internal("split_members: no members");
  std::vector<Member> members(offsets.size() - 1);
  if (members.size() == 1) {
    members[0] = {std::move(mesh), std::move(origin), std::move(successor), {}};
    members[0].vertices.resize(members[0].mesh.vertex_count());
    std::iota(members[0].vertices.begin(), members[0].vertices.end(), 0u);
    return members;
  }
  // A joined vertex may be in several parts: a restored form's face normals are welded again, and
  // coincident corners of two members with the same values become one vertex (two primitives
  // drawing one flat quad). Each part's indices are set while it is at hand, then cleared.
  std::vector<uint32_t> index(mesh.vertex_count(), ~0u);  // joined vertex -> its index in the part at hand
  if (!successor.empty())
    for (size_t k = 0; k < members.size(); ++k) members[k].successor.assign(offsets[k + 1] - offsets[k], ~0u);
  for (MaterialPart& part : split_by_material(mesh)) {
    const size_t k = size_t(part.material) - 1;
    if (part.material == 0 || k >= members.size())
      throw_internal("split_members: a joined mesh's part has material id " + std::to_string(part.material));
    members[k].mesh = std::move(part.mesh);
    keep_streams(members[k].mesh, j.layouts[k]);
    members[k].vertices = part.vertices;
    for (uint32_t i = 0; i < part.vertices.size(); ++i) {
      const uint32_t v = part.vertices[i];
      index[v] = i;
      if (origin.empty()) continue;
      // Wedges continue within their material, so a member's vertex comes from its own input.
      const uint32_t from = origin[v];
      if (from < offsets[k] || from >= offsets[k + 1]) throw_internal("split_members: a joined mesh's vertex continues another member's");
      members[k].origin.push_back(from - offsets[k]);
    }
    // Its own part's vertex (a wedge relinked across a material border is none).
    if (!successor.empty())
      for (uint32_t v = offsets[k]; v < offsets[k + 1]; ++v)
        if (successor[v] != ~0u) members[k].successor[v - offsets[k]] = index[successor[v]];
    for (const uint32_t v : part.vertices) index[v] = ~0u;
  }
  return members;
}

Command register_convert(CLI::App& root) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* app = root.add_subcommand("convert", "Convert a mesh between OBJ, PLY, OFF, STL, glTF and GLB");
  app->add_option("input", options->input, "Input mesh file")->required();
  app->add_option("output", options->output, "Output mesh file; the format follows the extension");
  app->add_option("-o,--output", options->output_flag, "Output mesh file (same as the second argument)");
  app->add_flag("--ascii", options->ascii, "Write PLY and STL as text instead of binary");
  add_gltf_output_flags(app, options->gltf);
  app->add_flag("--force", options->force, "Allow writing over the input file");
  app->add_flag("--json", options->json, "Print a machine-readable report on stdout");
  return {app, [options] {
            ConvertOptions& o = *options;
            if (!o.output_flag.empty()) {
              if (!o.output.empty()) throw_usage("give the output once, either as OUTPUT or -o OUTPUT");
              o.output = o.output_flag;
            }
            if (o.output.empty()) throw_usage("convert needs an output file: lodkit convert IN OUT");
            format_from_path(o.input);
            format_from_path(o.output);
            check_output(o.input, o.output, o.force);
            check_gltf_output_flags(o.gltf, o.output);
            // glTF to glTF goes through the scene (GeometryFile), so everything lodkit does not
            // change is kept; any other pair converts the (flattened) mesh, keeping its vertex order
            // and material ids.
            auto start = std::chrono::steady_clock::now();
            const GeometryFile file(o.input, o.output, o.force);
            double load_seconds = seconds_since(start);
            size_t vertices = 0, triangles = 0;
            for (const Mesh* m : file.meshes) {
              validate(*m, o.input);
              vertices += m->vertex_count();
              triangles += m->triangle_count();
            }
            // STL and a glTF written from a mesh hold triangles only: the points would be lost.
            // (glTF to glTF keeps points and lines as they were; OBJ, PLY and OFF keep the vertices.)
            const FileFormat out_format = format_from_path(o.output);
            if (!(is_gltf(o.input) && is_gltf(o.output)) && (out_format == FileFormat::stl || is_gltf(o.output)))
              require_triangles(file.meshes, o.input, o.output + " would be empty (OBJ, PLY and OFF keep the vertices)");
            start = std::chrono::steady_clock::now();
            WriteOptions write_options = o.gltf;
            write_options.binary = !o.ascii;
            const WriteReport written = file.write(o.output, write_options);
            double write_seconds = seconds_since(start);
            if (o.json) {
              nlohmann::json j = {{"input", o.input}, {"output", o.output}, {"vertices", vertices},
                                  {"triangles", triangles}, {"load_seconds", load_seconds},
                                  {"write_seconds", write_seconds}};
              add_write_report(j, written, write_options);
              fmt::print("{}\n", j.dump(2));
            } else {
              fmt::print("{:<8}{:>12}{:>12}{:>10}  {}\n", "step", "triangles", "vertices", "time", "file");
              fmt::print("{:<8}{:>12}{:>12}{:>9.3f}s  {}\n", "read", triangles, vertices, load_seconds, o.input);
              fmt::print("{:<8}{:>12}{:>12}{:>9.3f}s  {} ({} bytes)\n", "write", triangles, vertices, write_seconds, o.output,
                         written.bytes);
              fmt::print("{}", draco_line(written, write_options));
            }
            return 0;
          }};
}

}  // namespace lod::cli
