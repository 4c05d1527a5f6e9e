// Wavefront OBJ: v (optionally with r g b), vt, vn, faces of any size (fan-triangulated), negative
// (relative) indices, g/o groups and usemtl materials. Other statements (mtllib, s, l, p, ...) are
// skipped.
//
// Vertices: a file whose faces use positions only keeps its `v` list as the vertex list, in file
// order. Otherwise every distinct (v, vt, vn) triple becomes one vertex, in order of first use.
// The writer emits the same layout back, so read -> write -> read is exact.
#include <algorithm>
#include <limits>
#include <string>
#include <unordered_map>

#include "io/text_reader.h"
#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

constexpr uint32_t absent = std::numeric_limits<uint32_t>::max();

// Names in order of first use (materials, groups); id lookup by name.
class NameTable {
 public:
  uint32_t id(std::string_view name) {
    auto it = ids_.find(std::string(name));
    if (it != ids_.end()) return it->second;
    names_.emplace_back(name);
    ids_.emplace(names_.back(), uint32_t(names_.size() - 1));
    return uint32_t(names_.size() - 1);
  }
  std::vector<std::string> take_names() { return std::move(names_); }

 private:
  std::vector<std::string> names_;
  std::unordered_map<std::string, uint32_t> ids_;
};

// Parses a decimal integer at p (optional '-'); returns the end, or nullptr if none.
const char* parse_index(const char* p, const char* end, int64_t& value) {
  bool negative = false;
  if (p < end && *p == '-') negative = true, ++p;
  const char* start = p;
  uint64_t v = 0;
  while (p < end && *p >= '0' && *p <= '9' && p - start < 18) v = v * 10 + uint64_t(*p++ - '0');
  if (p == start || (p < end && *p >= '0' && *p <= '9')) return nullptr;
  value = negative ? -int64_t(v) : int64_t(v);
  return p;
}

// Resolves an OBJ index (1-based, or negative = relative to the `count` defined so far) to 0-based.
uint32_t resolve(int64_t index, size_t count, io::TextReader& in, const char* what) {
  int64_t r = index > 0 ? index - 1 : int64_t(count) + index;
  if (index == 0 || r < 0 || r >= int64_t(count))
    in.fail(std::string(what) + " index " + std::to_string(index) + " is out of range (" + std::to_string(count) +
            " defined so far)");
  return uint32_t(r);
}

struct Corner {
  uint32_t v, vt, vn;
};

}  // namespace

Mesh read_obj(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options) {
  io::TextReader in(bytes, name, &options);
  in.set_comment('#');
  if (bytes.empty()) in.fail("empty file, expected OBJ statements");
  std::vector<float3> positions;
  std::vector<float4> position_colors;  // the "v x y z r g b" extension
  std::vector<float2> texcoords;
  std::vector<float3> normals;
  std::vector<Corner> corners;  // 3 per triangle, resolved to 0-based pool indices
  bool any_texcoord = false, any_normal = false;
  NameTable materials, groups;
  std::vector<uint32_t> triangle_material, triangle_group;
  bool has_materials = false, has_groups = false;
  uint32_t current_material = absent, current_group = absent;
  std::vector<Corner> polygon;

  while (!in.at_end()) {
    std::string_view key = in.token();
    if (key.empty()) {
      in.next_line();
      continue;
    }
    if (key == "v") {
      float x = in.read_float("x"), y = in.read_float("y"), z = in.read_float("z");
      positions.push_back({x, y, z});
      float extra[4];
      int n = 0;
      while (n < 4 && in.try_read_float(extra[n])) ++n;
      // 4 values: a homogeneous w (ignored); 6: r g b colours; 7: r g b a.
      if (n == 3 || n == 4) {
        if (position_colors.size() + 1 < positions.size()) position_colors.resize(positions.size() - 1, {1, 1, 1, 1});
        position_colors.push_back({extra[0], extra[1], extra[2], n == 4 ? extra[3] : 1.0f});
      } else if (n > 1) {
        in.fail("a vertex has " + std::to_string(3 + n) + " values; expected x y z [w] or x y z r g b [a]");
      }
    } else if (key == "vt") {
      float u = in.read_float("u");
      float v = 0, w;
      in.try_read_float(v);
      in.try_read_float(w);
      texcoords.push_back({u, v});
    } else if (key == "vn") {
      float x = in.read_float("x"), y = in.read_float("y"), z = in.read_float("z");
      normals.push_back({x, y, z});
    } else if (key == "f") {
      polygon.clear();
      for (;;) {
        std::string_view t = in.token();
        if (t.empty()) break;
        const char *p = t.data(), *e = t.data() + t.size();
        int64_t iv = 0, it = 0, in_ = 0;
        Corner c{absent, absent, absent};
        p = parse_index(p, e, iv);
        if (!p) in.fail("bad face corner '" + std::string(t.substr(0, 40)) + "', expected v, v/vt, v//vn or v/vt/vn");
        c.v = resolve(iv, positions.size(), in, "vertex");
        if (p < e && *p == '/') {
          ++p;
          if (p < e && *p != '/') {
            p = parse_index(p, e, it);
            if (!p) in.fail("bad texture index in '" + std::string(t.substr(0, 40)) + "'");
            c.vt = resolve(it, texcoords.size(), in, "texture coordinate");
          }
          if (p < e && *p == '/') {
            ++p;
            p = parse_index(p, e, in_);
            if (!p) in.fail("bad normal index in '" + std::string(t.substr(0, 40)) + "'");
            c.vn = resolve(in_, normals.size(), in, "normal");
          }
        }
        if (p != e) in.fail("bad face corner '" + std::string(t.substr(0, 40)) + "'");
        if (polygon.size() >= io::max_face_corners) in.fail(io::polygon_size_problem("face", polygon.size() + 1));
        polygon.push_back(c);
      }
      if (polygon.size() < 3) in.fail(io::polygon_size_problem("face", polygon.size()));
      if (has_materials && current_material == absent) current_material = materials.id("");
      if (has_groups && current_group == absent) current_group = groups.id("");
      for (const Corner& c : polygon) any_texcoord |= c.vt != absent, any_normal |= c.vn != absent;
      io::append_fan(corners, polygon);
      if (has_materials) triangle_material.resize(corners.size() / 3, current_material);
      if (has_groups) triangle_group.resize(corners.size() / 3, current_group);
    } else if (key == "usemtl") {
      std::string_view m = in.rest_of_line();
      if (!has_materials) {
        // Faces before the first usemtl get the unnamed material.
        has_materials = true;
        if (!corners.empty()) triangle_material.assign(corners.size() / 3, materials.id(""));
      }
      current_material = materials.id(m);
    } else if (key == "g" || key == "o") {
      std::string_view g = in.rest_of_line();
      if (!has_groups) {
        has_groups = true;
        if (!corners.empty()) triangle_group.assign(corners.size() / 3, groups.id(""));
      }
      current_group = groups.id(g);
    } else if (key.starts_with('#')) {
      // comment line
    } else if (key == "vp" || key == "s" || key == "l" || key == "p" || key == "mtllib" || key == "usemap" ||
               key == "maplib" || key == "cstype" || key == "deg" || key == "curv" || key == "surf" || key == "parm" ||
               key == "end" || key == "trim" || key == "hole" || key == "bmat" || key == "step" || key == "lod" ||
               key == "shadow_obj" || key == "trace_obj" || key == "ctech" || key == "stech" || key == "call" ||
               key == "csh" || key == "bevel" || key == "c_interp" || key == "d_interp" || key == "mg" || key == "sp" ||
               key == "con" || key == "curv2") {
      // Known statements lodkit has no use for.
    } else {
      in.fail("unknown OBJ statement '" + std::string(key.substr(0, 40)) + "'");
    }
    in.next_line();
  }

  Mesh mesh;
  if (!position_colors.empty()) position_colors.resize(positions.size(), {1, 1, 1, 1});
  if (!any_texcoord && !any_normal) {
    // Positions only: the v list is the vertex list.
    mesh.positions = std::move(positions);
    mesh.colors = std::move(position_colors);
    mesh.indices.reserve(corners.size());
    for (const Corner& c : corners) mesh.indices.push_back(c.v);
  } else {
    // One vertex per distinct (v, vt, vn), found through a chain of the vertices made from each v.
    std::vector<uint32_t> first_of_position(positions.size(), absent), next_same_position;
    std::vector<Corner> vertex_corner;
    mesh.indices.reserve(corners.size());
    for (const Corner& c : corners) {
      uint32_t v = first_of_position[c.v];
      while (v != absent && (vertex_corner[v].vt != c.vt || vertex_corner[v].vn != c.vn)) v = next_same_position[v];
      if (v == absent) {
        v = uint32_t(vertex_corner.size());
        vertex_corner.push_back(c);
        next_same_position.push_back(first_of_position[c.v]);
        first_of_position[c.v] = v;
      }
      mesh.indices.push_back(v);
    }
    const size_t n = vertex_corner.size();
    mesh.positions.resize(n);
    if (!position_colors.empty()) mesh.colors.resize(n);
    if (any_texcoord) mesh.uvs[0].resize(n);
    if (any_normal) mesh.normals.resize(n);
    for (size_t v = 0; v < n; ++v) {
      const Corner& c = vertex_corner[v];
      mesh.positions[v] = positions[c.v];
      if (!position_colors.empty()) mesh.colors[v] = position_colors[c.v];
      if (any_texcoord) mesh.uvs[0][v] = c.vt != absent ? texcoords[c.vt] : float2{};
      if (any_normal) mesh.normals[v] = c.vn != absent ? normals[c.vn] : float3{};
    }
  }
  if (has_materials) {
    mesh.materials = std::move(triangle_material);
    mesh.material_names = materials.take_names();
  }
  if (has_groups) {
    mesh.groups = std::move(triangle_group);
    mesh.group_names = groups.take_names();
  }
  return mesh;
}

namespace {

void append_floats(std::string& out, const char* key, std::initializer_list<float> values) {
  out += key;
  for (float f : values) out += ' ', io::append_float(out, f);
  out += '\n';
}

// Pools of distinct values by exact bits, in order of first use, for vt and vn.
template <class T>
std::vector<uint32_t> pool_ids(const std::vector<T>& values, std::vector<T>& pool) {
  std::unordered_map<std::string, uint32_t> seen;
  std::vector<uint32_t> ids(values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    std::string key(reinterpret_cast<const char*>(&values[i]), sizeof(T));
    auto [it, inserted] = seen.try_emplace(key, uint32_t(pool.size()));
    if (inserted) pool.push_back(values[i]);
    ids[i] = it->second;
  }
  return ids;
}

// A name for usemtl/g: OBJ cannot express an empty one.
std::string_view printable(const std::vector<std::string>& names, uint32_t id) {
  return id < names.size() && !names[id].empty() ? std::string_view(names[id]) : std::string_view("default");
}

}  // namespace

void write_obj(const Mesh& mesh, std::string& out, const WriteOptions&) {
  out += "# written by lodkit\n";
  const bool uv = !mesh.uvs[0].empty(), normal = !mesh.normals.empty(), color = !mesh.colors.empty();
  const size_t n = mesh.vertex_count();
  // Positions only: one v per vertex keeps the vertex list (and its order) as it is. With vt/vn,
  // vertices sharing a position share one v (seams stay connected for other tools), except when two
  // vertices would get the same v/vt/vn triple; those keep their own v so they stay distinct.
  std::vector<uint32_t> v_of_vertex(n);
  std::vector<uint32_t> vt_of_vertex, vn_of_vertex;
  std::vector<float2> vt_pool;
  std::vector<float3> vn_pool;
  if (uv) vt_of_vertex = pool_ids(mesh.uvs[0], vt_pool);
  if (normal) vn_of_vertex = pool_ids(mesh.normals, vn_pool);
  std::vector<uint32_t> v_source;  // vertex whose position (and colour) each v line writes
  if (!uv && !normal) {
    for (uint32_t v = 0; v < n; ++v) v_of_vertex[v] = v, v_source.push_back(v);
  } else {
    const PositionIds pids = position_ids(mesh);
    std::vector<uint32_t> v_of_pid(pids.count, absent);
    std::unordered_map<uint64_t, std::vector<uint32_t>> triples;  // (vt, vn) -> v lines already paired with it
    for (uint32_t v = 0; v < n; ++v) {
      uint32_t p = pids.id[v];
      uint32_t line = v_of_pid[p];
      if (line != absent && color && !(mesh.colors[v_source[line]] == mesh.colors[v])) line = absent;
      std::vector<uint32_t>& taken = triples[(uint64_t(uv ? vt_of_vertex[v] : 0) << 32) | (normal ? vn_of_vertex[v] : 0)];
      if (line != absent && std::find(taken.begin(), taken.end(), line) != taken.end()) line = absent;
      if (line == absent) {
        line = uint32_t(v_source.size());
        v_source.push_back(v);
        if (v_of_pid[p] == absent) v_of_pid[p] = line;
      }
      taken.push_back(line);
      v_of_vertex[v] = line;
    }
  }
  out.reserve(out.size() + n * 40 + mesh.indices.size() * 12);
  for (uint32_t s : v_source) {
    const float3& p = mesh.positions[s];
    if (color) {
      const float4& c = mesh.colors[s];
      if (c.w == 1.0f) append_floats(out, "v", {p.x, p.y, p.z, c.x, c.y, c.z});
      else append_floats(out, "v", {p.x, p.y, p.z, c.x, c.y, c.z, c.w});
    } else {
      append_floats(out, "v", {p.x, p.y, p.z});
    }
  }
  for (const float2& t : vt_pool) append_floats(out, "vt", {t.x, t.y});
  for (const float3& m : vn_pool) append_floats(out, "vn", {m.x, m.y, m.z});
  // Faces before the first g/usemtl read back as the unnamed group/material: no statement needed there.
  auto switch_to = [&](const char* statement, const std::vector<std::string>& names, uint32_t id, size_t t) {
    if (t == 0 && id < names.size() && names[id].empty()) return;
    out += statement, out += ' ', out += printable(names, id), out += '\n';
  };
  uint32_t material = absent, group = absent;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (!mesh.groups.empty() && mesh.groups[t] != group) switch_to("g", mesh.group_names, group = mesh.groups[t], t);
    if (!mesh.materials.empty() && mesh.materials[t] != material)
      switch_to("usemtl", mesh.material_names, material = mesh.materials[t], t);
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      uint32_t v = mesh.indices[3 * t + k];
      out += ' ';
      io::append_uint(out, uint64_t(v_of_vertex[v]) + 1);
      if (uv || normal) {
        out += '/';
        if (uv) io::append_uint(out, uint64_t(vt_of_vertex[v]) + 1);
        if (normal) out += '/', io::append_uint(out, uint64_t(vn_of_vertex[v]) + 1);
      }
    }
    out += '\n';
  }
}

}  // namespace lod
