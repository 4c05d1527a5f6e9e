// lodkit lod IN -o OUT.glb: the main job. A chain of LODs with certified error bounds, written as a
// glTF whose first node carries the MSFT_lod extension (the coarser levels' nodes) and
// MSFT_screencoverage in its extras, so three.js / Babylon-style loaders switch levels by
// themselves; every level's error and switch distance are in its node's extras.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "lodkit/skin.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct LodCommand {
  std::string input, output, ratios, errors, metric = "cqem", attributes, lpm;
  uint32_t levels = 0;  // (read only when given: LodOptions has the default)
  float error_px = 1.0f, screen_height = 1080.0f, fov_degrees = 60.0f;
  bool from_input = false, morph = false, shared = false, json = false, force = false;
  WriteOptions gltf;  // -c, -q
  unsigned threads = 0;
  std::string skin_mode = "multipose";
  uint32_t poses = 16;
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

// A blend of per-vertex displacements.
float3 blend(const std::vector<float3>& values, const VertexBlend& b) {
  float3 out;
  for (size_t k = 0; k < 3; ++k) {
    const float3& v = values[b.vertex[k]];
    out.x += b.weight[k] * v.x, out.y += b.weight[k] * v.y, out.z += b.weight[k] * v.z;
  }
  return out;
}

// Morph targets at blends of their vertices (lod::vertex_blends): a level's, from its input's.
std::vector<MorphTarget> blended_targets(const std::vector<MorphTarget>& targets, const std::vector<VertexBlend>& at) {
  std::vector<MorphTarget> out(targets.size());
  for (size_t k = 0; k < targets.size(); ++k)
    for (const auto stream : morph_streams)
      if (!(targets[k].*stream).empty())
        for (const VertexBlend& b : at) (out[k].*stream).push_back(blend(targets[k].*stream, b));
  return out;
}

// Per vertex, a class shared exactly by the vertices whose displacements are all equal (bitwise), for
// a weld that must keep the others apart (WeldOptions::vertex_classes); empty without targets.
std::vector<uint32_t> displacement_classes(const std::vector<MorphTarget>& targets) {
  if (targets.empty()) return {};
  std::unordered_map<std::string, uint32_t> ids;  // displacements' bytes -> class
  std::vector<uint32_t> classes(targets[0].positions.size());
  std::string key;
  for (size_t v = 0; v < classes.size(); ++v) {
    key.clear();
    for (const MorphTarget& t : targets)
      for (const auto stream : morph_streams)
        if (!(t.*stream).empty()) key.append(reinterpret_cast<const char*>(&(t.*stream)[v]), sizeof(float3));
    classes[v] = ids.try_emplace(key, uint32_t(ids.size())).first->second;
  }
  return classes;
}

// The target on other vertices: vertex i takes `from[i]`'s displacements (a weld's first source
// vertices, a level part's vertices).
MorphTarget renumbered(const MorphTarget& t, const std::vector<uint32_t>& from) {
  MorphTarget out;
  for (const auto stream : morph_streams)
    if (!(t.*stream).empty())
      for (const uint32_t v : from) (out.*stream).push_back((t.*stream)[v]);
  return out;
}

// A static chain's morph targets: per level, the flattened input's at the level's vertices, driven
// by the source nodes' weights in turn. With one vertex buffer (LodChain::shared), one set at its vertices,
// which every level takes.
struct LevelTargets {
  std::vector<std::vector<MorphTarget>> levels;
  std::vector<int32_t> nodes;
  const std::vector<MorphTarget>& at(size_t level) const {
    static const std::vector<MorphTarget> none;
    return levels.size() == 1 ? levels[0] : level < levels.size() ? levels[level] : none;
  }
};

// The geomorph as a glTF morph target: the offset taking `fine`'s vertex v onto `coarse`'s vertex w,
// into entry `at` of `t` (positions, and normals where `t` has them).
void set_geomorph_offset(MorphTarget& t, size_t at, const Mesh& fine, uint32_t v, const Mesh& coarse, uint32_t w) {
  const float3 &a = fine.positions[v], &b = coarse.positions[w];
  t.positions[at] = {b.x - a.x, b.y - a.y, b.z - a.z};
  if (!t.normals.empty()) {
    const float3 &n = fine.normals[v], &m = coarse.normals[w];
    t.normals[at] = {m.x - n.x, m.y - n.y, m.z - n.z};
  }
}

MorphTarget zero_target(size_t vertices, bool normals) {
  MorphTarget t;
  t.positions.assign(vertices, float3{});
  if (normals) t.normals.assign(vertices, float3{});
  return t;
}

// Level i's geomorph over the one vertex buffer (subset placement: every level's vertex is one of
// the buffer's): each vertex of level i moves onto the buffer vertex of its target in level i + 1;
// the others, which level i does not draw, stay.
MorphTarget shared_geomorph(const LodChain& chain, size_t i) {
  const SharedVertices& buffer = chain.shared;
  const LodLevel &fine = chain.levels[i], &coarse = chain.levels[i + 1];
  std::vector<uint32_t> slot;  // input vertex -> buffer vertex
  for (uint32_t k = 0; k < buffer.vertex_origin.size(); ++k) {
    if (buffer.vertex_origin[k] >= slot.size()) slot.resize(size_t(buffer.vertex_origin[k]) + 1, ~0u);
    slot[buffer.vertex_origin[k]] = k;
  }
  MorphTarget t = zero_target(buffer.vertices.vertex_count(), !buffer.vertices.normals.empty());
  for (uint32_t v = 0; v < fine.mesh.vertex_count(); ++v) {
    const uint32_t a = slot[fine.vertex_origin[v]], b = slot[coarse.vertex_origin[chain.morphs[i].target[v]]];
    set_geomorph_offset(t, a, buffer.vertices, a, buffer.vertices, b);
  }
  return t;
}

// A node's name in reports and level names: its own, or "node N".
std::string node_label(const std::vector<Node>& nodes, size_t n) {
  return nodes[n].name.empty() ? fmt::format("node {}", n) : nodes[n].name;
}

struct ChainReport {
  std::string node;  // the skinned node's name, or those of the nodes drawing a separate mesh; empty for the static chain
  size_t instances = 0;  // a separate mesh's when instanced (EXT_mesh_gpu_instancing); 0 otherwise
  bool animated = false;  // a separate mesh that a node in motion draws, or a rigid group in motion
  bool switched = false;  // one below a visibility switch (KHR_node_visibility)
  size_t group_meshes = 0;  // a rigid group's: the nodes drawing its meshes (`node` names its frame)
  LodChain chain;
  std::vector<double> distances, coverage;
};

// What a level's node says about it (extras "lodkit"; lodkit render --sheet and lodkit info read it).
nlohmann::json level_facts(const ChainReport& r, size_t i) {
  const LodLevel& level = r.chain.levels[i];
  nlohmann::json facts = {{"level", i},
                          {"triangles", level.mesh.triangle_count()},
                          {"error", level.error},
                          {"error_bound", level.error_bound},
                          {"relative_error", level.relative_error},
                          {"switch_distance", r.distances[i]}};
  if (!r.chain.shared.prefix.empty()) facts["vertex_prefix"] = r.chain.shared.prefix[i];
  return facts;
}

// Drops the triangles of the source's meshes that chains replace, those `dropped` says (meshes past
// the source's are new levels).
void drop_chained_meshes(Scene& scene, const std::function<bool(uint32_t)>& dropped) {
  const auto chained = [&](int32_t mesh) { return mesh >= 0 && uint32_t(mesh) < scene.gltf_mesh_count && dropped(uint32_t(mesh)); };
  // Those left keep the primitives whose vertices they share, renumbered.
  std::vector<int32_t> index(scene.primitives.size(), -1);
  int32_t kept_count = 0;
  for (size_t i = 0; i < scene.primitives.size(); ++i)
    if (!chained(int32_t(scene.primitives[i].gltf_mesh))) index[i] = kept_count++;
  for (Primitive& p : scene.primitives)
    if (p.shares_vertices_with >= 0) p.shares_vertices_with = index[size_t(p.shares_vertices_with)];
  std::erase_if(scene.primitives, [&](const Primitive& p) { return chained(int32_t(p.gltf_mesh)); });
  // Their nodes no longer draw their triangles (an earlier chain's levels among them): what lodkit
  // said about them, and an earlier chain's MSFT_lod, would describe what is gone.
  for (Node& node : scene.nodes)
    if (chained(node.mesh)) {
      node.lod_ids.clear();
      erase_extras(node, {"lodkit", "LODKIT_geomorph", "MSFT_screencoverage"});
    }
}

// The skinned nodes an earlier run made coarser levels of another (listed in its MSFT_lod): not
// characters of their own, so that lod on its own output replaces their levels rather than chaining
// them too. Returns their glTF meshes (those no other skinned node draws) and takes their
// primitives out of `skinned`.
std::set<int32_t> earlier_skinned_levels(const Scene& scene, std::vector<SkinnedPrimitive>& skinned) {
  std::set<uint32_t> levels;
  for (const Node& node : scene.nodes)
    for (const int32_t id : node.lod_ids)
      if (id >= 0 && size_t(id) < scene.nodes.size()) levels.insert(uint32_t(id));
  std::set<int32_t> meshes, characters;
  for (const SkinnedPrimitive& sp : skinned)
    (levels.count(sp.node) ? meshes : characters).insert(int32_t(scene.primitives[sp.primitive].gltf_mesh));
  std::erase_if(skinned, [&](const SkinnedPrimitive& sp) { return levels.count(sp.node) > 0; });
  std::erase_if(meshes, [&](int32_t m) { return characters.count(m) > 0; });
  return meshes;
}

// The nodes of an earlier run's chains (lod on its own output): the first levels it made (an
// MSFT_lod and its extras) and every coarser level an MSFT_lod lists (a chain of the input's own
// among them). New chains replace the meshes they draw; they go, rather than stay as empty nodes
// (lod::erase_nodes).
std::vector<bool> earlier_chain_nodes(const Scene& scene) {
  std::vector<bool> earlier(scene.nodes.size(), false);
  for (const Node& node : scene.nodes) {
    for (const int32_t id : node.lod_ids)
      if (id >= 0 && size_t(id) < earlier.size()) earlier[size_t(id)] = true;
  }
  for (size_t n = 0; n < scene.nodes.size(); ++n) {
    const Node& node = scene.nodes[n];
    if (node.lod_ids.empty() || node.extras_json.empty()) continue;
    const nlohmann::json extras = nlohmann::json::parse(node.extras_json);
    earlier[n] = earlier[n] || (extras.is_object() && extras.contains("lodkit"));
  }
  return earlier;
}

// Whether node `n` is a first level an earlier run made (`earlier`) where that run put it
// (untransformed, childless): lod on its own output puts the new chain in its place rather than
// below it, so that chains do not nest. The node goes, unless it lends the chain its morph weights,
// which only a node of the document can hold: then it becomes the new first level (ChainPlace::first).
bool earlier_level_in_place(const Scene& scene, const std::vector<bool>& earlier, int32_t n) {
  const Node& node = scene.nodes[size_t(n)];
  const bool placed = node.has_matrix || node.translation != float3{} || node.rotation != float4{0, 0, 0, 1} ||
                      node.scale != float3{1, 1, 1} || !node.children.empty();
  return earlier[size_t(n)] && !placed;
}

// Where the levels of a separate mesh that node `n` draws go: below `n`, or below its parent when it
// is an earlier run's first level in place, as that run put them.
int32_t levels_parent(const Scene& scene, const std::vector<bool>& earlier, int32_t n) {
  const int32_t parent = scene.nodes[size_t(n)].parent;
  return parent >= 0 && earlier_level_in_place(scene, earlier, n) ? parent : n;
}

// The document static chains go into: the glTF `source` (flattened into the chains' inputs, so
// material id k + 1 is its material k) without its triangles, so that materials, textures and
// everything else stay and its nodes remain, without those meshes; or a new document with the
// materials (names and looks) of the input, `input`.
Scene chain_document(const Scene* source, const Mesh& input) {
  Scene scene;
  if (!source) {
    scene.material_names = input.material_names;
    scene.material_looks = input.material_looks;
    return scene;
  }
  scene = *source;
  drop_chained_meshes(scene, [](uint32_t) { return true; });
  return scene;
}

// Where a chain's nodes go: named `prefix`LODi, the first under `parent` (a new root when -1), each
// drawn once per instance of `instances` (a chain in its mesh's own space, for a node drawing that
// mesh), with the morph weights of node `weights_of` (-1: the chain's own morphing nodes'). With
// `meshes` set, the levels' glTF meshes are those an earlier add_chain of the chain returned. With
// `first` set, that node (an earlier run's first level, in place, lending its weights: it keeps
// them, its clips, name and place) is the first level, and the others take its weights.
struct ChainPlace {
  std::string prefix;
  int32_t parent = -1;
  std::vector<Node::GpuInstance> instances;
  int32_t weights_of = -1;
  std::optional<uint32_t> meshes;
  int32_t first = -1;
};

// Appends a chain to a chain_document: one new glTF mesh per level with a primitive per material
// (unless `place.meshes` names them), and one node per level, the first listing the others
// (MSFT_lod). Each material's primitives keep the vertex streams `streams` gives its id (all when
// it has none; with one vertex buffer, all: the materials share it). Returns the first level's glTF mesh.
uint32_t add_chain(Scene& scene, const ChainReport& r, const LevelTargets& targets, const std::vector<uint32_t>& streams,
                   const ChainPlace& place) {
  const LodChain& chain = r.chain;
  uint32_t mesh_base = scene.source ? scene.gltf_mesh_count : 0;
  for (const Primitive& p : scene.primitives) mesh_base = std::max(mesh_base, p.gltf_mesh + 1);
  if (place.meshes) mesh_base = *place.meshes;
  const int32_t node_base = int32_t(scene.nodes.size());
  const size_t first_primitive = scene.primitives.size();
  const auto material = [&](const Mesh& level, uint32_t id) {
    if (level.materials.empty()) return scene.source || level.material_names.empty() ? -1 : 0;
    return scene.source ? int32_t(id) - 1 : int32_t(id);
  };
  for (size_t i = 0; i < chain.levels.size() && !place.meshes; ++i) {
    const Mesh& level = chain.levels[i].mesh;
    uint32_t next_primitive = 0;  // of level i's glTF mesh
    const auto add = [&](Primitive prim, uint32_t id) {
      prim.material = material(level, id);
      prim.gltf_mesh = mesh_base + uint32_t(i);
      prim.gltf_primitive = next_primitive++;
      scene.primitives.push_back(std::move(prim));
    };
    if (!chain.shared.indices.empty()) {
      // One vertex buffer for the chain; level i's indices use only its first prefix[i] vertices.
      // Level i's triangles are its mesh's, in order, so they keep its material ids.
      const std::vector<uint32_t>& indices = chain.shared.indices[i];
      std::vector<MorphTarget> level_targets = targets.at(i);  // on the buffer: exact, as subset placement moves no vertex
      if (i < chain.morphs.size()) level_targets.push_back(shared_geomorph(chain, i));
      for (const MaterialPart& part : split_by_material(level)) {
        Primitive prim;
        prim.mesh = chain.shared.vertices;
        prim.mesh.materials.clear(), prim.mesh.groups.clear();
        copy_id_tables(prim.mesh, Mesh{});
        prim.mesh.indices.clear();
        prim.targets = level_targets;
        for (size_t t = 0; t < level.triangle_count(); ++t)
          if (level.material(t) == part.material)
            prim.mesh.indices.insert(prim.mesh.indices.end(), indices.begin() + ptrdiff_t(3 * t), indices.begin() + ptrdiff_t(3 * t + 3));
        if (scene.primitives.size() > first_primitive) prim.shares_vertices_with = int32_t(first_primitive);
        add(std::move(prim), part.material);
      }
      continue;
    }
    for (MaterialPart& part : split_by_material(level)) {
      Primitive prim;
      prim.mesh = std::move(part.mesh);
      if (part.material < streams.size()) keep_streams(prim.mesh, streams[part.material]);
      for (const MorphTarget& t : targets.at(i)) prim.targets.push_back(renumbered(t, part.vertices));
      if (i < chain.morphs.size()) {
        // The geomorph as a glTF morph target, after the input's: weight t gives (1 - t) P + t P_target,
        // positions and normals, in any viewer; LODKIT_geomorph in the extras says which and where it
        // leads. (The writer gives it weight 0 in the input's weights and clips.)
        const Mesh& coarse = chain.levels[i + 1].mesh;
        MorphTarget target = zero_target(part.vertices.size(), !level.normals.empty() && !coarse.normals.empty());
        for (size_t k = 0; k < part.vertices.size(); ++k)
          set_geomorph_offset(target, k, level, part.vertices[k], coarse, chain.morphs[i].target[part.vertices[k]]);
        prim.targets.push_back(std::move(target));
      }
      add(std::move(prim), part.material);
    }
  }
  const bool reuse = place.first >= 0;
  const int32_t weights_of = reuse ? place.first : place.weights_of;
  const auto level_node = [&](size_t i) { return i == 0 && reuse ? place.first : node_base + int32_t(i) - int32_t(reuse); };
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    Node node;
    node.name = fmt::format("{}LOD{}", place.prefix, i);
    node.mesh = int32_t(mesh_base + i);
    node.gpu_instances = place.instances;
    nlohmann::json extras = {{"lodkit", level_facts(r, i)}};
    if (i < chain.morphs.size()) extras["LODKIT_geomorph"] = {{"target", targets.at(i).size()}, {"to_node", level_node(i + 1)}};
    if (!targets.at(i).empty()) node.morph_weights_of = weights_of >= 0 ? std::vector<int32_t>{weights_of} : targets.nodes;
    if (i == 0) {
      for (size_t k = 1; k < chain.levels.size(); ++k) node.lod_ids.push_back(level_node(k));
      extras["MSFT_screencoverage"] = r.coverage;
      node.parent = place.parent;
    }
    node.extras_json = extras.dump();
    if (i == 0 && reuse) {
      Node& old = scene.nodes[size_t(place.first)];
      old.mesh = node.mesh, old.gpu_instances = std::move(node.gpu_instances), old.lod_ids = std::move(node.lod_ids);
      old.extras_json = std::move(node.extras_json);
      continue;
    }
    scene.nodes.push_back(std::move(node));
  }
  if (place.parent < 0 && !reuse) scene.roots.push_back(node_base);
  return mesh_base;
}

// Several morphing nodes: the levels take their weights in turn, one channel per clip
// (lod::concatenate_weights, which the writer applies). Why a clip cannot be merged exactly, or "".
std::string unmergeable_weights(const Scene& scene, const FlatMorphTargets& morph) {
  std::vector<WeightsSource> sources(morph.nodes.size());
  for (size_t k = 0; k < sources.size(); ++k)
    sources[k].rest.assign((k + 1 < morph.first.size() ? morph.first[k + 1] : morph.targets.size()) - morph.first[k], 0.0f);
  for (const Animation& clip : scene.animations) {
    bool any = false;
    for (size_t k = 0; k < sources.size(); ++k) {
      sources[k].channel = weights_channel(clip, morph.nodes[k]);
      any = any || sources[k].channel;
    }
    if (any && !concatenate_weights(sources))
      return fmt::format("clip '{}' drives the {} morphing nodes' weights with curves one channel cannot hold exactly "
                         "(step with smooth ones)", clip.name, morph.nodes.size());
  }
  return "";
}


// Switch distances: where a level's error bound shrinks to error_px on screen. Screen coverage
// (MSFT_screencoverage): the bounding sphere's projected height over the screen height at the
// distance where the next level takes over; 0 after the last (never culled).
void set_switching(ChainReport& r, const LodCommand& o) {
  const double fov = o.fov_degrees * M_PI / 180.0;
  const double radius = 0.5 * r.chain.diagonal;
  for (const LodLevel& level : r.chain.levels)
    r.distances.push_back(switch_distance(level.error_bound, o.error_px, o.screen_height, fov));
  for (size_t i = 0; i < r.chain.levels.size(); ++i) {
    const double d = i + 1 < r.chain.levels.size() ? r.distances[i + 1] : 0.0;
    r.coverage.push_back(d > 0 ? std::min(1.0, radius / (d * std::tan(fov / 2))) : 0.0);
  }
}

nlohmann::json levels_json(const ChainReport& r) {
  nlohmann::json levels = nlohmann::json::array();
  for (size_t i = 0; i < r.chain.levels.size(); ++i) {
    const LodLevel& l = r.chain.levels[i];
    levels.push_back({{"level", i}, {"triangles", l.mesh.triangle_count()}, {"vertices", l.mesh.vertex_count()},
                      {"error", l.error}, {"error_bound", l.error_bound}, {"relative_error", l.relative_error},
                      {"engine_error", l.engine_error}, {"switch_distance", r.distances[i]},
                      {"screen_coverage", r.coverage[i]}});
  }
  return levels;
}

SkinMode parse_skin_mode(const std::string& name) {
  for (const SkinMode m : {SkinMode::houle, SkinMode::subset, SkinMode::multipose})
    if (name == skin_mode_name(m)) return m;
  throw_usage("--skin-mode: '" + name + "' is not houle, subset or multipose");
}

// A skinned glTF mesh instance: the primitives a skinned node draws (one per material, all with
// its skin), simplified together as one mesh (join_members: member k is material id k + 1), so that
// the borders between their materials stay closed; level i of each goes into one new glTF mesh. A
// glTF mesh drawn by several skinned nodes (a crowd's skeletons, each its own skin) gets one chain,
// simplified in the first node's skin, whose level meshes each of them draws with its own skin.
struct SkinnedGroup {
  uint32_t node = 0, skin = 0;
  std::vector<uint32_t> primitives;  // into Scene::primitives, in order
  std::vector<uint32_t> also;        // the other nodes drawing the glTF mesh, in order
};

std::vector<SkinnedGroup> skinned_groups(const Scene& scene, const std::vector<SkinnedPrimitive>& skinned) {
  std::vector<SkinnedGroup> groups;
  std::map<uint32_t, size_t> group_of;  // glTF mesh -> its group
  for (const SkinnedPrimitive& sp : skinned) {
    const Primitive& p = scene.primitives[sp.primitive];
    const auto [it, added] = group_of.try_emplace(p.gltf_mesh, groups.size());
    if (added) groups.push_back({sp.node, sp.skin, {}, {}});
    SkinnedGroup& g = groups[it->second];
    if (g.node == sp.node) g.primitives.push_back(sp.primitive);
    else if (std::find(g.also.begin(), g.also.end(), sp.node) == g.also.end()) g.also.push_back(sp.node);
  }
  return groups;
}

// A group's members joined (a copy, or the one primitive's mesh itself).
Joined join_group(const Scene& scene, const SkinnedGroup& g) {
  std::vector<const Mesh*> members;
  for (const uint32_t p : g.primitives) members.push_back(&scene.primitives[p].mesh);
  return join_members(members);
}

// The skins a group is drawn with: its first node's, then those of the others (a crowd), each once.
std::vector<uint32_t> group_skins(const Scene& scene, const SkinnedGroup& g) {
  std::vector<uint32_t> skins{g.skin};
  for (const uint32_t n : g.also)
    if (const int32_t s = scene.nodes[n].skin; s >= 0 && std::find(skins.begin(), skins.end(), uint32_t(s)) == skins.end())
      skins.push_back(uint32_t(s));
  return skins;
}

// The skinned simplifier's options for a group's skins: their poses as the mode needs them. Houle's
// one pose is the first skin's; multipose takes `pose_count` of every skin, so that a crowd's chain
// holds in the poses of each skeleton drawing it (another clip, other proportions), their joints
// cut to the fewest any skin has (the mesh uses no more).
SkinSimplifyOptions skin_options(const Scene& scene, const std::vector<uint32_t>& skins, SkinMode mode, uint32_t pose_count) {
  SkinSimplifyOptions so;
  so.mode = mode;
  if (mode == SkinMode::houle) {
    so.poses = {joint_matrices(scene, skins[0], world_matrices(scene, mid_range_pose(scene, skins[0])))};
  } else if (mode == SkinMode::multipose) {
    for (const uint32_t skin : skins) {
      std::vector<std::vector<mat4>> poses = sample_poses(scene, skin, pose_count);
      so.poses.insert(so.poses.end(), std::make_move_iterator(poses.begin()), std::make_move_iterator(poses.end()));
    }
    size_t joints = SIZE_MAX;
    for (const std::vector<mat4>& pose : so.poses) joints = std::min(joints, pose.size());
    for (std::vector<mat4>& pose : so.poses) pose.resize(joints);
  }
  return so;
}

// The progressive mesh of a skinned group, from its input down to `triangles`. A multi-pose record
// replays on the input with its weights normalised (lod::simplify_skinned), a subset one on the
// input itself.
ProgressiveMesh skinned_progressive_mesh(const Scene& scene, const SkinnedGroup& g, SkinMode mode, uint32_t pose_count,
                                         SimplifyOptions simplify, uint64_t triangles) {
  SkinSimplifyOptions so = skin_options(scene, group_skins(scene, g), mode, pose_count);
  so.simplify = std::move(simplify);
  so.simplify.target_triangles = std::max<uint64_t>(1, triangles);
  so.simplify.record = true;
  Mesh input = join_group(scene, g).mesh();
  SimplifyResult r = simplify_skinned(input, so);
  if (mode == SkinMode::multipose) normalize_influences(input);
  return ProgressiveMesh(std::move(input), std::move(r.record));
}

// The skinned chains. The groups of the same skins (a character's meshes, usually) share their
// simplifier, so they are built in one batch (lod::build_lod_chains: small ones side by side); each
// chain is what it would be alone.
std::vector<ChainReport> build_skinned(const Scene& scene, const std::vector<SkinnedGroup>& groups, SkinMode mode,
                                       uint32_t pose_count, const LodOptions& base,
                                       const std::function<void(double)>& progress) {
  std::map<std::vector<uint32_t>, std::vector<size_t>> by_skin;  // skins -> their groups, in order
  uint64_t total = 0, done = 0;                                  // triangles
  for (size_t k = 0; k < groups.size(); ++k) {
    by_skin[group_skins(scene, groups[k])].push_back(k);
    for (const uint32_t p : groups[k].primitives) total += scene.primitives[p].mesh.triangle_count();
  }
  std::vector<ChainReport> reports(groups.size());
  for (const auto& [skins, batch] : by_skin) {
    std::vector<Joined> joined;
    joined.reserve(batch.size());  // (no reallocation: the pointers below stay valid)
    std::vector<const Mesh*> meshes;
    uint64_t triangles = 0;
    for (const size_t k : batch) {
      for (const uint32_t p : groups[k].primitives) validate(scene.primitives[p].mesh, scene.name);
      joined.push_back(join_group(scene, groups[k]));
      meshes.push_back(&joined.back().mesh());
      triangles += meshes.back()->triangle_count();
    }
    LodOptions options = base;
    options.simplifier = skinned_simplifier(skin_options(scene, skins, mode, pose_count));
    options.progress = [&](double f) { progress((double(done) + f * double(triangles)) / double(std::max<uint64_t>(1, total))); };
    std::vector<LodChain> chains = build_lod_chains(meshes, options);
    for (size_t i = 0; i < batch.size(); ++i) {
      const SkinnedGroup& g = groups[batch[i]];
      std::vector<std::string> names{node_label(scene.nodes, g.node)};
      for (const uint32_t n : g.also) names.push_back(node_label(scene.nodes, n));
      reports[batch[i]].node = fmt::format("{}", fmt::join(names, ", "));
      reports[batch[i]].chain = std::move(chains[i]);
    }
    done += triangles;
  }
  return reports;
}

// A skinned chain's levels in its group's members: levels[i][k] is level i's primitive of member k
// (its mesh, the source streams it gathers, its morph targets; the caller places it). Level 0's
// start as the members' source primitives, the others with their materials only.
std::vector<std::vector<Primitive>> member_levels(const Scene& scene, const SkinnedGroup& g, const LodChain& chain) {
  const size_t members = g.primitives.size();
  std::vector<std::vector<MorphTarget>> targets(members);
  std::vector<std::vector<Primitive>> levels(chain.levels.size(), std::vector<Primitive>(members));
  for (size_t k = 0; k < members; ++k) {
    const Primitive& source = scene.primitives[g.primitives[k]];
    targets[k] = source_morph_targets(scene, g.primitives[k]);
    levels[0][k] = source;
    for (size_t i = 1; i < levels.size(); ++i) levels[i][k].material = source.material;
  }
  const Joined joined = join_group(scene, g);
  const std::vector<uint32_t>& offsets = joined.offsets;
  const SharedVertices& buffer = chain.shared;
  if (!buffer.indices.empty()) {
    // One vertex buffer (subset placement). Member k's: the buffer's vertices from its own input, in
    // the buffer's order, so that each level still uses a prefix of it; the source's streams and
    // morph targets at them, exact, written once (every level shares level 0's).
    std::vector<Mesh> own(members);
    std::vector<std::vector<uint32_t>> origin(members);
    std::vector<uint32_t> member(buffer.vertex_origin.size()), local(buffer.vertex_origin.size());
    if (members == 1) own[0] = buffer.vertices, own[0].indices.clear();
    for (uint32_t b = 0; b < buffer.vertex_origin.size(); ++b) {
      const uint32_t from = buffer.vertex_origin[b];
      const size_t k = size_t(std::upper_bound(offsets.begin(), offsets.end(), from) - offsets.begin()) - 1;
      if (k >= members) throw_internal("lod: a skinned buffer vertex comes from no member");
      member[b] = uint32_t(k), local[b] = uint32_t(origin[k].size());
      origin[k].push_back(from - offsets[k]);
      if (members > 1) append_vertex(own[k], buffer.vertices, b);
    }
    for (size_t k = 0; k < members; ++k) keep_streams(own[k], joined.layouts[k]);
    for (size_t i = 0; i < levels.size(); ++i) {
      const Mesh& level = chain.levels[i].mesh;
      for (size_t k = 0; k < members; ++k) levels[i][k].mesh = own[k];
      for (size_t t = 0; t < level.triangle_count(); ++t) {
        // Wedges continue within their material: a triangle of member k draws its vertices.
        const size_t k = members == 1 ? 0 : size_t(level.material(t)) - 1;
        for (size_t c = 0; c < 3; ++c) {
          const uint32_t b = buffer.indices[i][3 * t + c];
          if (k >= members || member[b] != k) throw_internal("lod: a skinned level's triangle draws another member's vertex");
          levels[i][k].mesh.indices.push_back(local[b]);
        }
      }
      for (size_t k = 0; k < members; ++k) {
        Primitive& prim = levels[i][k];
        prim.targets.clear();
        for (const MorphTarget& t : targets[k]) prim.targets.push_back(renumbered(t, origin[k]));
        if (i == 0) prim.source_vertices = origin[k], prim.source_weights.clear();
        else prim.shares_vertices_with = int32_t(g.primitives[k]);
      }
    }
    return levels;
  }
  // The coarser levels' morph targets: blended on the joined input, from the members' targets
  // joined (a level's vertex near a material border may lie over the other material's triangles;
  // a stream a member's target lacks displaces nothing there).
  std::vector<MorphTarget> joined_targets(targets[0].size());
  for (size_t t = 0; t < joined_targets.size(); ++t)
    for (const auto stream : morph_streams) {
      bool any = false;
      for (size_t k = 0; k < members; ++k) any = any || (t < targets[k].size() && !(targets[k][t].*stream).empty());
      for (size_t k = 0; k < members && any; ++k) {
        const size_t count = offsets[k + 1] - offsets[k];
        const bool has = t < targets[k].size() && !(targets[k][t].*stream).empty();
        if (has) (joined_targets[t].*stream).insert((joined_targets[t].*stream).end(), (targets[k][t].*stream).begin(), (targets[k][t].*stream).end());
        else (joined_targets[t].*stream).resize((joined_targets[t].*stream).size() + count, float3{});
      }
    }
  for (size_t i = 0; i < levels.size(); ++i) {
    const LodLevel& level = chain.levels[i];
    std::vector<MorphTarget> level_targets;
    if (i > 0 && !joined_targets.empty())
      level_targets = blended_targets(joined_targets, vertex_blends(joined.mesh(), level.vertex_successor, level.mesh));
    std::vector<Member> parts = split_members(joined, level.mesh, level.vertex_origin, level.vertex_successor);
    for (size_t k = 0; k < members; ++k) {
      const Mesh& source = scene.primitives[g.primitives[k]].mesh;
      Primitive& prim = levels[i][k];
      // Level 0 is the source's vertices reordered for the vertex cache, unless it was simplified:
      // its morph targets and other streams follow a reordering, and are interpolated where it
      // moved them (lod::vertex_blends, within the member: they are gathered from its source).
      if (i == 0 && parts[k].mesh.vertex_count() == source.vertex_count()) prim.source_vertices = std::move(parts[k].origin);
      else if (i == 0) blend_sources(prim, vertex_blends(source, parts[k].successor, parts[k].mesh));
      // The coarser levels': the member's streams of the joined level's.
      for (size_t t = 0; t < level_targets.size() && t < targets[k].size(); ++t) {
        MorphTarget& out = prim.targets.emplace_back(renumbered(level_targets[t], parts[k].vertices));
        for (const auto stream : morph_streams)
          if ((targets[k][t].*stream).empty()) (out.*stream).clear();
      }
      prim.mesh = std::move(parts[k].mesh);
    }
  }
  return levels;
}

// The input scene with each skinned group's levels: level 0 replaces its primitives' geometry,
// level i > 0 becomes a new glTF mesh (a primitive per member), drawn for each skinned node drawing
// the group's mesh by a new node with that node's skin, listed in its MSFT_lod. Skeleton, skins,
// animations, materials and everything else of the source are written back unchanged.
Scene skinned_scene(Scene scene, const std::vector<SkinnedGroup>& groups, const std::vector<ChainReport>& reports) {
  uint32_t next_mesh = scene.gltf_mesh_count;  // new meshes come after the source's
  for (size_t gi = 0; gi < groups.size(); ++gi) {
    const SkinnedGroup& g = groups[gi];
    const ChainReport& r = reports[gi];
    std::vector<std::vector<Primitive>> levels = member_levels(scene, g, r.chain);
    // Each level's node takes the skinned node's morph weights and clips (glTF: every primitive of
    // a mesh has the same targets).
    const bool morphs = !source_morph_targets(scene, g.primitives[0]).empty();
    for (size_t k = 0; k < g.primitives.size(); ++k) scene.primitives[g.primitives[k]] = std::move(levels[0][k]);
    std::vector<int32_t> level_meshes(r.chain.levels.size(), -1);
    for (size_t i = 1; i < r.chain.levels.size(); ++i) {
      level_meshes[i] = int32_t(next_mesh++);
      uint32_t next_primitive = 0;
      for (Primitive& prim : levels[i]) {
        if (prim.mesh.indices.empty()) continue;  // (a member collapsed away)
        prim.gltf_mesh = uint32_t(level_meshes[i]), prim.gltf_primitive = next_primitive++;
        scene.primitives.push_back(std::move(prim));
      }
    }
    std::vector<uint32_t> drawers{g.node};
    drawers.insert(drawers.end(), g.also.begin(), g.also.end());
    for (const uint32_t d : drawers) {
      const std::string owner = scene.nodes[d].name;  // a copy: scene.nodes grows below
      // The source node's own extras are kept; its MSFT_lod (an earlier chain's) gives way to this one.
      const std::string& old_extras = scene.nodes[d].extras_json;
      nlohmann::json extras = old_extras.empty() ? nlohmann::json::object() : nlohmann::json::parse(old_extras);
      if (!extras.is_object()) extras = nlohmann::json::object();
      scene.nodes[d].lod_ids.clear();
      extras["MSFT_screencoverage"] = r.coverage;
      // Each level's node says what it is, as in a static chain (lodkit render --sheet reads it).
      extras["lodkit"] = level_facts(r, 0);
      for (size_t i = 1; i < r.chain.levels.size(); ++i) {
        Node node;
        node.name = fmt::format("{}_LOD{}", owner, i);
        node.mesh = level_meshes[i];
        node.skin = scene.nodes[d].skin;
        if (morphs) node.morph_weights_of = {int32_t(d)};
        node.extras_json = nlohmann::json{{"lodkit", level_facts(r, i)}}.dump();
        scene.nodes.push_back(std::move(node));
        scene.nodes[d].lod_ids.push_back(int32_t(scene.nodes.size() - 1));
      }
      scene.nodes[d].extras_json = extras.dump();
    }
  }
  return scene;
}

// A static chain: a mesh (a flattened glTF scene, `scene`, or another file's) simplified level by
// level in its surface form, with the morph targets the scene's nodes drive at each level's vertices.
// prepare_static readies it (in the scene's current view), lod::build_lod_chains builds all of a
// run's chains at once (small ones side by side), finish_static puts the levels in their form.
struct StaticChain {
  ChainReport report;
  LevelTargets targets;
  SurfaceForm form;             // built on the fronts, or without face normals (reported)
  std::string targets_dropped;  // why the input's morph targets are not on the levels, if they are not
  Mesh input;                   // as read (welded where morph targets allow)
  FlatMorphTargets morph;       // the targets to carry to the levels
  std::vector<uint32_t> streams;  // per material id, the vertex streams its levels keep (flatten_streams)
  const Mesh& to_simplify() const { return form.to_simplify(input); }
};

// flatten(scene) keeping every vertex stream a primitive it draws has (flatten would keep only the
// streams all have, so a textured mesh beside a plain one would lose its UVs): the others get
// neutral values (FlattenOptions::fill_streams). `streams` gets, per material id (flatten's
// numbering: the glTF material + 1), the streams all its primitives have: what its levels keep
// (add_chain).
Mesh flatten_streams(const Scene& scene, std::vector<uint32_t>& streams) {
  streams.clear();
  for (const size_t drawn : flattened_primitives(scene)) {
    const Primitive& p = scene.primitives[drawn];
    const size_t id = size_t(std::max(p.material, -1) + 1);
    if (streams.size() <= id) streams.resize(id + 1, ~0u);
    streams[id] &= stream_layout(p.mesh);
  }
  return flatten(scene, {.fill_streams = true});
}

StaticChain prepare_static(Mesh mesh, const Scene* scene, const LodCommand& o) {
  StaticChain out;
  // Morph targets go to every level, interpolated where the vertices moved (with geomorphs, before
  // each level's geomorph target).
  if (scene) out.morph = flatten_morph_targets(*scene);
  if (out.morph.nodes.size() > 1) out.targets_dropped = unmergeable_weights(*scene, out.morph);
  if (!out.targets_dropped.empty()) out.morph.targets.clear();
  // The chain replaces the input's geometry: only the morph targets to carry, so vertices whose
  // displacements differ stay apart.
  const std::vector<uint32_t> first = weld_duplicates(mesh, displacement_classes(out.morph.targets));
  if (!first.empty())
    for (MorphTarget& t : out.morph.targets) t = renumbered(t, first);
  // Flat-shaded: the chain is built without the normals, then each level faceted again (not with
  // geomorphs or one vertex buffer, whose tables follow the vertices). Double-sided likewise: the
  // chain is built on the fronts, and each level gets its backs.
  if (!o.morph && !o.shared) out.form = surface_form(mesh);
  out.input = std::move(mesh);
  return out;
}

void finish_static(StaticChain& out, LodChain built) {
  out.report.chain = std::move(built);
  const LodChain& chain = out.report.chain;
  const std::vector<MorphTarget>& targets = out.morph.targets;
  for (LodLevel& level : out.report.chain.levels) {
    if (out.form.changed()) level.vertex_origin.clear(), restore_form(out.form, level.mesh, level.vertex_successor);
    if (!targets.empty() && chain.shared.indices.empty())
      out.targets.levels.push_back(blended_targets(targets, vertex_blends(out.input, level.vertex_successor, level.mesh)));
  }
  if (!targets.empty() && !chain.shared.indices.empty()) {
    out.targets.levels.emplace_back();
    for (const MorphTarget& t : targets) out.targets.levels[0].push_back(renumbered(t, chain.shared.vertex_origin));
  }
  out.targets.nodes = std::move(out.morph.nodes);
  out.morph = {};
  // The progressive mesh's input: the mesh as simplified.
  if (out.form.changed()) out.input = std::move(out.form.mesh);
}

// A part of a glTF scene that gets a chain of its own, in its own space rather than the static
// chain's:
// - a mesh with triangles and no skin that an instanced node draws (EXT_mesh_gpu_instancing: baking
//   its instances into the static chain would multiply its triangles by the instance count), or
//   that nodes in motion draw (a clip moves them or an ancestor: baked into the static chain at
//   rest, the mesh would no longer follow) or nodes below a visibility switch (KHR_node_visibility:
//   in the static chain, a hidden mesh would show), each of which gets the chain's levels under it;
// - a rigid group: the meshes drawn below one such animated or switching node (the `frame`: a
//   car's body and doors under the root a clip drives) and by no node elsewhere, in the frame's
//   space. One chain for the lot, under the frame, rather than one per mesh: levels as coarse as
//   the group allows, and one switch.
struct SeparatePart {
  std::vector<int32_t> meshes;  // glTF meshes: one, or a rigid group's
  std::vector<int32_t> nodes;   // the nodes that draw them (from the scene's roots)
  int32_t frame = -1;           // a rigid group's animated or switching node
  size_t instances = 0;         // drawn, over those nodes
  bool instanced = false, animated = false, switched = false;
};

std::vector<SeparatePart> separate_parts(const Scene& scene) {
  std::vector<bool> animated(scene.nodes.size(), false);
  for (const Animation& clip : scene.animations)
    for (const AnimationChannel& ch : clip.channels)
      if (ch.path != AnimationPath::weights && ch.node >= 0 && size_t(ch.node) < animated.size()) animated[size_t(ch.node)] = true;
  // Reached from the roots; the frame each goes with: the nearest animated or switching node at or
  // above it (-1: none); in motion (an animated node at or above it) and switched (a switching one).
  struct Reach {
    int32_t frame = -1;
    bool moving = false, switched = false;
  };
  std::vector<bool> reached(scene.nodes.size(), false);
  std::vector<Reach> reach(scene.nodes.size());
  std::vector<std::pair<int32_t, Reach>> stack;
  for (const int32_t r : scene.roots) stack.emplace_back(r, Reach{});
  while (!stack.empty()) {
    const auto [n, above] = stack.back();
    stack.pop_back();
    if (n < 0 || size_t(n) >= scene.nodes.size() || reached[size_t(n)]) continue;
    reached[size_t(n)] = true;
    const bool moves = animated[size_t(n)], switches = scene.nodes[size_t(n)].has_visibility;
    Reach& r = reach[size_t(n)];
    r = {moves || switches ? n : above.frame, above.moving || moves, above.switched || switches};
    for (const int32_t c : scene.nodes[size_t(n)].children) stack.emplace_back(c, r);
  }
  // Per glTF mesh (a map: deterministic order), as its own part, with the frames of the nodes
  // drawing it and whether one of them skins it.
  struct Drawn {
    SeparatePart part;
    std::set<int32_t> frames;
    bool skinned = false;
  };
  std::map<int32_t, Drawn> meshes;
  for (size_t n = 0; n < scene.nodes.size(); ++n) {
    const Node& node = scene.nodes[n];
    if (!reached[n] || node.mesh < 0) continue;
    Drawn& d = meshes[node.mesh];
    SeparatePart& m = d.part;
    m.meshes = {node.mesh};
    m.nodes.push_back(int32_t(n));
    m.instances += std::max<size_t>(1, node.gpu_instances.size());
    m.instanced = m.instanced || !node.gpu_instances.empty();
    m.animated = m.animated || reach[n].moving;
    m.switched = m.switched || reach[n].switched;
    d.frames.insert(reach[n].frame);
    d.skinned = d.skinned || node.skin >= 0;
  }
  std::set<int32_t> with_triangles;
  for (const Primitive& p : scene.primitives)
    if (p.mesh.triangle_count() > 0) with_triangles.insert(int32_t(p.gltf_mesh));
  std::vector<SeparatePart> out;
  std::map<int32_t, SeparatePart> groups;  // by frame
  for (auto& [mesh, d] : meshes) {
    SeparatePart& m = d.part;
    if (!(m.instanced || m.animated || m.switched) || d.skinned || !with_triangles.count(mesh)) continue;
    const std::set<int32_t>& f = d.frames;
    if (m.instanced || f.size() > 1) {
      out.push_back(std::move(m));
      continue;
    }
    SeparatePart& g = groups[*f.begin()];
    g.frame = *f.begin();
    g.animated = g.animated || m.animated, g.switched = g.switched || m.switched;
    g.meshes.push_back(mesh);
    g.nodes.insert(g.nodes.end(), m.nodes.begin(), m.nodes.end());
    g.instances += m.instances;
  }
  // A group of one mesh is that mesh: a chain in its own space under each node drawing it (the
  // levels shared).
  for (auto& [f, g] : groups) {
    if (g.meshes.size() == 1) g.frame = -1;
    out.push_back(std::move(g));
  }
  std::sort(out.begin(), out.end(), [](const SeparatePart& a, const SeparatePart& b) { return a.meshes[0] < b.meshes[0]; });
  return out;
}

}  // namespace

Command register_lod(CLI::App& root) {
  auto o = std::make_shared<LodCommand>();
  CLI::App* app = root.add_subcommand("lod", "Build a LOD chain with error bounds and write it as glTF (MSFT_lod)");
  app->add_option("input", o->input, "Input mesh file")->required();
  app->add_option("-o,--output", o->output, "Output glTF (.glb or .gltf)")->required();
  app->add_option("--levels", o->levels, "Number of levels, halving the triangles each time (default 4)");
  app->add_option("--ratios", o->ratios, "Fractions of the triangles per level, finest first, e.g. 1,0.5,0.25");
  app->add_option("--errors", o->errors, "Per level, a limit on its certified distance to the input (fraction of the diagonal), finest first, e.g. 0,0.001,0.01");
  app->add_option("--error-px", o->error_px, "Pixels of error allowed on screen when switching (default 1)");
  app->add_option("--screen-height", o->screen_height, "Screen height in pixels (default 1080)");
  app->add_option("--fov", o->fov_degrees, "Vertical field of view in degrees (default 60)");
  app->add_flag("--from-input", o->from_input, "Simplify every level from the input, not from the previous level");
  app->add_flag("--morph", o->morph, "Write geomorphs: each level's last morph target (after the input's) moves it onto the next level");
  app->add_flag("--shared-vertices", o->shared,
                "Subset placement and one vertex buffer for all levels (coarser levels use a prefix of it)");
  app->add_option("--metric", o->metric, "edge, qem, cqem (default), memoryless or cmemoryless");
  app->add_option("--attributes", o->attributes, "Attribute weights, e.g. normal=1,uv=1,color=1");
  app->add_option("--skin-mode", o->skin_mode,
                 "Skinned glTF input: houle, subset or multipose (default: quadrics over --poses poses of every clip)");
  app->add_option("--poses", o->poses, "Skinned input, multipose mode: poses sampled over the clips, per skin drawing the mesh (default 16)");
  app->add_option("--lpm", o->lpm, "Also write a progressive mesh (.lpm) down to the coarsest level (skinned input: multipose or subset mode, one skinned mesh)");
  app->add_option("--threads", o->threads, "Worker threads (0: all); the output does not depend on it");
  app->add_flag("--force", o->force, "Allow writing over the input file");
  add_gltf_output_flags(app, o->gltf);
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o, app] {
            const FileFormat format = format_from_path(o->output);
            if (format != FileFormat::glb && format != FileFormat::gltf)
              throw_usage("lod writes glTF: give an output ending in .glb or .gltf");
            if (!(o->error_px > 0) || !(o->screen_height > 0) || !(o->fov_degrees > 0 && o->fov_degrees < 180))
              throw_usage("--error-px and --screen-height must be > 0 and --fov in (0, 180)");
            check_output(o->input, o->output, o->force);
            check_gltf_output_flags(o->gltf, o->output);
            if (!o->lpm.empty()) check_output(o->input, o->lpm, o->force);
            // Checked before loading, so a mistyped mode is refused for a mesh without skins too.
            const SkinMode skin_mode = parse_skin_mode(o->skin_mode);
            if (o->poses == 0) throw_usage("--poses must be at least 1");
            LodOptions options;
            if (!o->ratios.empty()) options.ratios = parse_list(o->ratios, "--ratios");
            if (!o->errors.empty()) options.errors = parse_list(o->errors, "--errors");
            // Each of the three sets the levels; given together, one would be ignored.
            if (app->count("--levels") + !o->ratios.empty() + !o->errors.empty() > 1)
              throw_usage("--levels, --ratios and --errors exclude each other (each sets the levels)");
            if (app->count("--levels")) options.levels = o->levels;  // (0 is refused with the others)
            options.from_previous = !o->from_input;
            if (o->morph && o->from_input) throw_usage("--morph needs each level simplified from the previous one (drop --from-input)");
            options.morph = o->morph;
            options.shared_vertices = o->shared;
            options.simplify.metric = parse_metric(o->metric);
            options.simplify.threads = o->threads;
            // Compressed output: the levels in the LRU-style order meshoptimizer's codecs favour
            // (bunny00's chain 4% smaller than in the FIFO order; bench/README.md, compress).
            if (o->gltf.meshopt_compression) options.cache.policy = CachePolicy::lru, options.cache.index_codec = true;
            if (!o->attributes.empty()) parse_attributes(o->attributes, options.simplify);

            auto start = std::chrono::steady_clock::now();
            // glTF input is read as a scene: a skinned character keeps its skeleton and clips, an
            // instanced mesh (EXT_mesh_gpu_instancing) its instances and an animated node its motion.
            const FileFormat in_format = format_from_path(o->input);
            Scene scene;
            Mesh mesh;
            {
              ProgressBar bar("loading");
              if (in_format == FileFormat::glb || in_format == FileFormat::gltf) scene = read_scene(o->input, bar.read_options());
              else mesh = read_mesh(o->input, bar.read_options());
            }
            {
              std::vector<const Mesh*> loaded = {&mesh};
              for (const Primitive& p : scene.primitives) loaded.push_back(&p.mesh);
              require_triangles(loaded, o->input, "nothing to build levels of; lodkit works on triangle meshes");
            }
            check_not_source(scene, o->output, o->force);
            check_not_source(scene, o->lpm, o->force);
            // lod on its own output: the earlier geomorphs lead to levels that go, and are not
            // blend shapes to carry; the earlier chains' nodes go (once the new chains are built).
            drop_geomorphs(scene, [](const Node&) { return true; });
            const std::vector<bool> earlier = earlier_chain_nodes(scene);
            std::vector<SkinnedPrimitive> skinned = scene.source ? skinned_primitives(scene) : std::vector<SkinnedPrimitive>{};
            const std::set<int32_t> earlier_levels = earlier_skinned_levels(scene, skinned);
            const std::vector<SkinnedGroup> groups = skinned_groups(scene, skinned);
            const std::vector<SeparatePart> separate = scene.source ? separate_parts(scene) : std::vector<SeparatePart>{};
            // The meshes skinned nodes draw: the skinned chains' (in place in the document).
            std::set<int32_t> skinned_meshes;
            for (const SkinnedPrimitive& sp : skinned) skinned_meshes.insert(int32_t(scene.primitives[sp.primitive].gltf_mesh));
            // The scenes flattened below differ from the input in their nodes and roots only: each
            // borrows it with those swapped in (a copy of the primitives would double a large
            // input's memory).
            const auto with_nodes = [&](std::vector<Node> nodes, std::vector<int32_t> roots, auto&& use) {
              std::swap(scene.nodes, nodes), std::swap(scene.roots, roots);
              use(static_cast<const Scene&>(scene));
              std::swap(scene.nodes, nodes), std::swap(scene.roots, roots);
            };
            std::vector<Node> static_nodes;  // the input's, without the separate and skinned meshes
            std::vector<uint32_t> static_streams;  // the static chain's per material (flatten_streams)
            if (scene.source) {
              static_nodes = scene.nodes;
              for (const SeparatePart& m : separate)
                for (const int32_t n : m.nodes) static_nodes[size_t(n)].mesh = -1;
              for (Node& node : static_nodes)
                if (skinned_meshes.count(node.mesh) || earlier_levels.count(node.mesh)) node.mesh = -1;
              with_nodes(static_nodes, scene.roots, [&](const Scene& view) { mesh = flatten_streams(view, static_streams); });
            }
            const double load_seconds = seconds_since(start);
            // (Before any chain is built: the progressive mesh is the static chain's.)
            if (!o->lpm.empty() && skinned.empty() && !separate.empty() && mesh.triangle_count() == 0)
              throw_usage("--lpm: all of the input's geometry is instanced (EXT_mesh_gpu_instancing), animated or below a "
                          "visibility switch (KHR_node_visibility), with chains of its own");

            // The skinned chains, then the static chain (if any geometry is neither skinned nor
            // separate), then one per separate mesh.
            std::vector<ChainReport> reports;
            std::vector<StaticChain> chains;  // the static and separate ones
            start = std::chrono::steady_clock::now();
            if (!skinned.empty()) {
              // A glTF morph target moves a vertex but not its joint weights, so a skinned level's
              // geomorph would not land on the next level in a pose: skinned chains morph at run time
              // (lod::SkinnedGeomorph), and --morph gives only the props' chains theirs.
              if (o->morph && mesh.triangle_count() == 0 && separate.empty())
                throw_usage("--morph: skinned input morphs at run time (lod::SkinnedGeomorph), not as glTF morph targets, "
                            "and this input has nothing else to morph");
              const SkinMode mode = skin_mode;
              if (!o->lpm.empty() && mode == SkinMode::houle)
                throw_usage("--lpm: --skin-mode houle simplifies in one pose, so its collapse record is not in bind "
                            "space; use multipose or subset");
              if (!o->lpm.empty() && groups.size() > 1)
                throw_usage(fmt::format("--lpm: the input has {} skinned meshes, and a .lpm file holds one", groups.size()));
              ProgressBar bar("building skinned LODs");
              LodOptions skinned_options = options;
              skinned_options.morph = false;
              reports = build_skinned(scene, groups, mode, o->poses, skinned_options, [&](double f) { bar.update(f); });
            }
            const size_t first_chain = reports.size();
            // A skinned character's props: a chain when there are triangles (the character alone
            // needs none); without skins, the input must have some.
            int32_t static_first = -1;  // the node the static chain's first level takes over (ChainPlace::first)
            if (skinned.empty() ? separate.empty() || mesh.triangle_count() > 0 : mesh.triangle_count() > 0) {
              validate(mesh, o->input);
              if (scene.source)
                with_nodes(static_nodes, scene.roots, [&](const Scene& view) { chains.push_back(prepare_static(std::move(mesh), &view, *o)); });
              else
                chains.push_back(prepare_static(std::move(mesh), nullptr, *o));
              chains.back().streams = std::move(static_streams);
              // Its levels are roots: an earlier static chain's first level, lending it the weights alone.
              const FlatMorphTargets& morph = chains.back().morph;
              if (!morph.targets.empty() && morph.nodes.size() == 1 && morph.nodes[0] >= 0 &&
                  scene.nodes[size_t(morph.nodes[0])].parent < 0 && earlier_level_in_place(scene, earlier, morph.nodes[0]))
                static_first = morph.nodes[0];
            }
            // Each separate part: its own chain in its own space (a mesh drawn once by its first
            // node, untransformed; a rigid group drawn by its nodes below its frame, untransformed),
            // and nothing else.
            std::vector<Node> solo = scene.nodes;
            std::vector<std::vector<int32_t>> separate_parents;  // per part, the frame or per drawing node levels_parent
            std::vector<std::vector<int32_t>> separate_firsts;   // and the node its first level takes over, or -1
            for (Node& node : solo) node.mesh = -1;
            for (const SeparatePart& m : separate) {
              const int32_t top = m.frame >= 0 ? m.frame : m.nodes[0];
              const std::vector<int32_t> drawing = m.frame >= 0 ? m.nodes : std::vector<int32_t>{top};
              for (const int32_t n : drawing) solo[size_t(n)].mesh = scene.nodes[size_t(n)].mesh;
              Node& node = solo[size_t(top)];
              node.gpu_instances.clear(), node.visible = true;  // (levels go below it: hidden when it is)
              node.has_matrix = false, node.translation = {}, node.rotation = {0, 0, 0, 1}, node.scale = {1, 1, 1};
              with_nodes(solo, {top}, [&](const Scene& view) {
                std::vector<uint32_t> streams;
                chains.push_back(prepare_static(flatten_streams(view, streams), &view, *o));
                chains.back().streams = std::move(streams);
              });
              // Named after the nodes its levels go below (a frame, or each node drawing it).
              const bool morphing = !chains.back().morph.targets.empty();
              std::vector<int32_t>& parents = separate_parents.emplace_back();
              std::vector<int32_t>& firsts = separate_firsts.emplace_back();
              for (const int32_t k : m.frame >= 0 ? std::vector<int32_t>{m.frame} : m.nodes) {
                parents.push_back(m.frame >= 0 ? k : levels_parent(scene, earlier, k));
                firsts.push_back(morphing && parents.back() != k ? k : -1);
              }
              std::vector<std::string> names;
              for (const int32_t k : parents) names.push_back(node_label(scene.nodes, size_t(k)));
              chains.back().report.node = fmt::format("{}", fmt::join(names, ", "));
              chains.back().report.instances = m.instanced ? m.instances : 0;
              chains.back().report.animated = m.animated;
              chains.back().report.switched = m.switched;
              chains.back().report.group_meshes = m.frame >= 0 ? m.nodes.size() : 0;
              node = scene.nodes[size_t(top)], node.mesh = -1;
              for (const int32_t n : drawing) solo[size_t(n)].mesh = -1;
            }
            {
              std::vector<const Mesh*> inputs;
              for (const StaticChain& c : chains) inputs.push_back(&c.to_simplify());
              ProgressBar bar(chains.size() > 1 ? fmt::format("building LODs ({} chains)", chains.size()) : "building LODs");
              options.progress = [&](double f) { bar.update(f); };
              std::vector<LodChain> built = build_lod_chains(inputs, options);
              options.progress = nullptr;
              for (size_t i = 0; i < chains.size(); ++i) finish_static(chains[i], std::move(built[i]));
            }
            for (StaticChain& c : chains) reports.push_back(std::move(c.report));
            const double build_seconds = seconds_since(start);
            for (ChainReport& r : reports) set_switching(r, *o);

            start = std::chrono::steady_clock::now();
            WriteReport written;
            // The progressive mesh spans the input down to the coarsest level's size.
            if (!skinned.empty() && !o->lpm.empty())
              write_progressive_mesh(skinned_progressive_mesh(scene, groups[0], skin_mode, o->poses,
                                                              options.simplify, reports[0].chain.levels.back().mesh.triangle_count()),
                                     o->lpm);
            Scene out;
            if (!skinned.empty()) {
              out = skinned_scene(std::move(scene), groups, reports);
              // With props, every other source mesh went into their chain.
              drop_chained_meshes(out, [&](uint32_t m) {
                return earlier_levels.count(int32_t(m)) || (!chains.empty() && !skinned_meshes.count(int32_t(m)));
              });
            } else {
              out = chain_document(scene.source ? &scene : nullptr, reports[0].chain.levels.front().mesh);
            }
            const size_t first_separate = chains.size() - separate.size();
            // An earlier run's chains (lod on its own output): the nodes whose meshes the new chains
            // replace go, save those the new levels go below or take morph weights from.
            std::vector<std::vector<Node::GpuInstance>> instances(out.nodes.size());  // (of separate meshes' nodes, which may go)
            {
              std::vector<bool> drawn(out.gltf_mesh_count, false);
              for (const Primitive& p : out.primitives)
                if (p.gltf_mesh < drawn.size()) drawn[p.gltf_mesh] = true;
              std::vector<bool> erase(out.nodes.size(), false);
              for (size_t n = 0; n < earlier.size() && n < erase.size(); ++n) {
                const int32_t drew = out.nodes[n].mesh;
                erase[n] = earlier[n] && (drew < 0 || (size_t(drew) < drawn.size() && !drawn[size_t(drew)]));
              }
              for (const StaticChain& c : chains)
                for (const int32_t n : c.targets.nodes)
                  if (n >= 0) erase[size_t(n)] = false;
              for (size_t c = first_separate; c < chains.size(); ++c) {
                for (const int32_t parent : separate_parents[c - first_separate]) erase[size_t(parent)] = false;
                for (const int32_t first : separate_firsts[c - first_separate])
                  if (first >= 0) erase[size_t(first)] = false;
              }
              for (const SeparatePart& part : separate)
                for (const int32_t n : part.nodes) instances[size_t(n)] = out.nodes[size_t(n)].gpu_instances;
              const std::vector<int32_t> remap = erase_nodes(out, erase);
              for (StaticChain& c : chains)
                for (int32_t& n : c.targets.nodes)
                  if (n >= 0) n = remap[size_t(n)];
              for (std::vector<int32_t>& parents : separate_parents)
                for (int32_t& n : parents) n = remap[size_t(n)];
              for (std::vector<int32_t>& firsts : separate_firsts)
                for (int32_t& n : firsts)
                  if (n >= 0) n = remap[size_t(n)];
              if (static_first >= 0) static_first = remap[size_t(static_first)];
            }
            for (size_t c = 0; c < first_separate; ++c)
              add_chain(out, reports[first_chain + c], chains[c].targets, chains[c].streams, {.first = static_first});
            for (size_t c = first_separate; c < chains.size(); ++c) {
              const SeparatePart& part = separate[c - first_separate];
              const std::vector<int32_t>& parents = separate_parents[c - first_separate];
              if (part.frame >= 0) {
                // A rigid group's levels under its frame, with its nodes' morph weights in turn.
                add_chain(out, reports[first_chain + c], chains[c].targets, chains[c].streams, {node_label(out.nodes, size_t(parents[0])) + "_", parents[0]});
                continue;
              }
              // Every node that drew the mesh draws the chain: its own level nodes, under it (or in
              // its stead, levels_parent), with its instances and morph weights.
              std::optional<uint32_t> meshes;
              for (size_t k = 0; k < part.nodes.size(); ++k) {
                const int32_t parent = parents[k], first = separate_firsts[c - first_separate][k];
                meshes = add_chain(out, reports[first_chain + c], chains[c].targets, chains[c].streams,
                                   {node_label(out.nodes, size_t(parent)) + "_", parent, instances[size_t(part.nodes[k])], parent,
                                    meshes, first});
              }
            }
            written = write_scene(out, o->output, o->gltf);
            if (skinned.empty() && !o->lpm.empty()) {
              SimplifyOptions so = options.simplify;
              so.target_triangles = std::max<uint64_t>(1, reports[0].chain.levels.back().mesh.triangle_count());
              SimplifyResult r = simplify(chains[0].input, so);
              write_progressive_mesh(ProgressiveMesh(chains[0].input, std::move(r.record)), o->lpm);
            }
            const double write_seconds = seconds_since(start);

            // The first chain's facts head the report (the static chain's, when there is one).
            const StaticChain none;
            const StaticChain& head = chains.empty() ? none : chains[0];
            const size_t morph_targets = head.targets.levels.empty() ? 0 : head.targets.levels[0].size();
            if (o->json) {
              // The skinned chains; the separate meshes' under "instanced" (with "animated" when a
              // node in motion draws them too), or else "animated" or "visibility" (below a
              // visibility switch only; "visibility" true in the others when also), as are rigid
              // groups (named after their frame, with "group_nodes"); beside skinned ones, the static
              // chain as "static".
              nlohmann::json listed = nlohmann::json::array(), instanced = listed, animated = listed, switched = listed, still;
              for (size_t k = 0; k < reports.size(); ++k) {
                const ChainReport& r = reports[k];
                nlohmann::json c = {{"node", r.node}, {"diagonal", r.chain.diagonal}, {"levels", levels_json(r)}};
                if (r.instances) c["instances"] = r.instances;
                if (r.instances && r.animated) c["animated"] = true;
                if ((r.instances || r.animated) && r.switched) c["visibility"] = true;
                if (r.group_meshes) c["group_nodes"] = r.group_meshes;
                if (!r.chain.morphs.empty()) c["geomorphs"] = true;
                if (k < first_chain) listed.push_back(std::move(c));
                else if (r.instances) instanced.push_back(std::move(c));
                else if (r.animated) animated.push_back(std::move(c));
                else if (r.switched) switched.push_back(std::move(c));
                else still = std::move(c), still.erase("node");  // (the static chain has none)
              }
              nlohmann::json j = {{"input", o->input}, {"output", o->output}, {"diagonal", reports[0].chain.diagonal},
                                  {"levels", levels_json(reports[0])}, {"load_seconds", load_seconds},
                                  {"build_seconds", build_seconds}, {"write_seconds", write_seconds},
                                  {"flat_shaded", head.form.flat_shaded}, {"double_sided", head.form.double_sided},
                                  {"morph_targets", morph_targets}, {"morph_targets_dropped", !head.targets_dropped.empty()}};
              if (!skinned.empty()) j["skinned"] = {{"mode", o->skin_mode}, {"poses", o->poses}, {"chains", listed}};
              if (!skinned.empty() && !still.is_null()) j["static"] = still;
              if (!instanced.empty()) j["instanced"] = instanced;
              if (!animated.empty()) j["animated"] = animated;
              if (!switched.empty()) j["visibility"] = switched;
              add_write_report(j, written, o->gltf);
              fmt::print("{}\n", j.dump(2));
            } else {
              for (const ChainReport& r : reports) {
                const std::string how = r.animated && r.switched ? "animated, below a visibility switch"
                                        : r.animated                ? "animated"
                                                                    : "below a visibility switch";
                if (r.instances)
                  fmt::print("instanced mesh of '{}' ({} instances{}{})\n", r.node, r.instances, r.animated || r.switched ? ", " : "",
                             r.animated || r.switched ? how : "");
                else if (r.group_meshes) fmt::print("group below '{}' ({} mesh nodes, {})\n", r.node, r.group_meshes, how);
                else if (r.animated || r.switched) fmt::print("mesh of '{}' ({})\n", r.node, how);
                else if (!r.node.empty()) fmt::print("skinned node '{}' ({} mode, {} poses)\n", r.node, o->skin_mode, o->poses);
                else if (reports.size() > 1) fmt::print("the rest of the scene\n");
                fmt::print("{:<6}{:>12}{:>12}{:>14}{:>11}{:>14}{:>14}\n", "level", "triangles", "vertices", "error", "% diag",
                           "bound", "switch at");
                for (size_t i = 0; i < r.chain.levels.size(); ++i) {
                  const LodLevel& l = r.chain.levels[i];
                  fmt::print("{:<6}{:>12}{:>12}{:>14.6g}{:>10.4f}%{:>14.6g}{:>14.6g}\n", i, l.mesh.triangle_count(),
                             l.mesh.vertex_count(), l.error, 100.0 * l.relative_error, l.error_bound, r.distances[i]);
                }
              }
              fmt::print("error: Hausdorff distance to the input (measured{}); bound: certified upper bound; switch at: the "
                         "distance where the bound is {} px ({} px screen, {} deg fov)\n",
                         skinned.empty() ? "" : ", bind pose", o->error_px, o->screen_height, o->fov_degrees);
              if (o->morph && !skinned.empty())
                fmt::print("geomorphs: on the other chains; the skinned ones morph at run time (lod::SkinnedGeomorph)\n");
              if (head.form.flat_shaded) fmt::print("flat-shaded: each level built without the normals, faceted again\n");
              if (head.form.double_sided) fmt::print("double-sided: each level built on the fronts, backs made again\n");
              if (morph_targets)
                fmt::print("morph targets: {} on every level{}, {}\n", morph_targets,
                           head.targets.nodes.size() > 1 ? fmt::format(" (of {} nodes, their clips merged)", head.targets.nodes.size()) : "",
                           o->shared ? "exact (one vertex buffer)" : "interpolated where the vertices moved");
              if (!head.targets_dropped.empty()) fmt::print("morph targets dropped: {}\n", head.targets_dropped);
              fmt::print("{}", draco_line(written, o->gltf));
              fmt::print("loaded in {:.3f}s, built in {:.3f}s, wrote {} ({} bytes) in {:.3f}s\n", load_seconds, build_seconds,
                         o->output, written.bytes, write_seconds);
            }
            return 0;
          }};
}

}  // namespace lod::cli
