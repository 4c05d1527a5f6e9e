// Progressive meshes on the collapse record, and the `.lpm` file.
#include <bit>
#include <cstring>
#include <type_traits>

#include <zlib.h>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/lod.h"
#include "simplify/record.h"

namespace lod {

struct ProgressiveMesh::Impl {
  Mesh input;
  SimplifyRecord record;
  collapse::Replay state;
  size_t applied = 0;
  uint32_t input_positions = 0;

  Impl(Mesh m, SimplifyRecord r) : input(std::move(m)), record(std::move(r)), state(input) {
    input_positions = position_ids(input).count;
  }
};

ProgressiveMesh::ProgressiveMesh() : ProgressiveMesh(Mesh{}, SimplifyRecord{}) {}

ProgressiveMesh::ProgressiveMesh(Mesh input, SimplifyRecord record)
    : impl_(std::make_unique<Impl>(std::move(input), std::move(record))) {
  for (size_t i = 0; i < impl_->record.collapses.size(); ++i) impl_->state.check(impl_->record, i);
  if (impl_->record.collapses.size() > impl_->input_positions)
    throw_usage("progressive mesh: the record has more collapses than the mesh has positions");
}

ProgressiveMesh::~ProgressiveMesh() = default;
ProgressiveMesh::ProgressiveMesh(ProgressiveMesh&&) noexcept = default;
ProgressiveMesh& ProgressiveMesh::operator=(ProgressiveMesh&&) noexcept = default;

size_t ProgressiveMesh::collapse_count() const { return impl_->record.collapses.size(); }
size_t ProgressiveMesh::collapses_applied() const { return impl_->applied; }
uint32_t ProgressiveMesh::max_positions() const { return impl_->input_positions; }
uint32_t ProgressiveMesh::min_positions() const { return impl_->input_positions - uint32_t(collapse_count()); }
uint32_t ProgressiveMesh::positions() const { return impl_->input_positions - uint32_t(impl_->applied); }

void ProgressiveMesh::set_collapses(size_t k) {
  Impl& m = *impl_;
  k = std::min(k, m.record.collapses.size());
  while (m.applied < k) m.state.apply(m.record, m.applied++);  // coarsen
  while (m.applied > k) m.state.undo(m.record, --m.applied);   // vertex split
}

void ProgressiveMesh::refine_to(uint32_t n) {
  n = std::clamp(n, min_positions(), max_positions());
  if (n > positions()) set_collapses(max_positions() - n);
}

void ProgressiveMesh::coarsen_to(uint32_t n) {
  n = std::clamp(n, min_positions(), max_positions());
  if (n < positions()) set_collapses(max_positions() - n);
}

Mesh ProgressiveMesh::mesh() const { return collapse::compact(impl_->input, impl_->state.snapshot(), nullptr, nullptr); }
const Mesh& ProgressiveMesh::input() const { return impl_->input; }
const SimplifyRecord& ProgressiveMesh::record() const { return impl_->record; }

// ---- .lpm ----------------------------------------------------------------------------------------
//
// header:  "LPM\x1a"  u32 version (3)  u64 payload size  u32 CRC-32 of the payload
// payload: the mesh streams, then the record arrays; each array is a u64 count and its elements.
// Version 2 added the second influence set (joints1, weights1) after the weights, version 3 the
// record's influence changes (skinned, multi-pose) at the end; older files, without them, still read.
// All little-endian; the element layouts are the structs' fields in declaration order, 4 bytes each
// (2 for joint indices).

namespace {

static_assert(std::endian::native == std::endian::little, ".lpm is written by copying little-endian memory");
constexpr char magic[4] = {'L', 'P', 'M', '\x1a'};
constexpr uint32_t version = 3;
constexpr size_t header_size = 4 + 4 + 8 + 4;

// Plain structs of 4-byte fields (or arrays of u16) copy as they are.
template <class T>
constexpr bool plain = std::is_trivially_copyable_v<T> && (sizeof(T) % 2 == 0);
static_assert(sizeof(float3) == 12 && sizeof(float4) == 16 && sizeof(ushort4) == 8 && sizeof(Relink) == 16 &&
              sizeof(WedgeChange) == 8 && sizeof(Collapse) == 4 * 17 && sizeof(InfluenceChange) == 2 * (16 + 32));

struct Writer {
  std::string out;
  template <class T>
  void value(const T& v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <class T>
  void array(const std::vector<T>& v) {
    static_assert(plain<T>);
    value(uint64_t(v.size()));
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void strings(const std::vector<std::string>& v) {
    value(uint64_t(v.size()));
    for (const std::string& s : v) value(uint64_t(s.size())), out += s;
  }
};

struct Reader {
  std::span<const uint8_t> bytes;
  const std::string& name;
  size_t at = 0;

  [[noreturn]] void fail(const std::string& what) const { throw_bad_input_at_byte(name, at, what); }
  template <class T>
  T value(const char* what) {
    if (bytes.size() - at < sizeof(T)) fail(std::string("truncated: expected ") + what);
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  // The count is checked against the bytes left before anything is allocated.
  uint64_t count(size_t element_size, const char* what) {
    const size_t where = at;
    const uint64_t n = value<uint64_t>(what);
    if (n > (bytes.size() - at) / element_size)
      throw_bad_input_at_byte(name, where, std::string("count of ") + what + " (" + std::to_string(n) +
                                               ") exceeds the bytes left in the file");
    return n;
  }
  template <class T>
  void array(std::vector<T>& v, const char* what) {
    const uint64_t n = count(sizeof(T), what);
    v.resize(n);
    if (n) std::memcpy(v.data(), bytes.data() + at, n * sizeof(T));  // an empty vector's data() may be null
    at += n * sizeof(T);
  }
  void strings(std::vector<std::string>& v, const char* what) {
    const uint64_t n = count(8, what);
    v.resize(n);
    for (std::string& s : v) {
      const uint64_t len = count(1, what);
      s.assign(reinterpret_cast<const char*>(bytes.data() + at), len);
      at += len;
    }
  }
};

void write_mesh_streams(Writer& w, const Mesh& m) {
  w.array(m.positions), w.array(m.normals), w.array(m.tangents);
  for (const auto& uv : m.uvs) w.array(uv);
  w.array(m.colors), w.array(m.joints), w.array(m.weights), w.array(m.joints1), w.array(m.weights1);
  w.array(m.indices), w.array(m.materials), w.strings(m.material_names);
  w.array(m.groups), w.strings(m.group_names);
}

void read_mesh_streams(Reader& r, Mesh& m, uint32_t file_version) {
  r.array(m.positions, "positions"), r.array(m.normals, "normals"), r.array(m.tangents, "tangents");
  for (auto& uv : m.uvs) r.array(uv, "texture coordinates");
  r.array(m.colors, "colours"), r.array(m.joints, "joints"), r.array(m.weights, "weights");
  if (file_version >= 2) r.array(m.joints1, "second-set joints"), r.array(m.weights1, "second-set weights");
  r.array(m.indices, "indices"), r.array(m.materials, "materials"), r.strings(m.material_names, "material names");
  r.array(m.groups, "groups"), r.strings(m.group_names, "group names");
}

}  // namespace

std::string encode_progressive_mesh(const ProgressiveMesh& pm) {
  Writer payload;
  write_mesh_streams(payload, pm.input());
  const SimplifyRecord& rec = pm.record();
  payload.value(rec.stride);
  payload.array(rec.collapses), payload.array(rec.removed_faces), payload.array(rec.relinks);
  payload.array(rec.wedges), payload.array(rec.moved_wedges), payload.array(rec.old_values);
  payload.array(rec.new_values);
  payload.array(rec.influences);

  Writer file;
  file.out.append(magic, 4);
  file.value(version);
  file.value(uint64_t(payload.out.size()));
  file.value(uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(payload.out.data()), uInt(payload.out.size()))));
  return file.out + payload.out;
}

void write_progressive_mesh(const ProgressiveMesh& pm, const std::filesystem::path& path) {
  write_file_atomic(path, encode_progressive_mesh(pm));
}

ProgressiveMesh decode_progressive_mesh(std::span<const uint8_t> bytes, const std::string& name) {
  Reader r{bytes, name};
  if (bytes.size() < header_size) r.fail("truncated: a .lpm file starts with a 20-byte header");
  if (std::memcmp(bytes.data(), magic, 4) != 0) r.fail("not a .lpm file (expected the magic \"LPM\\x1a\")");
  r.at = 4;
  const uint32_t file_version = r.value<uint32_t>("version");
  if (file_version < 1 || file_version > version)
    r.fail("unsupported .lpm version " + std::to_string(file_version) + " (this build reads versions 1 to 3)");
  const uint64_t payload_size = r.value<uint64_t>("payload size");
  const uint32_t crc = r.value<uint32_t>("checksum");
  if (payload_size != bytes.size() - header_size)
    r.fail("payload size " + std::to_string(payload_size) + " does not match the " +
           std::to_string(bytes.size() - header_size) + " bytes after the header (truncated or padded)");
  const std::span<const uint8_t> payload = bytes.subspan(header_size);
  // zlib's crc32 takes uInt lengths: feed it in pieces.
  uLong actual = crc32(0L, Z_NULL, 0);
  for (size_t done = 0; done < payload.size();) {
    const size_t n = std::min<size_t>(payload.size() - done, 1u << 30);
    actual = crc32(actual, payload.data() + done, uInt(n));
    done += n;
  }
  if (uint32_t(actual) != crc) r.fail("checksum mismatch: the file is corrupt");

  Mesh mesh;
  read_mesh_streams(r, mesh, file_version);
  validate(mesh, name);
  SimplifyRecord rec;
  rec.stride = r.value<uint32_t>("attribute stride");
  const size_t collapses_at = r.at;
  r.array(rec.collapses, "collapses"), r.array(rec.removed_faces, "removed faces"), r.array(rec.relinks, "relinks");
  r.array(rec.wedges, "wedge changes"), r.array(rec.moved_wedges, "moved wedges"), r.array(rec.old_values, "old values");
  r.array(rec.new_values, "new values");
  const size_t influences_at = r.at;
  if (file_version >= 3) r.array(rec.influences, "influence changes");
  if (r.at != bytes.size()) r.fail("unexpected bytes after the collapse record");

  // The record must play on the mesh: every index in range and every collapse starting from the
  // state the previous ones left (so undoing is exact). A record that does not is corrupt.
  collapse::Replay check(mesh);
  if (position_ids(mesh).count < rec.collapses.size())
    throw_bad_input_at_byte(name, collapses_at, "more collapses than the mesh has positions");
  if (!rec.influences.empty() && rec.influences.size() != rec.collapses.size())
    throw_bad_input_at_byte(name, influences_at,
                            std::to_string(rec.influences.size()) + " influence changes for " +
                                std::to_string(rec.collapses.size()) + " collapses (expected one per collapse, or none)");
  if (!rec.influences.empty() && mesh.joints.empty())
    throw_bad_input_at_byte(name, influences_at, "influence changes for a mesh without joints and weights");
  for (size_t i = 0; i < rec.collapses.size(); ++i)
    if (!check.apply_consistent(rec, i))
      throw_bad_input_at_byte(name, collapses_at + 8 + i * sizeof(Collapse),
                              "collapse " + std::to_string(i) +
                                  " does not fit the mesh (faces, vertices or values it does not have, or not as "
                                  "the earlier collapses left them)");
  return ProgressiveMesh(std::move(mesh), std::move(rec));
}

ProgressiveMesh read_progressive_mesh(const std::filesystem::path& path) {
  const FileBytes bytes = read_file_bytes(path);
  return decode_progressive_mesh(bytes, path.string());
}

}  // namespace lod
