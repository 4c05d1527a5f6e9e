// lodkit convert IN OUT: any supported format to any other. A glTF written from a glTF keeps
// everything but the geometry as it was.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <cmath>
#include <map>
#include <optional>
#include <memory>
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
  bool force = false;
  bool json = false;
};

}  // namespace

void check_not_input(const std::string& input, const std::string& output, bool force) {
  std::error_code ec;
  if (!force && std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec))
    throw_usage(output + ": refusing to overwrite the input file (use --force)");
}

namespace {
bool is_gltf(const std::string& path) {
  const FileFormat format = format_from_path(path);
  return format == FileFormat::gltf || format == FileFormat::glb;
}
}  // namespace

GeometryFile::GeometryFile(const std::string& input, const std::string& output)
    : as_scene_(is_gltf(input) && is_gltf(output)) {
  {
    ProgressBar bar("loading");
    if (as_scene_) scene_ = read_scene(input, bar.read_options());
    else mesh_ = read_mesh(input, bar.read_options());
  }
  if (as_scene_)
    for (Primitive& p : scene_.primitives) meshes.push_back(&p.mesh);
  else
    meshes.push_back(&mesh_);
}

void GeometryFile::write(const std::string& output) const {
  if (as_scene_) write_scene(scene_, output);
  else write_mesh(mesh_, output);
}

void GeometryFile::forget_lod_facts(const std::vector<bool>& changed) {
  if (!as_scene_) return;
  std::vector<bool> stale;  // per glTF mesh
  for (size_t i = 0; i < scene_.primitives.size(); ++i) {
    const uint32_t m = scene_.primitives[i].gltf_mesh;
    if (m >= stale.size()) stale.resize(size_t(m) + 1, false);
    if (changed[i]) stale[m] = true;
  }
  for (Node& node : scene_.nodes)
    if (node.mesh >= 0 && size_t(node.mesh) < stale.size() && stale[size_t(node.mesh)])
      erase_extras(node, {"lodkit", "LODKIT_geomorph"});
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

bool flat_shaded(const Mesh& mesh) {
  if (mesh.normals.empty() || !mesh.tangents.empty()) return false;  // (tangents would need the same care)
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float3& n = mesh.normals[mesh.indices[3 * t]];
    if (!(mesh.normals[mesh.indices[3 * t + 1]] == n) || !(mesh.normals[mesh.indices[3 * t + 2]] == n)) return false;
  }
  // Some position with two normals: else the normals cost the simplifier nothing.
  return position_ids(mesh).count < weld(mesh).output_vertices;
}

Mesh smooth_copy(const Mesh& mesh) {
  Mesh smooth = mesh;
  smooth.normals.clear();
  weld_duplicates(smooth, {});
  return smooth;
}

void refacet(Mesh& mesh) {
  Mesh split;
  split.material_names = mesh.material_names, split.group_names = mesh.group_names;
  split.materials = mesh.materials, split.groups = mesh.groups;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const float3 &a = mesh.positions[mesh.indices[3 * t]], &b = mesh.positions[mesh.indices[3 * t + 1]],
                 &c = mesh.positions[mesh.indices[3 * t + 2]];
    const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
    const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double length = std::sqrt(nx * nx + ny * ny + nz * nz);
    const float3 n = length > 0 ? float3{float(nx / length), float(ny / length), float(nz / length)} : float3{0, 0, 1};
    for (int k = 0; k < 3; ++k) {
      split.indices.push_back(uint32_t(split.positions.size()));
      append_vertex(split, mesh, mesh.indices[3 * t + k]);
      split.normals.push_back(n);
    }
  }
  mesh = weld(split).mesh;  // corners of one face normal (and the same other streams) shared again
}

namespace {
// A position's bits mixed into 64 (+0 and -0 alike, as position ids have them).
uint64_t position_hash(const float3& p) {
  uint64_t h = 0;
  for (const float f : {p.x, p.y, p.z}) {
    uint32_t bits = 0;
    const float g = f == 0.0f ? 0.0f : f;
    std::memcpy(&bits, &g, 4);
    h = (h ^ bits) * 0x9E3779B97F4A7C15ull;
    h ^= h >> 29;
  }
  return h;
}

// Per triangle: the index of its reversed twin among the triangles (each twin paired once, the
// earlier of a pair first), or -1. Position ids decide: the twin's corners are separate vertices.
std::vector<int64_t> twins(const Mesh& mesh) {
  const PositionIds ids = position_ids(mesh);
  std::map<std::array<uint32_t, 3>, std::vector<uint32_t>> open;  // a rotation of the corners -> unpaired triangles
  const auto rotated = [](std::array<uint32_t, 3> c) {  // the rotation starting at the smallest id
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    return c;
  };
  std::vector<int64_t> twin(mesh.triangle_count(), -1);
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t a = ids.id[mesh.indices[3 * t]], b = ids.id[mesh.indices[3 * t + 1]], c = ids.id[mesh.indices[3 * t + 2]];
    const auto reversed = open.find(rotated({a, c, b}));
    if (reversed != open.end() && !reversed->second.empty()) {
      twin[t] = reversed->second.back(), twin[reversed->second.back()] = t;
      reversed->second.pop_back();
    } else {
      open[rotated({a, b, c})].push_back(t);
    }
  }
  return twin;
}
}  // namespace

std::optional<Mesh> double_sided_fronts(const Mesh& mesh) {
  if (mesh.triangle_count() == 0 || mesh.triangle_count() % 2) return std::nullopt;
  // A quick filter before the exact pairing (a map over every triangle, a second on a 832k-triangle
  // mesh): each triangle adds the hash of its corners' positions in sorted order, with the sign of
  // the sort's permutation. A twin has the same sorted corners and the other sign, so a double-sided
  // mesh sums to zero; anything else almost surely does not.
  uint64_t sum = 0;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    uint64_t h[3];
    for (int k = 0; k < 3; ++k) h[k] = position_hash(mesh.positions[mesh.indices[3 * t + k]]);
    bool odd = false;
    const auto order = [&](int i, int j) {
      if (h[i] > h[j]) std::swap(h[i], h[j]), odd = !odd;
    };
    order(0, 1), order(1, 2), order(0, 1);
    const uint64_t key = (h[0] * 0x9E3779B97F4A7C15ull) ^ (h[1] * 0xC2B2AE3D27D4EB4Full + (h[1] >> 29)) ^ (h[2] * 0x165667B19E3779F9ull + (h[2] >> 31));
    sum += odd ? key : 0 - key;
  }
  if (sum != 0) return std::nullopt;
  const std::vector<int64_t> twin = twins(mesh);
  if (std::any_of(twin.begin(), twin.end(), [](int64_t t) { return t < 0; })) return std::nullopt;
  Mesh front = mesh;
  front.indices.clear(), front.materials.clear(), front.groups.clear();
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (size_t(twin[t]) < t) continue;  // the back of an earlier front
    front.indices.insert(front.indices.end(), mesh.indices.begin() + ptrdiff_t(3 * t), mesh.indices.begin() + ptrdiff_t(3 * t + 3));
    if (!mesh.materials.empty()) front.materials.push_back(mesh.materials[t]);
    if (!mesh.groups.empty()) front.groups.push_back(mesh.groups[t]);
  }
  return front;
}

void add_back_faces(Mesh& mesh) {
  const size_t triangles = mesh.triangle_count(), vertices = mesh.vertex_count();
  for (uint32_t v = 0; v < vertices; ++v) {
    append_vertex(mesh, mesh, v);
    if (!mesh.normals.empty()) {
      float3& n = mesh.normals.back();
      n = {-n.x, -n.y, -n.z};
    }
    if (!mesh.tangents.empty()) {
      float4& t = mesh.tangents.back();
      t.w = -t.w;  // u runs the same way on the back, whose normal is turned: the bitangent's sign flips
    }
  }
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
    mesh.indices.insert(mesh.indices.end(), {uint32_t(vertices) + a, uint32_t(vertices) + c, uint32_t(vertices) + b});
    if (!mesh.materials.empty()) mesh.materials.push_back(mesh.materials[t]);
    if (!mesh.groups.empty()) mesh.groups.push_back(mesh.groups[t]);
  }
  if (mesh.normals.empty()) weld_duplicates(mesh, {});  // without normals the twins' vertices are the fronts'
}

void erase_extras(Node& node, std::initializer_list<const char*> members) {
  if (node.extras_json.empty()) return;
  nlohmann::json extras = nlohmann::json::parse(node.extras_json);
  if (!extras.is_object()) return;
  for (const char* member : members) extras.erase(member);
  node.extras_json = extras.dump();  // "{}", not "": an empty text would keep the source's extras
}

void GeometryFile::renumbered(size_t i, const std::vector<uint32_t>& source) {
  if (!as_scene_) return;
  std::vector<uint32_t>& map = scene_.primitives[i].source_vertices;
  if (map.empty()) {
    map = source;
  } else {
    std::vector<uint32_t> composed(source.size());
    for (size_t v = 0; v < source.size(); ++v) composed[v] = map[source[v]];
    map = std::move(composed);
  }
}

std::vector<uint32_t> GeometryFile::vertex_classes(size_t i) const {
  return as_scene_ ? source_vertex_classes(scene_, i) : std::vector<uint32_t>{};
}

std::vector<std::vector<size_t>> GeometryFile::joint_groups() const {
  if (!as_scene_) return {{0}};
  // Primitives with other streams stay apart: joining them would drop or invent values (see flatten).
  const auto layout = [](const Mesh& m) {
    uint32_t bits = 0, bit = 1;
    for (const bool empty : {m.normals.empty(), m.tangents.empty(), m.uvs[0].empty(), m.uvs[1].empty(),
                               m.uvs[2].empty(), m.uvs[3].empty(), m.colors.empty(), m.joints.empty(),
                               m.weights.empty(), m.joints1.empty(), m.weights1.empty()}) {
      if (!empty) bits |= bit;
      bit <<= 1;
    }
    return bits;
  };
  std::vector<std::vector<size_t>> groups;
  std::map<std::pair<uint32_t, uint32_t>, size_t> group_of;  // (glTF mesh, layout) -> group
  for (size_t i = 0; i < scene_.primitives.size(); ++i) {
    const Primitive& p = scene_.primitives[i];
    const auto [it, added] = group_of.try_emplace({p.gltf_mesh, layout(p.mesh)}, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(i);
  }
  return groups;
}

Command register_convert(CLI::App& root) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* app = root.add_subcommand("convert", "Convert a mesh between OBJ, PLY, OFF, STL, glTF and GLB");
  app->add_option("input", options->input, "Input mesh file")->required();
  app->add_option("output", options->output, "Output mesh file; the format follows the extension");
  app->add_option("-o,--output", options->output_flag, "Output mesh file (same as the second argument)");
  app->add_flag("--ascii", options->ascii, "Write PLY and STL as text instead of binary");
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
            check_not_input(o.input, o.output, o.force);
            // glTF to glTF goes through the scene, so everything lodkit does not change is kept; any
            // other pair converts the (flattened) mesh, keeping its vertex order and material ids.
            const auto is_gltf = [](const std::string& f) {
              const FileFormat format = format_from_path(f);
              return format == FileFormat::gltf || format == FileFormat::glb;
            };
            const bool as_scene = is_gltf(o.input) && is_gltf(o.output);
            auto start = std::chrono::steady_clock::now();
            Scene scene;
            Mesh mesh;
            {
              ProgressBar bar("loading");
              if (as_scene) scene = read_scene(o.input, bar.read_options());
              else mesh = read_mesh(o.input, bar.read_options());
            }
            double load_seconds = seconds_since(start);
            size_t vertices = 0, triangles = 0;
            auto count = [&](const Mesh& m) {
              validate(m, o.input);
              vertices += m.vertex_count();
              triangles += m.triangle_count();
            };
            if (as_scene) for (const Primitive& p : scene.primitives) count(p.mesh);
            else count(mesh);
            start = std::chrono::steady_clock::now();
            if (as_scene) write_scene(scene, o.output, {.binary = !o.ascii});
            else write_mesh(mesh, o.output, {.binary = !o.ascii});
            double write_seconds = seconds_since(start);
            if (o.json) {
              nlohmann::json j = {{"input", o.input}, {"output", o.output}, {"vertices", vertices},
                                  {"triangles", triangles}, {"load_seconds", load_seconds},
                                  {"write_seconds", write_seconds}};
              fmt::print("{}\n", j.dump(2));
            } else {
              fmt::print("{:<8}{:>12}{:>12}{:>10}  {}\n", "step", "triangles", "vertices", "time", "file");
              fmt::print("{:<8}{:>12}{:>12}{:>9.3f}s  {}\n", "read", triangles, vertices, load_seconds, o.input);
              fmt::print("{:<8}{:>12}{:>12}{:>9.3f}s  {}\n", "write", triangles, vertices, write_seconds, o.output);
            }
            return 0;
          }};
}

}  // namespace lod::cli
