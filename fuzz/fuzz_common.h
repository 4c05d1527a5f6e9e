// The oracle every libFuzzer harness shares. A reader may reject any input, but only with
// lod::Error(bad_input); everything else (another exception type, another category, a mesh that does
// not validate, a write -> read round trip that changes the geometry) is a bug, and the harness
// calls abort() so libFuzzer records the input as a crash.
//
// Environment:
//   LODKIT_FUZZ_STRICT_WEIGHTS=1  also require skin weights to be non-negative and sum to 1 (the
//                                 full validate()); off by default because the PLY and glTF readers
//                                 pass weights through as stored, and that finding would mask the rest.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/mesh.h"

// Recoverable UBSan checks only print by default: make them abort so libFuzzer keeps the input,
// also when a reproducer runs by hand. (Defined here because each harness is one translation unit;
// UBSAN_OPTIONS in the environment still overrides.)
extern "C" const char* __ubsan_default_options() { return "halt_on_error=1:print_stacktrace=1"; }

namespace lod::fuzz {

// Round trips are skipped above this size so the fuzzer keeps its speed on the odd large mesh.
inline constexpr size_t max_round_trip_vertices = 100'000;

[[noreturn]] inline void fail(const std::string& stage, const std::string& what) {
  std::fprintf(stderr, "\n==== lodkit fuzz oracle: %s: %s\n", stage.c_str(), what.c_str());
  std::fflush(stderr);
  std::abort();
}

inline const char* category_name(ErrorCategory category) {
  switch (category) {
    case ErrorCategory::bad_input: return "bad_input";
    case ErrorCategory::usage: return "usage";
    case ErrorCategory::internal: return "internal";
  }
  return "?";
}

// Runs `step`. When `may_reject`, a lod::Error(bad_input) means "input refused" and yields nullopt;
// every other exception aborts. Without `may_reject` (writers, re-reads of our own output) any
// exception aborts.
template <class Step>
auto run_step(const std::string& stage, bool may_reject, Step&& step) -> std::optional<decltype(step())> {
  try {
    return step();
  } catch (const Error& e) {
    if (may_reject && e.category() == ErrorCategory::bad_input) return std::nullopt;
    fail(stage, std::string("lod::Error(") + category_name(e.category()) + "): " + e.what());
  } catch (const std::exception& e) {
    fail(stage, std::string("unexpected exception: ") + e.what());
  } catch (...) {
    fail(stage, "unexpected exception of unknown type");
  }
}

// Read options whose progress callback checks its documented contract: a fraction in [0, 1].
inline ReadOptions checked_read_options(const std::string& stage) {
  ReadOptions options;
  options.progress = [stage](double fraction) {
    if (!(fraction >= 0.0 && fraction <= 1.0)) fail(stage, "progress fraction " + std::to_string(fraction) + " outside [0, 1]");
  };
  return options;
}

inline bool strict_weights() {
  static const bool strict = [] {
    const char* v = std::getenv("LODKIT_FUZZ_STRICT_WEIGHTS");
    return v && *v && *v != '0';
  }();
  return strict;
}

// The mesh a reader returns must validate: stream sizes match, values finite, indices in range.
inline void check_mesh(const Mesh& mesh, const std::string& stage) {
  try {
    if (strict_weights() || mesh.weights.empty()) {
      validate(mesh, stage);
      return;
    }
    // Same checks, minus the weight sum and sign: finite weights become {1, 0, 0, 0} in the first set
    // and {0, 0, 0, 0} in the second (which counts towards the same sum), non-finite ones stay so
    // validate() still reports them.
    Mesh relaxed = mesh;
    const auto finite = [](const float4& w) { return std::isfinite(w.x) && std::isfinite(w.y) && std::isfinite(w.z) && std::isfinite(w.w); };
    for (float4& w : relaxed.weights)
      if (finite(w)) w = {1, 0, 0, 0};
    for (float4& w : relaxed.weights1)
      if (finite(w)) w = {0, 0, 0, 0};
    validate(relaxed, stage);
  } catch (const Error& e) {
    fail(stage, std::string("the reader returned a mesh that does not validate: ") + e.what());
  }
}

enum class Exactness {
  bits,   // binary formats: positions must come back bit for bit
  value,  // text formats: equal as floats (+0 == -0); the writers print the shortest exact form
};

inline bool same_float(float a, float b, Exactness exactness) {
  return exactness == Exactness::bits ? std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b) : a == b;
}

// Write -> read must keep the geometry: vertex and triangle counts, every position, every index.
inline void require_same_geometry(const Mesh& before, const Mesh& after, Exactness exactness, const std::string& stage) {
  if (after.vertex_count() != before.vertex_count())
    fail(stage, "vertex count changed from " + std::to_string(before.vertex_count()) + " to " + std::to_string(after.vertex_count()));
  if (after.indices.size() != before.indices.size())
    fail(stage, "triangle count changed from " + std::to_string(before.triangle_count()) + " to " +
                    std::to_string(after.triangle_count()));
  for (size_t v = 0; v < before.positions.size(); ++v) {
    const float3 &a = before.positions[v], &b = after.positions[v];
    if (!same_float(a.x, b.x, exactness) || !same_float(a.y, b.y, exactness) || !same_float(a.z, b.z, exactness)) {
      char text[200];
      std::snprintf(text, sizeof text, "position %zu changed from (%a %a %a) to (%a %a %a)", v, double(a.x), double(a.y),
                    double(a.z), double(b.x), double(b.y), double(b.z));
      fail(stage, text);
    }
  }
  for (size_t i = 0; i < before.indices.size(); ++i)
    if (after.indices[i] != before.indices[i])
      fail(stage, "index " + std::to_string(i) + " changed from " + std::to_string(before.indices[i]) + " to " +
                      std::to_string(after.indices[i]));
}

// One single-mesh format: its in-memory reader and writer.
using MeshReader = Mesh (*)(std::span<const uint8_t>, const std::string&, const ReadOptions&);
using MeshWriter = void (*)(const Mesh&, std::string&, const WriteOptions&);

struct MeshFormat {
  const char* name;       // for messages, e.g. "ply"
  const char* file_name;  // passed to the reader as the source name
  MeshReader read;
  MeshWriter write;
  bool has_binary;  // the writer honours WriteOptions::binary
};

// Writes `mesh` in `format`, reads it back and requires the same geometry.
inline void check_round_trip(const MeshFormat& format, const Mesh& mesh, bool binary) {
  const std::string stage = std::string(format.name) + (binary ? " binary" : " text") + " round trip";
  std::string out;
  run_step(stage + ": write", false, [&] {
    format.write(mesh, out, {.binary = binary});
    return true;
  });
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(out.data()), out.size());
  const std::optional<Mesh> again =
      run_step(stage + ": read back", false, [&] { return format.read(bytes, "round-trip", checked_read_options(stage)); });
  check_mesh(*again, stage + ": read back");
  require_same_geometry(mesh, *again, binary ? Exactness::bits : Exactness::value, stage);
}

// The whole harness of a single-mesh format: parse, validate, round trip (binary, then text).
inline int fuzz_mesh_format(const MeshFormat& format, std::span<const uint8_t> input) {
  const std::string stage = std::string(format.name) + " read";
  const std::optional<Mesh> mesh = run_step(stage, true, [&] { return format.read(input, format.file_name, checked_read_options(stage)); });
  if (!mesh) return 0;
  check_mesh(*mesh, stage);
  if (mesh->vertex_count() > max_round_trip_vertices) return 0;
  if (format.has_binary) check_round_trip(format, *mesh, true);
  check_round_trip(format, *mesh, false);
  return 0;
}

}  // namespace lod::fuzz
