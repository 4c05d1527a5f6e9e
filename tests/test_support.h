// Shared test helpers: temporary folders, running the CLI, the corpus location.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodkit/mesh.h"

namespace lod::test {

// A fresh empty folder under the system temp dir, removed by the destructor.
struct TempDir {
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::filesystem::path path;
  std::filesystem::path operator/(const std::string& name) const { return path / name; }
};

struct RunResult {
  int exit_code = -1;   // exit status, or -1 when the process died from a signal
  int signal = 0;       // the signal that ended it, 0 when it exited
  std::string out, err;
};
// Runs the built `lodkit` CLI with arguments (no shell), capturing stdout and stderr; with a non-zero
// `address_space_limit` (bytes), under that cap.
RunResult run_cli(const std::vector<std::string>& args, uint64_t address_space_limit = 0);
// Runs argv[0] (looked up in PATH) the same way.
RunResult run_program(std::vector<std::string> argv, uint64_t address_space_limit = 0);
// Whether a program is on the PATH (tests that need a Debian tool skip without it).
bool program_available(const std::string& name);

// data/corpus, or an empty path when the corpus is absent (call GTEST_SKIP then).
std::filesystem::path corpus_dir();
std::vector<std::filesystem::path> corpus_files();

void write_text(const std::filesystem::path& path, const std::string& text);

// A second glTF reader (tests/gltf-loader: glTF-Transform with Google's draco3dgltf WebAssembly
// decoder and meshoptimizer's JavaScript one, installed by scripts/setup.sh through npm): every
// mesh primitive of `file` as it decodes it (load.mjs's JSON: mesh, primitive, attributes and
// morph targets as {type, normalized, values}, indices); with flag "--textures", per material its
// texture references (slot, texCoord, KHR_texture_transform). Fails the calling test when it cannot.
bool second_reader_available();
nlohmann::json read_with_second_reader(const std::filesystem::path& file, const std::string& flag = {});

// Khronos gltf-validator (tests/gltf-validator, installed by scripts/setup.sh through npm).
struct ValidatorRun {
  int status = -1;     // 0 when every file has zero errors
  std::string output;  // its report
};
bool validator_available();
ValidatorRun run_validator(const std::vector<std::filesystem::path>& files);
// Every file has zero errors by the validator; skips the calling test where it is not installed.
void expect_valid_gltf(const std::vector<std::filesystem::path>& files);
void write_bytes(const std::filesystem::path& path, const std::vector<uint8_t>& bytes);
std::string read_bytes(const std::filesystem::path& path);  // the whole file ("" when unreadable)

// Standard base64 with '=' padding (for data: URIs in hand-written glTF files), and back (for test
// data other programs write; characters outside the alphabet are skipped).
std::string base64(std::span<const uint8_t> bytes);
std::vector<uint8_t> from_base64(const std::string& text);

inline std::span<const uint8_t> bytes_of(const std::string& s) {
  return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

// Runs `read(bytes, name)` and checks it throws a bad-input Error whose message starts with `name:`
// (so it names the file and a line or byte offset). Returns the message, or "" after a test failure.
using Reader = std::function<void(std::span<const uint8_t>, const std::string&)>;
std::string expect_bad_input(const Reader& read, const std::string& input, const std::string& name);

// The distance from p to triangle abc, computed on its own (not by lodkit's measure): to the plane
// where p projects inside (barycentric coordinates from Cramer's rule), else to the nearest edge.
double triangle_distance(const float3& p, const float3& a, const float3& b, const float3& c);

// A 1x1 RGB PNG's bytes (signature, IHDR, IDAT of one filtered pixel, IEND), made with zlib by hand.
std::string tiny_png();

// A .glb's two chunks, parsed without lodkit: the JSON and the BIN data (empty when absent).
struct Glb {
  nlohmann::json doc;
  std::vector<uint8_t> bin;
};
Glb read_glb(const std::filesystem::path& path);
// A .glb of those chunks (padded as GLB requires; the JSON as given).
std::vector<uint8_t> glb_bytes(const Glb& glb);
// The JSON chunk of a .glb.
nlohmann::json glb_json(const std::filesystem::path& path);
// A float accessor's components (tightly packed), read straight from a .glb's JSON and BIN chunk.
std::vector<float> glb_floats(const std::filesystem::path& path, size_t accessor);
// Morph target `target`'s POSITION offsets of a .glb's mesh `mesh`, primitive `primitive`, read
// straight from the file's JSON and BIN chunk (lodkit's reader does not model targets). Empty when
// that primitive has no such target.
std::vector<float3> glb_morph_positions(const std::filesystem::path& path, size_t mesh = 0, size_t primitive = 0,
                                        size_t target = 0);

// Gives the mesh, which has normals, a unit tangent across each normal (in the xy plane; +x where the
// normal is about z) with handedness alternating +1, -1 by vertex.
void add_tangents(Mesh& m);

// Describes the first difference between two meshes ("" when equal, bitwise on floats).
std::string mesh_difference(const Mesh& a, const Mesh& b);

// A triangle list's triangles through a vertex map (none: as they are), each as its rotation that
// starts at the smallest id (so the winding counts), sorted: what survives a codec that reorders
// triangles and may start one at another corner.
std::vector<std::array<uint32_t, 3>> canonical_triangles(const std::vector<uint32_t>& indices, const std::vector<uint32_t>* map = nullptr);

}  // namespace lod::test
