// PLY (Stanford polygon format): ASCII, binary little- and big-endian. Any element and property
// order, every scalar type, lists with any integer count type; unknown elements and properties are
// skipped. Vertex properties we map: x y z, nx ny nz, u v | s t | texture_u texture_v (uv set 0),
// u1 v1 .. u3 v3, tx ty tz tw (tangent), red green blue alpha (integer types are normalised to 0..1),
// joint0..3, weight0..3. Face properties: vertex_indices | vertex_index (triangulated as a fan),
// material_index | texnumber, and texcoord (MeshLab's per-corner UVs: a vertex with several becomes
// one vertex per UV). Header comments "TextureFile NAME" (MeshLab's) name each texnumber's texture.
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/heap.h"
#include "io/text_reader.h"
#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

enum class Type : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

constexpr size_t type_size(Type t) {
  constexpr size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return sizes[size_t(t)];
}
constexpr bool is_float(Type t) { return t == Type::f32 || t == Type::f64; }

std::optional<Type> parse_type(std::string_view s) {
  static constexpr std::pair<std::string_view, Type> names[] = {
      {"char", Type::i8},     {"int8", Type::i8},     {"uchar", Type::u8},   {"uint8", Type::u8},
      {"short", Type::i16},   {"int16", Type::i16},   {"ushort", Type::u16}, {"uint16", Type::u16},
      {"int", Type::i32},     {"int32", Type::i32},   {"uint", Type::u32},   {"uint32", Type::u32},
      {"float", Type::f32},   {"float32", Type::f32}, {"double", Type::f64}, {"float64", Type::f64}};
  for (const auto& [name, type] : names)
    if (s == name) return type;
  return std::nullopt;
}

// Largest value of an integer type, the scale that maps integer colours onto [0, 1].
double type_max(Type t) {
  switch (t) {
    case Type::i8: return 127;
    case Type::u8: return 255;
    case Type::i16: return 32767;
    case Type::u16: return 65535;
    case Type::i32: return 2147483647.0;
    case Type::u32: return 4294967295.0;
    default: return 1;
  }
}

// Where a property's values go.
enum class Target : uint8_t { skip, float_stream, color, joint, indices, material, corner_uvs };

struct Property {
  std::string name;
  Type type = Type::f32;
  bool list = false;
  Type count_type = Type::u8;
  Target target = Target::skip;
  float* floats = nullptr;      // float_stream / color: component 0 of vertex 0
  uint16_t* ushorts = nullptr;  // joint
  size_t stride = 0;            // in components
  double scale = 1;             // color: 1 / type max
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  uint64_t line = 0;
  // Smallest number of bytes one record can take: binary sizes, or 2 characters per value in ASCII.
  uint64_t min_record_bytes(bool ascii) const {
    uint64_t n = 0;
    for (const Property& p : properties) n += ascii ? 2 : type_size(p.list ? p.count_type : p.type);
    return n;
  }
};

enum class Format { ascii, binary_le, binary_be };

// Binary value source: bounds-checked loads with byte order applied.
class BinarySource {
 public:
  BinarySource(std::span<const uint8_t> bytes, size_t offset, const std::string& name, bool big_endian)
      : begin_(bytes.data()), p_(bytes.data() + offset), end_(bytes.data() + bytes.size()), name_(name),
        swap_(big_endian != (std::endian::native == std::endian::big)) {}

  double value(Type t) {
    const size_t n = type_size(t);
    last_ = p_;
    if (size_t(end_ - p_) < n) fail(std::string("unexpected end of file, expected a ") + type_name(t) + " value");
    p_ += n;
    switch (t) {
      case Type::i8: return load<int8_t>(last_);
      case Type::u8: return load<uint8_t>(last_);
      case Type::i16: return load<int16_t>(last_);
      case Type::u16: return load<uint16_t>(last_);
      case Type::i32: return load<int32_t>(last_);
      case Type::u32: return load<uint32_t>(last_);
      case Type::f32: return load<float>(last_);
      default: return load<double>(last_);
    }
  }
  void skip(uint64_t bytes) {
    last_ = p_;
    if (bytes > uint64_t(end_ - p_)) fail("unexpected end of file in a skipped element");
    p_ += bytes;
  }
  uint64_t remaining() const { return uint64_t(end_ - p_); }
  // `bytes` bytes at the cursor, consumed; the caller has checked they exist.
  const uint8_t* take_block(uint64_t bytes) {
    last_ = p_;
    p_ += bytes;
    return last_;
  }
  [[noreturn]] void fail_at(const uint8_t* at, const std::string& what) const {
    throw_bad_input_at_byte(name_, size_t(at - begin_), what);
  }
  template <class T>
  double load(const uint8_t* p) const {
    uint8_t raw[sizeof(T)];
    std::memcpy(raw, p, sizeof(T));
    if (swap_) std::reverse(raw, raw + sizeof(T));
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return double(v);
  }
  double fraction() const { return double(p_ - begin_) / double(std::max<ptrdiff_t>(1, end_ - begin_)); }
  // Errors point at the start of the value just read (or that could not be read).
  [[noreturn]] void fail(const std::string& what) const { throw_bad_input_at_byte(name_, size_t(last_ - begin_), what); }

 private:
  static const char* type_name(Type t) {
    constexpr const char* names[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
    return names[size_t(t)];
  }
  const uint8_t* begin_;
  const uint8_t* p_;
  const uint8_t* end_;
  const uint8_t* last_ = p_;
  const std::string& name_;
  bool swap_;
};

// ASCII value source: whitespace-separated numbers; records may wrap lines.
class AsciiSource {
 public:
  explicit AsciiSource(io::TextReader& in) : in_(in) {}

  double value(Type t) {
    while (in_.at_line_end()) {
      if (in_.at_end()) fail("unexpected end of file, expected a number");
      in_.next_line();
    }
    const std::string_view token = in_.token();
    if (t == Type::f32) {
      float f;
      if (!io::parse_float(token, f)) fail("expected a finite number, found '" + std::string(token.substr(0, 40)) + "'");
      return f;
    }
    if (t == Type::f64) {
      double d = 0;
      const char* b = token.data() + (token.starts_with('+') ? 1 : 0);
      auto [ptr, ec] = std::from_chars(b, token.data() + token.size(), d);
      if (ec != std::errc() || ptr != token.data() + token.size() || !std::isfinite(d))
        fail("expected a finite number, found '" + std::string(token.substr(0, 40)) + "'");
      return d;
    }
    int64_t i = 0;
    const char* b = token.data() + (token.starts_with('+') ? 1 : 0);
    auto [ptr, ec] = std::from_chars(b, token.data() + token.size(), i);
    if (ec != std::errc() || ptr != token.data() + token.size())
      fail("expected an integer, found '" + std::string(token.substr(0, 40)) + "'");
    const bool is_signed = t == Type::i8 || t == Type::i16 || t == Type::i32;
    const double lo = is_signed ? -type_max(t) - 1 : 0;
    if (double(i) < lo || double(i) > type_max(t)) fail("integer " + std::to_string(i) + " does not fit the property's type");
    return double(i);
  }
  uint64_t remaining() const { return in_.remaining(); }
  double fraction() const { return double(in_.offset()) / double(std::max<size_t>(1, in_.offset() + in_.remaining())); }
  [[noreturn]] void fail(const std::string& what) const { in_.fail(what); }

 private:
  io::TextReader& in_;
};

// What the writer calls each UV set (the reader also takes u v, s t, texture_s texture_t for set 0).
// Set 0 is MeshLab's name: MeshLab reads no other but s t, and Blender, Assimp and VTK read it too.
const char* uv_names[max_uv_sets][2] = {{"texture_u", "texture_v"}, {"u1", "v1"}, {"u2", "v2"}, {"u3", "v3"}};

// Parses the header up to and including "end_header"; the reader is left at the first data byte.
std::vector<Element> parse_header(io::TextReader& in, Format& format, std::vector<std::string>* textures) {
  if (in.at_end()) in.fail("empty file, expected a PLY header");
  if (in.token() != "ply" || !in.at_line_end()) in.fail("not a PLY file: the first line must be 'ply'");
  in.next_line();
  bool have_format = false;
  std::vector<Element> elements;
  for (;;) {
    if (in.at_end()) in.fail("unexpected end of file in the header, expected 'end_header'");
    const std::string_view keyword = in.token();
    if (keyword == "end_header") {
      if (!have_format) in.fail("the header has no 'format' line");
      // Binary data starts right after this line's newline.
      while (!in.at_end() && !in.at_line_end()) in.token();
      in.next_line();
      return elements;
    }
    if (keyword == "format") {
      const std::string_view f = in.token();
      if (f == "ascii") format = Format::ascii;
      else if (f == "binary_little_endian") format = Format::binary_le;
      else if (f == "binary_big_endian") format = Format::binary_be;
      else in.fail("unknown PLY format '" + std::string(f.substr(0, 40)) + "' (expected ascii, binary_little_endian or binary_big_endian)");
      if (in.token() != "1.0") in.fail("unsupported PLY version, expected 1.0");
      have_format = true;
    } else if (keyword == "element") {
      Element e;
      e.name = std::string(in.token());
      if (e.name.empty()) in.fail("element without a name");
      e.count = in.read_uint("the element count");
      e.line = in.line();
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (elements.empty()) in.fail("'property' before any 'element'");
      Property p;
      std::string_view type = in.token();
      if (type == "list") {
        p.list = true;
        const std::string_view count_type = in.token();
        const auto ct = parse_type(count_type);
        if (!ct || is_float(*ct)) in.fail("list count type must be an integer type, found '" + std::string(count_type.substr(0, 40)) + "'");
        p.count_type = *ct;
        type = in.token();
      }
      const auto t = parse_type(type);
      if (!t) in.fail("unknown property type '" + std::string(type.substr(0, 40)) + "'");
      p.type = *t;
      p.name = std::string(in.token());
      if (p.name.empty()) in.fail("property without a name");
      elements.back().properties.push_back(std::move(p));
    } else if (keyword == "comment") {
      if (in.token() == "TextureFile" && textures) {
        const std::string_view file = in.rest_of_line();
        if (!file.empty()) textures->emplace_back(file);
      }
    } else if (keyword != "obj_info" && !keyword.empty()) {
      in.fail("unexpected header line starting with '" + std::string(keyword.substr(0, 40)) + "'");
    }
    in.next_line();
  }
}

// Points each vertex property at its stream in `mesh` (sized to `count`); unknown ones are skipped.
void bind_vertex_properties(Element& e, Mesh& mesh, const io::TextReader& in) {
  auto find = [&](std::initializer_list<const char*> names) -> Property* {
    for (const char* n : names)
      for (Property& p : e.properties)
        if (!p.list && p.name == n) return &p;
    return nullptr;
  };
  auto bind = [&](auto& stream, size_t components, std::initializer_list<std::initializer_list<const char*>> names,
                  Target target) {
    std::vector<Property*> found;
    for (auto alternatives : names) found.push_back(find(alternatives));
    if (std::none_of(found.begin(), found.end(), [](Property* p) { return p; })) return false;
    core::assign_huge(stream, e.count, {});  // huge pages: the stream is filled once, front to back
    if (stream.empty()) return true;  // no records: nothing to point at
    for (size_t c = 0; c < found.size(); ++c) {
      if (!found[c]) continue;
      found[c]->target = target;
      found[c]->stride = components;
      if constexpr (std::is_same_v<typename std::decay_t<decltype(stream)>::value_type, ushort4>)
        found[c]->ushorts = reinterpret_cast<uint16_t*>(stream.data()) + c;
      else
        found[c]->floats = reinterpret_cast<float*>(stream.data()) + c;
      if (target == Target::color) found[c]->scale = 1.0 / type_max(found[c]->type);
    }
    return true;
  };
  if (!find({"x"}) || !find({"y"}) || !find({"z"})) in.fail("the vertex element needs x, y and z properties");
  bind(mesh.positions, 3, {{"x"}, {"y"}, {"z"}}, Target::float_stream);
  bind(mesh.normals, 3, {{"nx"}, {"ny"}, {"nz"}}, Target::float_stream);
  bind(mesh.tangents, 4, {{"tx"}, {"ty"}, {"tz"}, {"tw"}}, Target::float_stream);
  bind(mesh.uvs[0], 2, {{"u", "s", "texture_u", "texture_s"}, {"v", "t", "texture_v", "texture_t"}}, Target::float_stream);
  for (size_t k = 1; k < max_uv_sets; ++k) bind(mesh.uvs[k], 2, {{uv_names[k][0]}, {uv_names[k][1]}}, Target::float_stream);
  if (bind(mesh.colors, 4, {{"red", "r"}, {"green", "g"}, {"blue", "b"}, {"alpha", "a"}}, Target::color) && !find({"alpha", "a"}))
    for (float4& c : mesh.colors) c.w = 1;
  bind(mesh.joints, 4, {{"joint0"}, {"joint1"}, {"joint2"}, {"joint3"}}, Target::joint);
  bind(mesh.weights, 4, {{"weight0"}, {"weight1"}, {"weight2"}, {"weight3"}}, Target::float_stream);
  bind(mesh.joints1, 4, {{"joint4"}, {"joint5"}, {"joint6"}, {"joint7"}}, Target::joint);
  bind(mesh.weights1, 4, {{"weight4"}, {"weight5"}, {"weight6"}, {"weight7"}}, Target::float_stream);
  if (e.count > 0 && (mesh.joints.empty() != mesh.weights.empty() || mesh.joints1.empty() != mesh.weights1.empty()))
    throw_bad_input_at_line(in.name(), e.line, "skin joints (joint0..7) and weights (weight0..7) must come together");
  if (e.count > 0 && mesh.joints.empty() && !mesh.joints1.empty())
    throw_bad_input_at_line(in.name(), e.line, "skin influences 4..7 need influences 0..3");
}

// Binary element without lists (vertices, nearly always): every record has the same size, so the
// block is bounds-checked once and each mapped property decoded as one typed column.
template <class T>
void decode_column(BinarySource& src, const uint8_t* block, uint64_t count, uint64_t record, uint64_t offset,
                   const Property& p, const std::string& element) {
  for (uint64_t r = 0; r < count; ++r) {
    const uint8_t* at = block + r * record + offset;
    const double v = src.load<T>(at);
    if (p.target == Target::joint) {
      if (!(v >= 0 && v <= 65535)) src.fail_at(at, element + " " + std::to_string(r) + ": joint index outside 0..65535");
      p.ushorts[r * p.stride] = uint16_t(v);
    } else {
      const float f = float(v * p.scale);
      if (!std::isfinite(f)) src.fail_at(at, element + " " + std::to_string(r) + ": property '" + p.name + "' is not a finite number");
      p.floats[r * p.stride] = f;
    }
  }
}

bool has_lists(const Element& e) {
  return std::any_of(e.properties.begin(), e.properties.end(), [](const Property& p) { return p.list; });
}

void read_fixed_element(BinarySource& src, const Element& e) {
  const uint64_t record = e.min_record_bytes(false);
  if (e.count > src.remaining() / record)
    src.fail("element '" + e.name + "' needs " + std::to_string(e.count) + " records of " + std::to_string(record) +
             " bytes, the file ends first");
  const uint8_t* block = src.take_block(e.count * record);
  uint64_t offset = 0;
  for (const Property& p : e.properties) {
    if (p.target == Target::float_stream || p.target == Target::color || p.target == Target::joint) {
      switch (p.type) {
        case Type::i8: decode_column<int8_t>(src, block, e.count, record, offset, p, e.name); break;
        case Type::u8: decode_column<uint8_t>(src, block, e.count, record, offset, p, e.name); break;
        case Type::i16: decode_column<int16_t>(src, block, e.count, record, offset, p, e.name); break;
        case Type::u16: decode_column<uint16_t>(src, block, e.count, record, offset, p, e.name); break;
        case Type::i32: decode_column<int32_t>(src, block, e.count, record, offset, p, e.name); break;
        case Type::u32: decode_column<uint32_t>(src, block, e.count, record, offset, p, e.name); break;
        case Type::f32: decode_column<float>(src, block, e.count, record, offset, p, e.name); break;
        case Type::f64: decode_column<double>(src, block, e.count, record, offset, p, e.name); break;
      }
    }
    offset += type_size(p.type);
  }
}

// One face corner, range-checked against the vertex count.
template <class Source>
uint32_t read_index(Source& src, uint64_t face, uint64_t vertex_count, Type type) {
  const double index = src.value(type);
  if (!(index >= 0 && index < double(vertex_count)))
    src.fail("face " + std::to_string(face) + ": vertex index " + std::to_string(int64_t(index)) + " is outside 0.." +
             std::to_string(vertex_count ? vertex_count - 1 : 0));
  return uint32_t(index);
}

// Reads every record of one element from `src`: vertex values land in their streams, face corners
// are range-checked and triangulated, everything else is consumed and dropped.
template <class Source>
void read_element(Source& src, const Element& e, bool is_face, uint64_t vertex_count, Mesh& mesh,
                  std::vector<float2>& corner_uvs, const ReadOptions& options) {
  const auto has = [&](Target t) {
    return is_face && std::any_of(e.properties.begin(), e.properties.end(), [&](const Property& p) { return p.target == t; });
  };
  const bool with_materials = has(Target::material), with_uvs = has(Target::corner_uvs);
  std::vector<uint32_t> polygon;
  std::vector<float2> uvs;  // this face's texcoord list
  for (uint64_t r = 0; r < e.count; ++r) {
    if (options.progress && (r & 0x3ffff) == 0x3ffff) options.progress(src.fraction());
    uint32_t material = 0;
    uint64_t corners = 0;
    for (const Property& p : e.properties) {
      if (p.list) {
        const double count = src.value(p.count_type);
        if (count < 0) src.fail(e.name + " " + std::to_string(r) + ": negative list length");
        const uint64_t n = uint64_t(count);
        if (p.target == Target::corner_uvs) {
          if (n % 2 != 0 || n / 2 > io::max_face_corners)
            src.fail("face " + std::to_string(r) + ": a texcoord list of " + std::to_string(n) + " values is not a (u, v) per corner");
          uvs.clear();
          for (uint64_t i = 0; i < n / 2; ++i) {
            const float u = float(src.value(p.type)), v = float(src.value(p.type));
            if (!std::isfinite(u) || !std::isfinite(v)) src.fail("face " + std::to_string(r) + ": texcoord is not a finite number");
            uvs.push_back({u, v});
          }
          continue;
        }
        if (p.target != Target::indices) {
          if constexpr (std::is_same_v<Source, BinarySource>) {
            if (n > src.remaining() / type_size(p.type))
              src.fail(e.name + " " + std::to_string(r) + ": a list of " + std::to_string(n) + " values runs past the end of the file");
            src.skip(n * type_size(p.type));
          } else {
            for (uint64_t i = 0; i < n; ++i) src.value(p.type);
          }
          continue;
        }
        if (n < 3 || n > io::max_face_corners) src.fail(io::polygon_size_problem("face " + std::to_string(r), n));
        corners = n;
        if (n == 3) {  // the common case, without the polygon buffer
          // push_back, not a range insert: that one calls memmove per triangle.
          for (int k = 0; k < 3; ++k) mesh.indices.push_back(read_index(src, r, vertex_count, p.type));
          continue;
        }
        polygon.clear();
        for (uint64_t i = 0; i < n; ++i) {
          polygon.push_back(read_index(src, r, vertex_count, p.type));
        }
        io::append_fan(mesh.indices, polygon);
        continue;
      }
      const double v = src.value(p.type);
      switch (p.target) {
        case Target::float_stream:
        case Target::color: {
          const float f = float(v * p.scale);
          if (!std::isfinite(f)) src.fail(e.name + " " + std::to_string(r) + ": property '" + p.name + "' is not a finite number");
          p.floats[r * p.stride] = f;
          break;
        }
        case Target::joint:
          if (!(v >= 0 && v <= 65535)) src.fail(e.name + " " + std::to_string(r) + ": joint index outside 0..65535");
          p.ushorts[r * p.stride] = uint16_t(v);
          break;
        case Target::material:
          if (!(v >= 0 && v <= double(UINT32_MAX))) src.fail("face " + std::to_string(r) + ": material index outside 0..2^32-1");
          material = uint32_t(v);
          break;
        default: break;
      }
    }
    // The material and UVs may be listed before or after the corners: apply them once the record is
    // complete.
    if (with_materials) mesh.materials.resize(mesh.triangle_count(), material);
    if (with_uvs) {
      if (uvs.size() != corners)
        src.fail("face " + std::to_string(r) + ": texcoord has " + std::to_string(uvs.size()) + " (u, v) pairs for " +
                 std::to_string(corners) + " corners");
      io::append_fan(corner_uvs, uvs);
      uvs.clear();
    }
  }
}

// The mesh with `uvs` (one per corner) as its UV set 0: each (vertex, UV) pair one vertex, in order
// of first use; a vertex no face uses is dropped.
Mesh with_corner_uvs(const Mesh& mesh, const std::vector<float2>& uvs) {
  struct Key {
    uint32_t vertex, u, v;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      return std::hash<uint64_t>()((uint64_t(k.vertex) << 32 | k.u) * 0x9E3779B97F4A7C15ull ^ k.v);
    }
  };
  Mesh out;
  copy_id_tables(out, mesh);
  out.materials = mesh.materials;
  out.groups = mesh.groups;
  out.indices.reserve(mesh.indices.size());
  std::unordered_map<Key, uint32_t, Hash> vertex_of;
  for (size_t c = 0; c < mesh.indices.size(); ++c) {
    const Key key{mesh.indices[c], std::bit_cast<uint32_t>(uvs[c].x), std::bit_cast<uint32_t>(uvs[c].y)};
    const auto [it, inserted] = vertex_of.try_emplace(key, uint32_t(out.vertex_count()));
    if (inserted) {
      append_vertex(out, mesh, key.vertex);
      out.uvs[0].resize(out.vertex_count());
      out.uvs[0].back() = uvs[c];
    }
    out.indices.push_back(it->second);
  }
  return out;
}

// MeshLab's link from faces to textures, for a mesh with UVs whose materials have base colour
// textures: "comment TextureFile" lines, one per texture number, and a face's texnumber. PLY keeps
// no material table, so the ids are free to renumber: the used materials with a texture come
// first, in id order, each its texture's number (no gap for a line to stand in); the other used
// ones follow, numbers without a texture (MeshLab draws them untextured). With no texture to name,
// nothing changes: material_index keeps the mesh's ids.
struct TextureTable {
  std::vector<std::string> files;  // texture k's path, as the PLY's folder names it
  std::vector<uint32_t> used;      // the material ids faces use, ascending
  std::vector<uint32_t> new_id;    // by position in `used`
  uint32_t renumber(uint32_t id) const { return new_id[size_t(std::lower_bound(used.begin(), used.end(), id) - used.begin())]; }
};

TextureTable texture_table(const Mesh& mesh, const std::filesystem::path& folder) {
  TextureTable table;
  if (mesh.uvs[0].empty() || mesh.triangle_count() == 0) return table;
  // (Sorted rather than flagged by id: a bad input's ids go up to 2^32 - 1.)
  table.used = mesh.materials.empty() ? std::vector<uint32_t>{0} : mesh.materials;
  std::sort(table.used.begin(), table.used.end());
  table.used.erase(std::unique(table.used.begin(), table.used.end()), table.used.end());
  const auto textured = [&](uint32_t id) { return id < mesh.material_looks.size() && !mesh.material_looks[id].base_color_texture.empty(); };
  table.new_id.assign(table.used.size(), 0);
  uint32_t next = 0;
  for (size_t k = 0; k < table.used.size(); ++k)
    if (textured(table.used[k]))
      table.new_id[k] = next++, table.files.push_back(io::path_from(mesh.material_looks[table.used[k]].base_color_texture, folder));
  if (table.files.empty()) return {};
  for (size_t k = 0; k < table.used.size(); ++k)
    if (!textured(table.used[k])) table.new_id[k] = next++;
  return table;
}

}  // namespace

Mesh read_ply(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options,
              std::vector<std::string>* textures) {
  io::TextReader in(bytes, name, &options);
  Format format = Format::ascii;
  std::vector<Element> elements = parse_header(in, format, textures);
  const bool ascii = format == Format::ascii;

  // Bound every declared count by the bytes left before reserving anything, so a 200-byte file
  // cannot make us allocate for four billion elements.
  uint64_t budget = in.remaining();
  Element* vertex = nullptr;
  Element* face = nullptr;
  for (Element& e : elements) {
    if (e.name == "vertex" && !vertex) vertex = &e;
    if (e.name == "face" && !face) face = &e;
    const uint64_t record = e.min_record_bytes(ascii);
    if (record == 0) continue;
    if (e.count > budget / record)
      throw_bad_input_at_line(name, e.line,
                              "element '" + e.name + "' declares " + std::to_string(e.count) + " records, more than the " +
                                  std::to_string(in.remaining()) + " data bytes can hold");
    budget -= e.count * record;
  }
  if (!vertex) in.fail("the header declares no 'vertex' element");
  if (vertex->count > UINT32_MAX) throw_bad_input_at_line(name, vertex->line, "more than 2^32 - 1 vertices");

  Mesh mesh;
  bind_vertex_properties(*vertex, mesh, in);
  if (face) {
    Element& f = *face;
    bool have_indices = false;
    for (Property& p : f.properties) {
      if (p.list && !have_indices && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (is_float(p.type)) throw_bad_input_at_line(name, f.line, "face vertex indices must have an integer type");
        p.target = Target::indices;
        have_indices = true;
      } else if (!p.list && (p.name == "material_index" || p.name == "texnumber") &&
                 std::none_of(f.properties.begin(), f.properties.end(), [](const Property& q) { return q.target == Target::material; })) {
        p.target = Target::material;
      } else if (p.list && p.name == "texcoord" && is_float(p.type)) {
        p.target = Target::corner_uvs;
      }
    }
    if (!have_indices && f.count > 0) throw_bad_input_at_line(name, f.line, "the face element has no vertex_indices list");
    core::reserve_huge(mesh.indices, f.count * 3);
  }

  const size_t data_offset = in.offset();
  BinarySource binary(bytes, data_offset, name, format == Format::binary_be);
  AsciiSource text(in);
  std::vector<float2> corner_uvs;
  for (const Element& e : elements) {
    if (e.properties.empty()) continue;  // no data to consume
    // A second vertex or face element is read but dropped, like any unknown element.
    const bool is_face = &e == face;
    if (ascii) read_element(text, e, is_face, vertex->count, mesh, corner_uvs, options);
    else if (!has_lists(e)) read_fixed_element(binary, e);
    else read_element(binary, e, is_face, vertex->count, mesh, corner_uvs, options);
  }
  if (!corner_uvs.empty()) mesh = with_corner_uvs(mesh, corner_uvs);
  make_unit_directions(mesh);
  return mesh;
}

void write_ply(const Mesh& mesh, std::string& out, const WriteOptions& options, const std::filesystem::path& folder) {
  const bool binary = options.binary;
  out += "ply\nformat ";
  out += binary ? "binary_little_endian" : "ascii";
  out += " 1.0\ncomment written by lodkit\n";
  const TextureTable textures = texture_table(mesh, folder);
  for (const std::string& file : textures.files) out += "comment TextureFile " + file + '\n';
  out += "element vertex ";
  io::append_uint(out, mesh.vertex_count());
  out += '\n';
  // One list of float components per vertex, in header order; joints are written separately.
  std::vector<std::pair<const float*, size_t>> streams;  // (component 0 of vertex 0, stride)
  // Positions are always declared, so even an empty mesh reads back.
  auto declare = [&](const auto& stream, size_t components, std::initializer_list<const char*> names) {
    if (stream.empty() && static_cast<const void*>(&stream) != &mesh.positions) return;
    size_t c = 0;
    for (const char* n : names) {
      out += "property float ";
      out += n;
      out += '\n';
      // No pointer arithmetic on an empty stream's null data (there are no vertices to write then).
      if (!stream.empty()) streams.emplace_back(reinterpret_cast<const float*>(stream.data()) + c, components);
      ++c;
    }
  };
  declare(mesh.positions, 3, {"x", "y", "z"});
  declare(mesh.normals, 3, {"nx", "ny", "nz"});
  declare(mesh.tangents, 4, {"tx", "ty", "tz", "tw"});
  for (size_t k = 0; k < max_uv_sets; ++k) declare(mesh.uvs[k], 2, {uv_names[k][0], uv_names[k][1]});
  // Colours in unsigned bytes, PLY's custom and the only type MeshLab reads, when that is exact
  // (every channel k / 255, as the reader scales it); floats otherwise, which keep any value.
  const bool byte_colors = std::all_of(mesh.colors.begin(), mesh.colors.end(), [](const float4& c) {
    return std::all_of(&c.x, &c.x + 4, [](float v) {
      const double k = std::round(double(v) * 255);
      return k >= 0 && k <= 255 && float(k * (1.0 / type_max(Type::u8))) == v;
    });
  });
  if (!byte_colors) declare(mesh.colors, 4, {"red", "green", "blue", "alpha"});
  declare(mesh.weights, 4, {"weight0", "weight1", "weight2", "weight3"});
  declare(mesh.weights1, 4, {"weight4", "weight5", "weight6", "weight7"});
  // Byte colours after the floats (each record is the float streams, then bytes, then joints).
  const std::vector<float4>* colors = byte_colors && !mesh.colors.empty() ? &mesh.colors : nullptr;
  if (colors)
    for (const char* n : {"red", "green", "blue", "alpha"}) out += std::string("property uchar ") + n + '\n';
  // Joint indices last, as ushorts: joint0..3, then joint4..7 for a second influence set.
  std::vector<const std::vector<ushort4>*> joint_sets;
  for (const auto* set : {&mesh.joints, &mesh.joints1})
    if (!set->empty()) joint_sets.push_back(set);
  for (size_t k = 0; k < 4 * joint_sets.size(); ++k) {
    out += "property ushort joint";
    io::append_uint(out, k);
    out += '\n';
  }
  out += "element face ";
  io::append_uint(out, mesh.triangle_count());
  out += "\nproperty list uchar uint vertex_indices\n";
  const bool materials = !mesh.materials.empty();
  // MeshLab takes a face's texnumber only beside per-corner UVs (and with that type): with more
  // than one texture, the corners repeat their vertices' UVs.
  const bool corner_uvs = textures.files.size() > 1;
  if (corner_uvs) out += "property list uchar float texcoord\n";
  if (materials) out += textures.files.empty() ? "property uint material_index\n" : "property int texnumber\n";
  out += "end_header\n";
  const auto material = [&](size_t t) { return textures.files.empty() ? mesh.materials[t] : textures.renumber(mesh.materials[t]); };

  const size_t vertex_bytes = streams.size() * 4 + 4 * (colors != nullptr) + 8 * joint_sets.size();
  out.reserve(out.size() + (binary ? mesh.vertex_count() * vertex_bytes + mesh.triangle_count() * (13 + 4 * materials + 25 * corner_uvs)
                                   : mesh.vertex_count() * streams.size() * 12 + mesh.triangle_count() * 24));
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    for (size_t s = 0; s < streams.size(); ++s) {
      const float f = streams[s].first[v * streams[s].second];
      if (binary) {
        io::append_binary(out, f);
      } else {
        if (s) out += ' ';
        io::append_float(out, f);
      }
    }
    if (colors) {
      const float4& c = (*colors)[v];
      for (float f : {c.x, c.y, c.z, c.w}) {
        const auto byte = uint8_t(std::lround(double(f) * 255));
        if (binary) {
          out += char(byte);
        } else {
          out += ' ';
          io::append_uint(out, byte);
        }
      }
    }
    for (const auto* set : joint_sets) {
      for (uint16_t value : (*set)[v]) {
        if (binary) {
          io::append_binary(out, value);
        } else {
          out += ' ';
          io::append_uint(out, value);
        }
      }
    }
    if (!binary) out += '\n';
  }
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    const uint32_t* c = &mesh.indices[3 * t];
    if (binary) {
      out += char(3);
      io::append_binary(out, c[0]), io::append_binary(out, c[1]), io::append_binary(out, c[2]);
      if (corner_uvs) {
        out += char(6);
        for (size_t k = 0; k < 3; ++k) io::append_binary(out, mesh.uvs[0][c[k]].x), io::append_binary(out, mesh.uvs[0][c[k]].y);
      }
      if (materials) io::append_binary(out, material(t));
    } else {
      out += "3 ";
      io::append_uint(out, c[0]), out += ' ', io::append_uint(out, c[1]), out += ' ', io::append_uint(out, c[2]);
      if (corner_uvs) {
        out += " 6";
        for (size_t k = 0; k < 3; ++k) out += ' ', io::append_float(out, mesh.uvs[0][c[k]].x), out += ' ', io::append_float(out, mesh.uvs[0][c[k]].y);
      }
      if (materials) out += ' ', io::append_uint(out, material(t));
      out += '\n';
    }
  }
}

}  // namespace lod
