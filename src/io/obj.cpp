// Wavefront OBJ: v (optionally with r g b), vt, vn, faces of any size (fan-triangulated), negative
// (relative) indices, g/o groups, usemtl materials and the mtllib statements naming their libraries
// (read by the file layer, io.cpp). Other statements (s, l, p, ...) are skipped.
//
// Vertices: a file whose faces use positions only keeps its `v` list as the vertex list, in file
// order. Otherwise every distinct (v, vt, vn) triple becomes one vertex, in order of first use.
// The writer emits the same layout back, so read -> write -> read is exact.
//
// Indices: positive ones may point anywhere in the file (forward references are accepted, as most
// readers do); negative ones count back from the statement. Large files are parsed in pieces on
// several threads and joined in file order, so the mesh is the same for any thread count.
#include <algorithm>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>

#include "core/heap.h"
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

struct Corner {
  uint32_t v, vt, vn;
};

// Pieces of a file parsed on separate threads are at least this large: below, a thread costs more
// than it saves.
constexpr size_t min_chunk = size_t(1) << 20;

enum Kind { kind_v, kind_vt, kind_vn };
constexpr const char* kind_names[] = {"vertex", "texture coordinate", "normal"};

// An index relative to its chunk's first v/vt/vn, resolved when the chunks are joined.
constexpr uint32_t chunk_local = 0x80000000u;

// How one chunk resolves its indices. First pass (`known` false): chunks run in parallel without
// knowing how many v/vt/vn come before them, so positive indices are kept as they are and negative
// ones become chunk-local. Checking pass (`known` true): the counts before the chunk and in the
// whole file are known, every index is resolved and range-checked at its line. It re-runs a chunk
// whose indices failed the join, so that the error names the line.
struct Counts {
  uint64_t n[3] = {0, 0, 0};
};
struct Resolve {
  bool known = false;
  Counts before, total;
};

// A material or group statement, at the triangle it precedes (chunk-local).
struct Event {
  size_t triangle;
  bool material;
  std::string name;
};

// What one chunk of lines holds.
struct Chunk {
  std::vector<float3> positions;
  std::vector<float4> colors;  // empty, or one per position (white where a v line had none)
  std::vector<float2> texcoords;
  std::vector<float3> normals;
  std::vector<Corner> corners;  // 3 per triangle
  std::vector<Event> events;
  std::vector<std::string> libraries;  // mtllib statements' text
  bool any_texcoord = false, any_normal = false;
  bool local_refs = false;  // holds chunk_local indices
  uint64_t lines = 0;
  std::exception_ptr error;
  Counts counts() const { return {{positions.size(), texcoords.size(), normals.size()}}; }
};

uint32_t resolve(int64_t index, Kind kind, uint64_t defined, const Resolve& r, Chunk& chunk, io::TextReader& in) {
  if (index == 0) in.fail(std::string(kind_names[kind]) + " index 0 is invalid: OBJ indices start at 1");
  if (r.known) {
    // Positive indices may point forward, anywhere in the file; negative ones count back from here.
    const int64_t g = index > 0 ? index - 1 : int64_t(r.before.n[kind] + defined) + index;
    if (g < 0 || uint64_t(g) >= r.total.n[kind])
      in.fail(std::string(kind_names[kind]) + " index " + std::to_string(index) + " is out of range (" +
              std::to_string(r.total.n[kind]) + " in the file, " + std::to_string(r.before.n[kind] + defined) +
              " defined so far)");
    return uint32_t(g);
  }
  if (index > 0) {
    if (uint64_t(index) > chunk_local - 1) in.fail(std::string(kind_names[kind]) + " index " + std::to_string(index) + " is too large");
    return uint32_t(index - 1);
  }
  // Negative: relative to what this chunk has defined; one that reaches into an earlier chunk is
  // left to the checking pass (flagged by an impossible value).
  const int64_t local = int64_t(defined) + index;
  chunk.local_refs = true;
  return local >= 0 && local < int64_t(chunk_local - 1) ? chunk_local | uint32_t(local) : absent - 1;
}

void parse_chunk(std::span<const uint8_t> bytes, const std::string& name, uint64_t first_line, const ReadOptions* options,
                 const Resolve& r, Chunk& chunk) {
  io::TextReader in(bytes, name, options, first_line);
  in.set_comment('#');
  std::vector<Corner> polygon;
  // Upper bounds ("v 1 2 3\n" and "f 1 2 3\n" are 8 bytes): address space only, since untouched
  // pages are never faulted in, and no reallocation copies on large files. Huge pages: a fault per
  // 2 MiB touched instead of per 4 KiB.
  if (bytes.size() >= min_chunk) {
    core::reserve_huge(chunk.positions, bytes.size() / 8);
    core::reserve_huge(chunk.corners, bytes.size() / 8 * 3);
  }
  while (!in.at_end()) {
    std::string_view key = in.token();
    if (key.empty()) {
      in.next_line();
      continue;
    }
    if (key == "v") {
      float x = in.read_float("x"), y = in.read_float("y"), z = in.read_float("z");
      chunk.positions.push_back({x, y, z});
      float extra[4];
      int n = 0;
      while (n < 4 && in.try_read_float(extra[n])) ++n;
      // 4 values: a homogeneous w (ignored); 6: r g b colours; 7: r g b a.
      if (n == 3 || n == 4) {
        chunk.colors.resize(chunk.positions.size() - 1, {1, 1, 1, 1});
        chunk.colors.push_back({extra[0], extra[1], extra[2], n == 4 ? extra[3] : 1.0f});
      } else if (n > 1) {
        in.fail("a vertex has " + std::to_string(3 + n) + " values; expected x y z [w] or x y z r g b [a]");
      }
    } else if (key == "vt") {
      float u = in.read_float("u");
      float v = 0, w;
      in.try_read_float(v);
      in.try_read_float(w);
      chunk.texcoords.push_back({u, v});
    } else if (key == "vn") {
      float x = in.read_float("x"), y = in.read_float("y"), z = in.read_float("z");
      chunk.normals.push_back({x, y, z});
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
        c.v = resolve(iv, kind_v, chunk.positions.size(), r, chunk, in);
        if (p < e && *p == '/') {
          ++p;
          if (p < e && *p != '/') {
            p = parse_index(p, e, it);
            if (!p) in.fail("bad texture index in '" + std::string(t.substr(0, 40)) + "'");
            c.vt = resolve(it, kind_vt, chunk.texcoords.size(), r, chunk, in);
          }
          if (p < e && *p == '/') {
            ++p;
            p = parse_index(p, e, in_);
            if (!p) in.fail("bad normal index in '" + std::string(t.substr(0, 40)) + "'");
            c.vn = resolve(in_, kind_vn, chunk.normals.size(), r, chunk, in);
          }
        }
        if (p != e) in.fail("bad face corner '" + std::string(t.substr(0, 40)) + "'");
        if (polygon.size() >= io::max_face_corners) in.fail(io::polygon_size_problem("face", polygon.size() + 1));
        polygon.push_back(c);
      }
      if (polygon.size() < 3) in.fail(io::polygon_size_problem("face", polygon.size()));
      for (const Corner& c : polygon) chunk.any_texcoord |= c.vt != absent, chunk.any_normal |= c.vn != absent;
      io::append_fan(chunk.corners, polygon);
    } else if (key == "usemtl" || key == "g" || key == "o") {
      chunk.events.push_back({chunk.corners.size() / 3, key == "usemtl", std::string(in.rest_of_line())});
    } else if (key.starts_with('#')) {
      // comment line
    } else if (key == "mtllib") {
      chunk.libraries.emplace_back(in.rest_of_line());
    } else if (key == "vp" || key == "s" || key == "l" || key == "p" || key == "usemap" ||
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
  chunk.lines = in.line() - first_line;
}

// Runs fn(0) .. fn(n - 1) at once, fn(0) on the calling thread. fn must not throw.
void in_parallel(size_t n, const std::function<void(size_t)>& fn) {
  std::vector<std::jthread> workers;
  for (size_t k = 1; k < n; ++k) workers.emplace_back(fn, k);
  if (n > 0) fn(0);
}

// Splits the file after newlines into pieces of about equal size, one per thread.
std::vector<std::span<const uint8_t>> split_lines(std::span<const uint8_t> bytes, unsigned threads) {
  const size_t pieces = std::max<size_t>(1, std::min<size_t>(threads, bytes.size() / min_chunk));
  std::vector<std::span<const uint8_t>> chunks;
  size_t begin = 0;
  for (size_t k = 1; k <= pieces && begin < bytes.size(); ++k) {
    size_t end = k == pieces ? bytes.size() : std::max(begin, bytes.size() * k / pieces);
    const auto* nl = static_cast<const uint8_t*>(std::memchr(bytes.data() + end, '\n', bytes.size() - end));
    end = k == pieces || !nl ? bytes.size() : size_t(nl - bytes.data()) + 1;
    chunks.push_back(bytes.subspan(begin, end - begin));
    begin = end;
  }
  return chunks;
}

// Joins the parsed chunks, in file order, into one mesh (indices already global).
Mesh join_chunks(std::vector<Chunk>& chunks, const Counts& total) {
  std::vector<float3> positions, normals;
  std::vector<float2> texcoords;
  std::vector<float4> colors;
  core::reserve_huge(positions, total.n[kind_v]);
  core::reserve_huge(texcoords, total.n[kind_vt]);
  core::reserve_huge(normals, total.n[kind_vn]);
  const bool any_color = std::any_of(chunks.begin(), chunks.end(), [](const Chunk& c) { return !c.colors.empty(); });
  bool any_texcoord = false, any_normal = false;
  size_t corner_count = 0;
  for (Chunk& c : chunks) {
    positions.insert(positions.end(), c.positions.begin(), c.positions.end());
    texcoords.insert(texcoords.end(), c.texcoords.begin(), c.texcoords.end());
    normals.insert(normals.end(), c.normals.begin(), c.normals.end());
    if (any_color) {
      c.colors.resize(c.positions.size(), {1, 1, 1, 1});
      colors.insert(colors.end(), c.colors.begin(), c.colors.end());
    }
    any_texcoord |= c.any_texcoord, any_normal |= c.any_normal;
    corner_count += c.corners.size();
    c.positions = {}, c.texcoords = {}, c.normals = {}, c.colors = {};
  }

  // Materials and groups: ids in order of first use; faces before the first usemtl (g/o) get the
  // unnamed one.
  NameTable materials, groups;
  std::vector<uint32_t> triangle_material, triangle_group;
  bool has_materials = false, has_groups = false;
  uint32_t current_material = absent, current_group = absent;
  size_t triangle_base = 0;
  for (const Chunk& c : chunks) {
    for (const Event& e : c.events) {
      const size_t t = triangle_base + e.triangle;
      bool& has = e.material ? has_materials : has_groups;
      NameTable& table = e.material ? materials : groups;
      std::vector<uint32_t>& per_triangle = e.material ? triangle_material : triangle_group;
      uint32_t& current = e.material ? current_material : current_group;
      if (!has) {
        has = true;
        if (t > 0) per_triangle.assign(t, table.id(""));
      }
      per_triangle.resize(t, current);
      current = table.id(e.name);
    }
    triangle_base += c.corners.size() / 3;
  }
  if (has_materials) triangle_material.resize(triangle_base, current_material);
  if (has_groups) triangle_group.resize(triangle_base, current_group);

  Mesh mesh;
  if (!any_texcoord && !any_normal) {
    // Positions only: the v list is the vertex list.
    mesh.positions = std::move(positions);
    mesh.colors = std::move(colors);
    core::resize_huge(mesh.indices, corner_count);
    std::vector<size_t> offset(chunks.size() + 1, 0);
    for (size_t k = 0; k < chunks.size(); ++k) offset[k + 1] = offset[k] + chunks[k].corners.size();
    in_parallel(chunks.size(), [&](size_t k) {
      uint32_t* out = mesh.indices.data() + offset[k];
      for (const Corner& corner : chunks[k].corners) *out++ = corner.v;
      chunks[k].corners = {};
    });
  } else {
    // One vertex per distinct (v, vt, vn), found through a chain of the vertices made from each v.
    std::vector<uint32_t> first_of_position(positions.size(), absent), next_same_position;
    std::vector<Corner> vertex_corner;
    core::reserve_huge(mesh.indices, corner_count);
    for (Chunk& chunk : chunks) {
      for (const Corner& c : chunk.corners) {
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
      chunk.corners = {};
    }
    const size_t n = vertex_corner.size();
    core::resize_huge(mesh.positions, n);
    if (any_color) core::resize_huge(mesh.colors, n);
    if (any_texcoord) core::resize_huge(mesh.uvs[0], n);
    if (any_normal) core::resize_huge(mesh.normals, n);
    for (size_t v = 0; v < n; ++v) {
      const Corner& c = vertex_corner[v];
      mesh.positions[v] = positions[c.v];
      if (any_color) mesh.colors[v] = colors[c.v];
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

}  // namespace

Mesh read_obj(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options,
              std::vector<std::string>* material_libraries) {
  if (bytes.empty()) throw_bad_input_at_line(name, 1, "empty file, expected OBJ statements");
  // Parse chunks of lines in parallel, then join them in file order: the result does not depend on
  // the number of threads. Only the first chunk reports progress (they advance at the same pace).
  // (hardware_concurrency reads /sys: skip it for files too small to split anyway.)
  const unsigned threads = options.threads            ? options.threads
                           : bytes.size() < min_chunk ? 1u
                                                      : std::max(1u, std::thread::hardware_concurrency());
  const auto pieces = split_lines(bytes, threads);
  std::vector<Chunk> chunks(pieces.size());
  in_parallel(chunks.size(), [&](size_t k) {
    try {
      parse_chunk(pieces[k], name, 1, k == 0 ? &options : nullptr, {}, chunks[k]);
    } catch (...) {
      chunks[k].error = std::current_exception();
    }
  });
  // The first failing chunk in file order has the file's first error; parse it again knowing its
  // first line number, so the message names the right line.
  std::vector<uint64_t> first_line(chunks.size() + 1, 1);
  std::vector<Counts> before(chunks.size() + 1);
  for (size_t k = 0; k < chunks.size(); ++k) {
    if (chunks[k].error) {
      Chunk again;
      parse_chunk(pieces[k], name, first_line[k], nullptr, {}, again);
      std::rethrow_exception(chunks[k].error);  // not reached unless parsing is not repeatable
    }
    first_line[k + 1] = first_line[k] + chunks[k].lines;
    for (int i = 0; i < 3; ++i) before[k + 1].n[i] = before[k].n[i] + chunks[k].counts().n[i];
  }
  const Counts total = before.back();
  if (total.n[kind_v] > chunk_local - 1) throw_bad_input(name, "more than 2^31 vertices");

  // Resolve chunk-local indices and check every index against the whole file (in parallel); a chunk
  // with a bad index is parsed again with the counts known, which throws at the offending line.
  std::vector<char> bad(chunks.size(), 0);
  in_parallel(chunks.size(), [&](size_t k) {
    for (Corner& corner : chunks[k].corners) {
      uint32_t* parts[3] = {&corner.v, &corner.vt, &corner.vn};
      for (int i = 0; i < 3; ++i) {
        uint32_t& x = *parts[i];
        if (x == absent) continue;
        if (x == absent - 1) bad[k] = 1;  // reached into an earlier chunk
        else if (x & chunk_local) x = uint32_t(before[k].n[i]) + (x & ~chunk_local);
        if (x >= total.n[i]) bad[k] = 1;
      }
    }
  });
  for (size_t k = 0; k < chunks.size(); ++k) {
    if (!bad[k]) continue;
    // The checking pass resolves relative indices that reached into earlier chunks, and throws at a
    // line only when an index is really out of range.
    Chunk again;
    parse_chunk(pieces[k], name, first_line[k], nullptr, {true, before[k], total}, again);
    chunks[k].corners = std::move(again.corners);
  }
  Mesh mesh = join_chunks(chunks, total);
  make_unit_directions(mesh);
  if (material_libraries)
    for (const Chunk& chunk : chunks) material_libraries->insert(material_libraries->end(), chunk.libraries.begin(), chunk.libraries.end());
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

}  // namespace

std::map<uint32_t, std::string> io::obj_names(const std::vector<std::string>& names, std::span<const uint32_t> ids) {
  std::map<uint32_t, std::string> out;
  for (uint32_t id : ids) out.try_emplace(id);
  std::set<std::string> taken;
  for (auto& [id, name] : out) {
    const std::string own = id < names.size() && !names[id].empty() ? names[id] : "default";
    name = own;
    for (int k = 0; !taken.insert(name).second; ++k) name = own + "_" + std::to_string(id) + (k ? "_" + std::to_string(k) : "");
  }
  return out;
}

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
  const std::vector<uint32_t> all_zero = {0};  // (no per-triangle ids: every triangle uses material 0)
  const std::span<const uint32_t> materials = mesh.materials.empty() ? std::span<const uint32_t>(all_zero) : mesh.materials;
  const std::map<uint32_t, std::string> material_names = io::obj_names(mesh.material_names, materials);
  const std::map<uint32_t, std::string> group_names = io::obj_names(mesh.group_names, mesh.groups);
  // Faces before the first g/usemtl read back as the unnamed group/material: no statement needed
  // there, unless an MTL library gives that material a look under its printed name.
  const bool library = !mesh.material_looks.empty();
  auto switch_to = [&](const char* statement, const std::vector<std::string>& names, const std::map<uint32_t, std::string>& printed,
                       uint32_t id, size_t t, bool named_anyway) {
    if (t == 0 && (id >= names.size() || names[id].empty()) && !named_anyway) return;
    out += statement, out += ' ', out += printed.at(id), out += '\n';
  };
  uint32_t material = absent, group = absent;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (!mesh.groups.empty() && mesh.groups[t] != group) switch_to("g", mesh.group_names, group_names, group = mesh.groups[t], t, false);
    if (const uint32_t id = materials[mesh.materials.empty() ? 0 : t]; id != material)
      switch_to("usemtl", mesh.material_names, material_names, material = id, t, library);
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
