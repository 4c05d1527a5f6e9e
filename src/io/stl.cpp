// STL, ASCII and binary. STL stores three positions per triangle and nothing else that lodkit maps
// (facet normals are recomputed on write; the 16-bit attribute is ignored), so the reader welds
// bit-identical positions into shared vertices.
//
// Binary or ASCII: a file of exactly 84 + 50 n bytes, where n is the count at byte 80, is binary even
// when its header starts with "solid" (many exporters do that); any other file starting with "solid"
// is ASCII; everything else is binary.
#include <cctype>
#include <cmath>
#include <cstring>
#include <string>

#include "core/hash.h"
#include "core/heap.h"
#include "core/vec3d.h"
#include "io/text_reader.h"
#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

constexpr size_t header_bytes = 84, triangle_bytes = 50;

bool starts_with_solid(std::span<const uint8_t> bytes) {
  size_t i = 0;
  while (i < bytes.size() && (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\r' || bytes[i] == '\n')) ++i;
  return bytes.size() - i >= 5 && std::memcmp(bytes.data() + i, "solid", 5) == 0 &&
         (bytes.size() - i == 5 || std::isspace(bytes[i + 5]));
}

uint32_t declared_triangles(std::span<const uint8_t> bytes) {
  uint32_t n = 0;
  if (bytes.size() >= header_bytes) std::memcpy(&n, bytes.data() + 80, 4);  // little-endian on every target we build
  return n;
}

Mesh read_binary(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options) {
  io::BinaryReader in(bytes, name);
  if (bytes.size() < header_bytes)
    in.fail("file of " + std::to_string(bytes.size()) + " bytes is too short for a binary STL (84-byte header) and is not ASCII STL");
  in.seek(80);
  const uint32_t count = in.read<uint32_t>(false, "the triangle count");
  // Bounded by the file size before anything is reserved; trailing bytes after the last triangle are ignored.
  in.require(count, triangle_bytes, "triangles");
  core::PositionWelder welder(size_t(count) * 3 / 2 + 16);
  Mesh mesh;
  core::resize_huge(mesh.indices, size_t(count) * 3);
  for (uint32_t t = 0; t < count; ++t) {
    if (options.progress && (t & 0x3ffff) == 0x3ffff) options.progress(double(t) / count);
    const uint8_t* record = in.take(triangle_bytes, "a triangle");
    float v[9];
    std::memcpy(v, record + 12, sizeof v);  // skip the facet normal
    for (int k = 0; k < 9; ++k)
      if (!std::isfinite(v[k]))
        throw_bad_input_at_byte(name, size_t(record - bytes.data()) + 12 + 4 * k,
                                "triangle " + std::to_string(t) + " has a coordinate that is not a finite number");
    for (int k = 0; k < 3; ++k) mesh.indices[3 * t + k] = welder.insert({v[3 * k], v[3 * k + 1], v[3 * k + 2]});
  }
  mesh.positions = welder.take_unique_positions();
  return mesh;
}

Mesh read_ascii(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options) {
  io::TextReader in(bytes, name, &options);
  auto expect = [&](std::string_view keyword, const char* context) {
    in.skip_empty_lines(0);
    if (in.at_end()) in.fail(std::string("unexpected end of file, expected '") + std::string(keyword) + "' " + context);
    const std::string_view t = in.token();
    if (t != keyword) in.fail(std::string("expected '") + std::string(keyword) + "' " + context + ", found '" + std::string(t.substr(0, 40)) + "'");
  };
  // Each facet takes at least ~100 bytes of text; a cheap hint, never a bound on what we accept.
  core::PositionWelder welder(bytes.size() / 200 + 16);
  Mesh mesh;
  std::vector<uint32_t> polygon;
  in.skip_empty_lines(0);
  while (!in.at_end()) {
    expect("solid", "at the start of a solid");
    in.next_line();  // the solid's name
    for (;;) {
      in.skip_empty_lines(0);
      if (in.at_end()) in.fail("unexpected end of file, expected 'facet' or 'endsolid'");
      const std::string_view keyword = in.token();
      if (keyword == "endsolid") {
        in.next_line();
        break;
      }
      if (keyword != "facet") in.fail("expected 'facet' or 'endsolid', found '" + std::string(keyword.substr(0, 40)) + "'");
      in.next_line();  // "normal nx ny nz": recomputed from the corners when needed
      expect("outer", "after 'facet'");
      if (in.token() != "loop") in.fail("expected 'outer loop'");
      in.next_line();
      polygon.clear();
      for (;;) {
        in.skip_empty_lines(0);
        if (in.at_end()) in.fail("unexpected end of file inside a facet, expected 'vertex' or 'endloop'");
        const std::string_view t = in.token();
        if (t == "endloop") break;
        if (t != "vertex") in.fail("expected 'vertex' or 'endloop', found '" + std::string(t.substr(0, 40)) + "'");
        float3 p;
        p.x = in.read_float("the vertex x coordinate");
        p.y = in.read_float("the vertex y coordinate");
        p.z = in.read_float("the vertex z coordinate");
        if (!in.at_line_end()) in.fail("a vertex line has more than 3 coordinates");
        if (polygon.size() >= io::max_face_corners) in.fail(io::polygon_size_problem("a facet", polygon.size() + 1));
        polygon.push_back(welder.insert(p));
        in.next_line();
      }
      if (polygon.size() < 3) in.fail(io::polygon_size_problem("a facet", polygon.size()));
      in.next_line();
      expect("endfacet", "after 'endloop'");
      in.next_line();
      io::append_fan(mesh.indices, polygon);
    }
    in.skip_empty_lines(0);
  }
  mesh.positions = welder.take_unique_positions();
  return mesh;
}

float3 facet_normal(const float3& a, const float3& b, const float3& c) {
  return core::unit_float3(core::triangle_cross(a, b, c), {0, 0, 0});
}


}  // namespace

Mesh read_stl(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options) {
  if (bytes.empty()) throw_bad_input_at_byte(name, 0, "empty file, expected an STL solid");
  const bool exact_binary_size =
      bytes.size() >= header_bytes && bytes.size() == header_bytes + uint64_t(declared_triangles(bytes)) * triangle_bytes;
  if (!exact_binary_size && starts_with_solid(bytes)) return read_ascii(bytes, name, options);
  return read_binary(bytes, name, options);
}

void write_stl(const Mesh& mesh, std::string& out, const WriteOptions& options) {
  const size_t triangles = mesh.triangle_count();
  if (options.binary) {
    if (triangles > UINT32_MAX) throw_usage("binary STL holds at most 2^32 - 1 triangles");
    // The header must not start with "solid", or readers may take the file for ASCII.
    std::string header = "binary STL written by lodkit";
    header.resize(80, ' ');
    out += header;
    out.reserve(out.size() + 4 + triangles * triangle_bytes);
    io::append_binary(out, uint32_t(triangles));
    for (size_t t = 0; t < triangles; ++t) {
      const float3 &a = mesh.positions[mesh.indices[3 * t]], &b = mesh.positions[mesh.indices[3 * t + 1]],
                   &c = mesh.positions[mesh.indices[3 * t + 2]];
      const float3 n = facet_normal(a, b, c);
      for (const float3& p : {n, a, b, c}) io::append_binary(out, p.x), io::append_binary(out, p.y), io::append_binary(out, p.z);
      io::append_binary(out, uint16_t(0));
    }
    return;
  }
  out += "solid lodkit\n";
  auto put3 = [&](const float3& p) {
    io::append_float(out, p.x), out += ' ', io::append_float(out, p.y), out += ' ', io::append_float(out, p.z), out += '\n';
  };
  for (size_t t = 0; t < triangles; ++t) {
    const float3 &a = mesh.positions[mesh.indices[3 * t]], &b = mesh.positions[mesh.indices[3 * t + 1]],
                 &c = mesh.positions[mesh.indices[3 * t + 2]];
    out += "facet normal ";
    put3(facet_normal(a, b, c));
    out += "outer loop\n";
    for (const float3& p : {a, b, c}) out += "vertex ", put3(p);
    out += "endloop\nendfacet\n";
  }
  out += "endsolid lodkit\n";
}

}  // namespace lod
