// OFF, with the [ST][C][N]OFF variants (texture coordinates, colours, normals per vertex).
// Vertex lines hold x y z [nx ny nz] [r g b [a]] [s t]; face lines n i0 .. i(n-1) [colour, ignored].
#include <algorithm>
#include <string>

#include "core/heap.h"
#include "io/text_reader.h"
#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

struct OffHeader {
  bool uv = false, color = false, normal = false;
};

bool is_integer_token(std::string_view t) {
  return !t.empty() && std::all_of(t.begin(), t.end(), [](char c) { return (c >= '0' && c <= '9') || c == '-' || c == '+'; });
}

OffHeader parse_keyword(std::string_view key, const io::TextReader& in) {
  OffHeader h;
  std::string_view k = key;
  if (k.size() < 3 || k.substr(k.size() - 3) != "OFF")
    in.fail("expected an OFF header keyword ([ST][C][N]OFF), found '" + std::string(key.substr(0, 40)) + "'");
  k.remove_suffix(3);
  if (k.starts_with("ST")) h.uv = true, k.remove_prefix(2);
  if (k.starts_with("C")) h.color = true, k.remove_prefix(1);
  if (k.starts_with("N")) h.normal = true, k.remove_prefix(1);
  if (k.starts_with("4") || k.starts_with("n")) in.fail("'" + std::string(key) + "': only 3D OFF files are supported");
  if (!k.empty()) in.fail("unknown OFF header keyword '" + std::string(key.substr(0, 40)) + "'");
  return h;
}

}  // namespace

Mesh read_off(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options) {
  io::TextReader in(bytes, name, &options);
  in.set_comment('#');
  in.skip_empty_lines('#');
  if (in.at_end()) in.fail("empty file, expected an OFF header");
  // The keyword may share its line with the counts ("OFF 8 6 0").
  const OffHeader header = parse_keyword(in.token(), in);
  if (in.peek_token() == "BINARY") in.fail("binary OFF is not supported");
  if (in.at_line_end()) {
    in.next_line();
    in.skip_empty_lines('#');
  }
  const uint64_t vertex_count = in.read_uint("the vertex count");
  const uint64_t face_count = in.read_uint("the face count");
  if (!in.at_line_end()) in.read_uint("the edge count");
  // Each vertex needs at least "0 0 0\n" and each face "3 0 1 2\n": bound declared counts by the
  // bytes left before reserving anything.
  if (vertex_count > in.remaining() / 6 || face_count > in.remaining() / 8)
    in.fail("header declares " + std::to_string(vertex_count) + " vertices and " + std::to_string(face_count) +
            " faces, more than the " + std::to_string(in.remaining()) + " remaining bytes can hold");
  if (vertex_count > UINT32_MAX) in.fail("too many vertices");
  in.next_line();

  Mesh mesh;
  core::reserve_huge(mesh.positions, vertex_count);
  if (header.normal) core::reserve_huge(mesh.normals, vertex_count);
  if (header.color) core::reserve_huge(mesh.colors, vertex_count);
  if (header.uv) mesh.uvs[0].reserve(vertex_count);

  float values[13];
  std::string_view tokens[13];
  for (uint64_t v = 0; v < vertex_count; ++v) {
    in.skip_empty_lines('#');
    if (in.at_end()) in.fail("unexpected end of file: expected vertex " + std::to_string(v) + " of " + std::to_string(vertex_count));
    size_t n = 0;
    while (!in.at_line_end() && n < 13) {
      tokens[n++] = in.token();
    }
    const size_t fixed = 3 + (header.normal ? 3 : 0) + (header.uv ? 2 : 0);
    size_t color_count = header.color ? n - std::min(n, fixed) : 0;
    if (n < fixed + (header.color ? 3 : 0) || (header.color && color_count != 3 && color_count != 4) || (!header.color && n != fixed))
      in.fail("vertex " + std::to_string(v) + " has " + std::to_string(n) + " values, expected " + std::to_string(fixed) +
               (header.color ? " plus 3 or 4 colour components" : ""));
    for (size_t i = 0; i < n; ++i) {
      if (!io::parse_float(tokens[i], values[i]))
        in.fail("vertex " + std::to_string(v) + ": expected a finite number, found '" + std::string(tokens[i].substr(0, 40)) + "'");
    }
    size_t k = 0;
    mesh.positions.push_back({values[0], values[1], values[2]});
    k = 3;
    if (header.normal) mesh.normals.push_back({values[k], values[k + 1], values[k + 2]}), k += 3;
    if (header.color) {
      // Integer components above 1 are 0..255; otherwise the components are floats in [0, 1].
      bool bytes_scale = false;
      for (size_t i = k; i < k + color_count; ++i)
        if (is_integer_token(tokens[i]) && values[i] > 1.0f) bytes_scale = true;
      float s = bytes_scale ? 1.0f / 255.0f : 1.0f;
      mesh.colors.push_back({values[k] * s, values[k + 1] * s, values[k + 2] * s, color_count == 4 ? values[k + 3] * s : 1.0f});
      k += color_count;
    }
    if (header.uv) mesh.uvs[0].push_back({values[k], values[k + 1]});
    in.next_line();
  }

  core::reserve_huge(mesh.indices, face_count * 3);
  std::vector<uint32_t> polygon;
  for (uint64_t f = 0; f < face_count; ++f) {
    in.skip_empty_lines('#');
    if (in.at_end()) in.fail("unexpected end of file: expected face " + std::to_string(f) + " of " + std::to_string(face_count));
    const uint64_t corners = in.read_uint("the face's vertex count");
    if (corners < 3 || corners > io::max_face_corners) in.fail(io::polygon_size_problem("face " + std::to_string(f), corners));
    polygon.clear();
    for (uint64_t i = 0; i < corners; ++i) {
      int64_t index = in.read_int("a vertex index");
      if (index < 0 || uint64_t(index) >= vertex_count)
        in.fail("face " + std::to_string(f) + ": vertex index " + std::to_string(index) + " is outside 0.." +
                std::to_string(vertex_count ? vertex_count - 1 : 0));
      polygon.push_back(uint32_t(index));
    }
    // Trailing face colour values are allowed and ignored.
    io::append_fan(mesh.indices, polygon);
    in.next_line();
  }
  make_unit_directions(mesh);
  return mesh;
}

void write_off(const Mesh& mesh, std::string& out, const WriteOptions&) {
  const bool uv = !mesh.uvs[0].empty(), color = !mesh.colors.empty(), normal = !mesh.normals.empty();
  out += uv ? "ST" : "";
  out += color ? "C" : "";
  out += normal ? "N" : "";
  out += "OFF\n";
  io::append_uint(out, mesh.vertex_count());
  out += ' ';
  io::append_uint(out, mesh.triangle_count());
  out += " 0\n";
  // Colours are written as floats with a decimal point so the reader never takes them for 0..255.
  auto put_color = [&](float c) {
    size_t start = out.size();
    io::append_float(out, c);
    if (out.find_first_of(".e", start) == std::string::npos) out += ".0";
  };
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    const float3& p = mesh.positions[v];
    io::append_float(out, p.x), out += ' ', io::append_float(out, p.y), out += ' ', io::append_float(out, p.z);
    if (normal) {
      const float3& n = mesh.normals[v];
      out += ' ', io::append_float(out, n.x), out += ' ', io::append_float(out, n.y), out += ' ', io::append_float(out, n.z);
    }
    if (color) {
      const float4& c = mesh.colors[v];
      out += ' ', put_color(c.x), out += ' ', put_color(c.y), out += ' ', put_color(c.z), out += ' ', put_color(c.w);
    }
    if (uv) {
      const float2& t = mesh.uvs[0][v];
      out += ' ', io::append_float(out, t.x), out += ' ', io::append_float(out, t.y);
    }
    out += '\n';
  }
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    out += "3 ";
    io::append_uint(out, mesh.indices[3 * t]), out += ' ';
    io::append_uint(out, mesh.indices[3 * t + 1]), out += ' ';
    io::append_uint(out, mesh.indices[3 * t + 2]), out += '\n';
  }
}

}  // namespace lod
