// libFuzzer harness for the glTF reader (.gltf JSON and .glb, told apart by the "glTF" magic).
// read_gltf runs with an empty base_dir, so only data: URIs and the GLB BIN chunk may supply
// buffers: an accepted document whose buffers name an external URI is a bug (it read a file, or
// silently dropped a buffer). Then every primitive must validate, flatten() must give a valid mesh,
// and write_gltf (.glb in a per-process temporary folder) -> read_gltf must give back the same
// primitives (minus those without a triangle, which the writer drops), positions bit for bit, and
// every node shown or hidden as it was; so must the same scene with every primitive's vertices
// renumbered (Primitive::source_vertices) and every node's visibility flipped,
// written with EXT_meshopt_compression (triangles up to the codec's rotations; the scene itself also
// with KHR_meshopt_compression at vertex codec version 1), and both must give
// the same vertex classes (source_vertex_classes) and morph targets (source_morph_targets). Written
// quantized (KHR_mesh_quantization), it must read back with the same vertices and triangles; with
// Draco (the reversed copy), with its triangles and positions within a quantization step, and
// Draco on the grid, with its triangles. erase_nodes on the nodes that draw nothing must keep what
// the scene draws and renumber every reference (check_erase_nodes).
// The shared oracle lives in fuzz_common.h.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <unordered_map>
#include <vector>

#include "fuzz_common.h"
#include "lodkit/optimize.h"

namespace {

using namespace lod;
using namespace lod::fuzz;

// The JSON text of a .gltf, or the JSON chunk of a .glb (empty if the GLB header is unreadable).
std::span<const uint8_t> json_text(std::span<const uint8_t> input) {
  if (input.size() < 4 || std::memcmp(input.data(), "glTF", 4) != 0) return input;
  if (input.size() < 20) return {};
  uint32_t length = 0;
  std::memcpy(&length, input.data() + 12, 4);
  if (length > input.size() - 20) return {};
  return input.subspan(20, length);
}

// The first buffer URI that is neither absent (GLB BIN chunk) nor a data: URI; empty if none.
std::string external_buffer_uri(std::span<const uint8_t> input) {
  const std::span<const uint8_t> text = json_text(input);
  const nlohmann::json doc = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (!doc.is_object() || !doc.contains("buffers") || !doc["buffers"].is_array()) return {};
  for (const nlohmann::json& buffer : doc["buffers"]) {
    if (!buffer.is_object() || !buffer.contains("uri") || !buffer["uri"].is_string()) continue;
    const std::string& uri = buffer["uri"].get_ref<const std::string&>();
    if (!uri.starts_with("data:")) return uri.empty() ? std::string("\"\"") : uri;
  }
  return {};
}

// A folder of our own for the round-trip file, removed when the process exits normally. Folders
// left by processes that crashed or were killed are swept when the next one starts.
class ScratchFolder {
 public:
  ScratchFolder() {
    std::error_code ec;
    const std::filesystem::path shm = "/dev/shm";
    const std::filesystem::path parent = std::filesystem::is_directory(shm, ec) ? shm : std::filesystem::temp_directory_path();
    const std::string prefix = "lodkit-fuzz-gltf-";
    for (const auto& entry : std::filesystem::directory_iterator(parent, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.starts_with(prefix) && !std::filesystem::exists("/proc/" + name.substr(prefix.size()), ec))
        std::filesystem::remove_all(entry.path(), ec);
    }
    path_ = parent / (prefix + std::to_string(getpid()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

size_t total_vertices(const Scene& scene) {
  size_t n = 0;
  for (const Primitive& p : scene.primitives) n += p.mesh.vertex_count();
  return n;
}

// Instancing (nodes and GPU instances) multiplies the vertices: flatten only scenes whose worst
// case stays small.
bool small_when_flat(const Scene& scene) {
  size_t placements = 1;
  for (const Node& node : scene.nodes) placements += std::max<size_t>(1, node.gpu_instances.size());
  return total_vertices(scene) * placements <= 10 * max_round_trip_vertices;
}

void check_flatten(const Scene& scene) {
  if (!small_when_flat(scene)) return;
  // flatten may refuse a scene whose node transforms overflow float, but only as bad input.
  const std::optional<Mesh> flat = run_step("gltf flatten", true, [&] { return flatten(scene); });
  if (flat) check_mesh(*flat, "gltf flatten");
  // With the streams some instance has filled in for the others (lod's and simplify's joins): a
  // valid mesh too, flatten's vertices and triangles with at least its streams.
  const std::optional<Mesh> filled = run_step("gltf flatten fill_streams", true, [&] { return flatten(scene, {.fill_streams = true}); });
  if (filled) check_mesh(*filled, "gltf flatten fill_streams");
  if (flat && filled &&
      (filled->positions != flat->positions || filled->indices != flat->indices || (stream_layout(*flat) & ~stream_layout(*filled)) != 0))
    fail("flatten fill_streams", "not flatten's vertices and triangles with at least its streams");
  // Its morph targets (the morphing nodes' in turn): one displacement per flattened vertex, each
  // node's first target in order.
  const FlatMorphTargets morph = *run_step("gltf flatten_morph_targets", false, [&] { return flatten_morph_targets(scene); });
  if (morph.first.size() != morph.nodes.size() || !std::is_sorted(morph.first.begin(), morph.first.end()) ||
      (!morph.first.empty() && morph.first.back() >= morph.targets.size()))
    fail("flatten_morph_targets", "the nodes' first targets are not in order within the targets");
  for (const MorphTarget& t : morph.targets)
    if (flat && (t.positions.size() != flat->vertex_count() || (!t.normals.empty() && t.normals.size() != flat->vertex_count())))
      fail("flatten_morph_targets", "a target's displacements are not one per flattened vertex");
}

// Each triangle as its lexicographically smallest rotation (winding kept; unique even when a
// degenerate triangle repeats its smallest index): the meshopt index codec may start a triangle at
// another corner.
Mesh canonical_rotations(Mesh mesh) {
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    const std::array<uint32_t, 3> best = std::min({std::array<uint32_t, 3>{a, b, c}, {b, c, a}, {c, a, b}});
    std::copy(best.begin(), best.end(), mesh.indices.begin() + ptrdiff_t(t));
  }
  return mesh;
}

// `quantize` (WriteOptions::quantize): positions may move to the grid, so only the topology must
// come back (vertex count, triangles), with valid streams.
// `draco` (WriteOptions::draco): every triangle comes back but those with a repeated corner, which
// Edgebreaker drops, and every position within a 14-bit quantization step of the input's bounds
// (unless quantized too: they are then in grid steps).
// `options.meshopt_khr` too: KHR_meshopt_compression, vertex streams at codec version 1.
void check_round_trip(const Scene& scene, const std::string& stage, const WriteOptions& options) {
  const bool compress = options.meshopt_compression, quantize = options.quantize, draco = options.draco;
  static const ScratchFolder folder;
  const std::filesystem::path file = folder.path() / "round-trip.glb";
  run_step(stage + ": write", false, [&] {
    write_gltf(scene, file, options);
    return true;
  });
  const std::optional<std::vector<uint8_t>> bytes = run_step(stage + ": load", false, [&] {
    const FileBytes f = read_file_bytes(file);
    return std::vector<uint8_t>(f.begin(), f.end());
  });
  std::error_code ec;
  std::filesystem::remove(file, ec);
  const std::optional<Scene> again =
      run_step(stage + ": read back", false, [&] { return read_gltf(*bytes, "round-trip.glb", {}, checked_read_options(stage)); });
  // Every node comes back, shown or hidden as it was (KHR_node_visibility). Quantized, a node whose
  // mesh takes the position grid may hand it to a new child node with the grid's transform.
  if (quantize ? again->nodes.size() < scene.nodes.size() : again->nodes.size() != scene.nodes.size())
    fail(stage, "node count changed from " + std::to_string(scene.nodes.size()) + " to " + std::to_string(again->nodes.size()));
  for (size_t n = 0; n < scene.nodes.size(); ++n)
    if (again->nodes[n].visible != scene.nodes[n].visible) fail(stage, "node " + std::to_string(n) + "'s visibility changed");
  // The writer drops triangle primitives left without a triangle (glTF forbids empty accessors);
  // every other primitive must come back, in order.
  std::vector<size_t> kept;
  for (size_t p = 0; p < scene.primitives.size(); ++p)
    if (!scene.primitives[p].mesh.indices.empty()) kept.push_back(p);
  if (again->primitives.size() != kept.size())
    fail(stage, "primitive count changed from " + std::to_string(kept.size()) + " (with triangles) to " +
                    std::to_string(again->primitives.size()));
  for (size_t k = 0; k < kept.size(); ++k) {
    const Primitive &before = scene.primitives[kept[k]], &after = again->primitives[k];
    const std::string where = stage + ": primitive " + std::to_string(kept[k]);
    check_mesh(after.mesh, where + " read back");
    if (after.material != before.material)
      fail(where, "material changed from " + std::to_string(before.material) + " to " + std::to_string(after.material));
    if (draco) {
      const size_t triangles = before.mesh.triangle_count();
      size_t repeated = 0;
      for (size_t t = 0; t < triangles; ++t) {
        const uint32_t* c = &before.mesh.indices[3 * t];
        repeated += c[0] == c[1] || c[1] == c[2] || c[2] == c[0];
      }
      if (after.mesh.triangle_count() > triangles || after.mesh.triangle_count() + repeated < triangles)
        fail(where, "Draco: " + std::to_string(after.mesh.triangle_count()) + " triangles read back of " + std::to_string(triangles) +
                        " (" + std::to_string(repeated) + " with a repeated corner)");
      float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
      for (const float3& p : before.mesh.positions)
        for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], (&p.x)[c]), hi[c] = std::max(hi[c], (&p.x)[c]);
      double extent = 0;
      for (int c = 0; c < 3; ++c) extent = std::max(extent, double(hi[c]) - double(lo[c]));
      const double margin = extent / 16383.0 + 1e-30;
      if (quantize) continue;  // (positions on -q's grid read back in grid steps)
      for (const float3& p : after.mesh.positions)
        for (int c = 0; c < 3; ++c)
          if (!(double((&p.x)[c]) >= lo[c] - margin && double((&p.x)[c]) <= hi[c] + margin))
            fail(where, "Draco: a position read back outside the input's bounds by more than a quantization step");
      continue;
    }
    if (quantize) {
      // (compressed too: the index codec may start a triangle at another corner)
      const bool same_triangles = compress ? canonical_rotations(after.mesh).indices == canonical_rotations(before.mesh).indices
                                           : after.mesh.indices == before.mesh.indices;
      if (after.mesh.vertex_count() != before.mesh.vertex_count() || !same_triangles)
        fail(where, "quantized, the vertex count or the triangles changed");
      continue;
    }
    if (compress) require_same_geometry(canonical_rotations(before.mesh), canonical_rotations(after.mesh), Exactness::bits, where);
    else require_same_geometry(before.mesh, after.mesh, Exactness::bits, where);
  }
}

// Every primitive's vertices in reverse order, Primitive::source_vertices saying so: the writer then
// gathers the streams lodkit does not model (morph targets, other attributes) from the source's
// accessors, whatever their types, strides and sparse parts. Every node's visibility is flipped too,
// for the writer to hide shown nodes and show hidden ones.
Scene reversed(Scene scene) {
  for (Node& node : scene.nodes) node.visible = !node.visible;
  for (Primitive& p : scene.primitives) {
    const size_t n = p.mesh.vertex_count();
    std::vector<uint32_t> remap(n);
    for (size_t v = 0; v < n; ++v) remap[v] = uint32_t(n - 1 - v), p.source_vertices.push_back(uint32_t(n - 1 - v));
    p.mesh = remap_vertices(p.mesh, remap, n);
  }
  return scene;
}

// lod::source_vertex_classes on the scene and on its reversed copy: one class per vertex (or none)
// and the same partition of the source's vertices, read through source_vertices.
void check_vertex_classes(const Scene& scene, const Scene& reversed_scene) {
  const std::string stage = "gltf vertex classes";
  for (size_t p = 0; p < scene.primitives.size(); ++p) {
    const std::string where = stage + ": primitive " + std::to_string(p);
    const auto a = run_step(where, false, [&] { return source_vertex_classes(scene, p); });
    const auto b = run_step(where + ", vertices reversed", false, [&] { return source_vertex_classes(reversed_scene, p); });
    const size_t n = scene.primitives[p].mesh.vertex_count();
    if (a->size() != b->size() || (!a->empty() && a->size() != n))
      fail(where, std::to_string(a->size()) + " and " + std::to_string(b->size()) + " classes for " + std::to_string(n) + " vertices");
    std::unordered_map<uint32_t, uint32_t> a_to_b, b_to_a;
    for (size_t v = 0; v < a->size(); ++v) {
      const uint32_t x = (*a)[v], y = (*b)[n - 1 - v];
      if (a_to_b.try_emplace(x, y).first->second != y || b_to_a.try_emplace(y, x).first->second != x)
        fail(where, "vertex " + std::to_string(v) + "'s class differs once its vertices are reversed");
    }
  }
}

// lod::source_morph_targets on an accepted document (the reader checked the targets' types and
// counts): one entry per vertex, the same through the reversed copy's source_vertices.
void check_morph_targets(const Scene& scene, const Scene& reversed_scene) {
  const std::string stage = "gltf morph targets";
  for (size_t p = 0; p < scene.primitives.size(); ++p) {
    const std::string where = stage + ": primitive " + std::to_string(p);
    const auto a = run_step(where, false, [&] { return source_morph_targets(scene, p); });
    const auto b = run_step(where + ", vertices reversed", false, [&] { return source_morph_targets(reversed_scene, p); });
    const size_t n = scene.primitives[p].mesh.vertex_count();
    if (a->size() != b->size()) fail(where, "a different target count once its vertices are reversed");
    for (size_t k = 0; k < a->size(); ++k) {
      const MorphTarget &x = (*a)[k], &y = (*b)[k];
      if (x.positions.size() != n) fail(where, "target " + std::to_string(k) + " does not have one entry per vertex");
      for (const auto stream : morph_streams) {
        const std::vector<float3> &xs = x.*stream, &ys = y.*stream;
        if ((!xs.empty() && xs.size() != n) || xs.size() != ys.size())
          fail(where, "target " + std::to_string(k) + " does not have one entry per vertex");
        for (size_t v = 0; v < xs.size(); ++v)
          if (std::memcmp(&xs[v], &ys[n - 1 - v], sizeof(float3)))
            fail(where, "target " + std::to_string(k) + " differs at vertex " + std::to_string(v) + " once its vertices are reversed");
      }
    }
  }
}

}  // namespace

// erase_nodes, asked to erase every node that draws no mesh (lod erases only such nodes): the
// nodes it keeps are the rest and those something needs, renumbered within the new count wherever
// they are named; what the nodes draw is what they drew (flatten, bit for bit, in the same order);
// and the document written back round-trips.
void check_erase_nodes(const Scene& scene) {
  const std::string stage = "erase_nodes";
  std::vector<bool> erase(scene.nodes.size());
  for (size_t n = 0; n < scene.nodes.size(); ++n) erase[n] = scene.nodes[n].mesh < 0;
  Scene erased = scene;
  const std::vector<int32_t> remap = *run_step(stage, false, [&] { return erase_nodes(erased, erase); });
  if (remap.size() != scene.nodes.size()) fail(stage, "the renumbering is not one entry per node");
  int32_t next = 0;
  for (size_t n = 0; n < remap.size(); ++n) {
    if (remap[n] < 0 && !erase[n]) fail(stage, "node " + std::to_string(n) + " was erased unasked");
    if (remap[n] >= 0 && remap[n] != next++) fail(stage, "the kept nodes are not numbered in order");
  }
  if (size_t(next) != erased.nodes.size()) fail(stage, "the scene does not have the kept nodes");
  const auto named = [&](int32_t n, const char* what) {
    if (n < -1 || n >= next) fail(stage, std::string(what) + " names node " + std::to_string(n) + " of " + std::to_string(next));
  };
  for (const Node& node : erased.nodes) {
    named(node.parent, "a parent");
    for (const int32_t c : node.children) named(c, "a child");
    for (const int32_t id : node.lod_ids) named(id, "an MSFT_lod id");
  }
  for (const int32_t r : erased.roots) named(r, "a root");
  for (const Skin& skin : erased.skins)
    for (const int32_t j : skin.joints) named(j, "a joint");
  for (const Animation& clip : erased.animations)
    for (const AnimationChannel& ch : clip.channels) named(ch.node, "a channel");
  // (Left without nodes or roots, flatten draws every primitive once, as for a scene without
  // nodes: not what the nodes drew.)
  const bool drawn_by_nodes = !erased.nodes.empty() && !erased.roots.empty();
  const std::optional<Mesh> before =
      drawn_by_nodes && small_when_flat(scene) ? run_step("gltf flatten", true, [&] { return flatten(scene); }) : std::nullopt;
  if (before) require_same_geometry(*before, *run_step(stage + ": flatten", false, [&] { return flatten(erased); }), Exactness::bits, stage);
  check_round_trip(erased, "gltf round trip, meshless nodes erased", {});
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> input(data, size);
  const std::string stage = "gltf read";
  const std::optional<Scene> scene =
      run_step(stage, true, [&] { return read_gltf(input, "fuzz.gltf", {}, checked_read_options(stage)); });
  if (!scene) return 0;
  if (const std::string uri = external_buffer_uri(input); !uri.empty())
    fail(stage, "accepted a buffer with the external URI '" + uri.substr(0, 200) + "' although base_dir is empty");
  for (size_t p = 0; p < scene->primitives.size(); ++p) check_mesh(scene->primitives[p].mesh, stage + ": primitive " + std::to_string(p));
  check_flatten(*scene);
  if (total_vertices(*scene) > max_round_trip_vertices) return 0;
  check_round_trip(*scene, "gltf round trip", {});
  check_erase_nodes(*scene);
  const Scene backwards = reversed(*scene);
  check_round_trip(backwards, "gltf round trip, vertices reversed, meshopt-compressed", {.meshopt_compression = true});
  check_round_trip(*scene, "gltf round trip, KHR meshopt version 1", {.meshopt_compression = true, .meshopt_khr = true});
  check_round_trip(*scene, "gltf round trip, quantized", {.quantize = true});
  // --cc: -c -q with the key filters, the octahedral normals and the strip-walk order's selection;
  // the reversed copy with 12-bit normals (shorts, and the filter on them) and 12-bit UVs (every
  // textured set on a box).
  check_round_trip(*scene, "gltf round trip, --cc", {.meshopt_compression = true, .quantize = true, .compress_more = true});
  check_round_trip(backwards, "gltf round trip, vertices reversed, --cc --normal-bits 12 --uv-bits 12",
                   {.meshopt_compression = true, .quantize = true, .compress_more = true, .normal_bits = 12, .uv_bits = 12});
  check_round_trip(backwards, "gltf round trip, vertices reversed, Draco", {.draco = true});
  check_round_trip(backwards, "gltf round trip, vertices reversed, Draco on the -q grid", {.quantize = true, .draco = true});
  check_vertex_classes(*scene, backwards);
  check_morph_targets(*scene, backwards);
  return 0;
}
