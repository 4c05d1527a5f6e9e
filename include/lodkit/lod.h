// lodkit: what the simplifier's output becomes in an application. A progressive mesh (refine or
// coarsen to any size), and a file format that stores it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "lodkit/mesh.h"
#include "lodkit/simplify.h"

namespace lod {

// A progressive mesh (Hoppe 1996) built from a collapse record: the coarsest mesh plus, read
// backwards, one vertex split per collapse. Moving to a size applies or undoes collapses from the
// current state, so a sweep costs what it changes. At k collapses the mesh is exactly the
// simplifier's (lod::replay(input, record, k)).
//
// Sizes count unique positions, as the simplifier does (one collapse removes one position; vertices
// split at seams move with their position).
class ProgressiveMesh {
 public:
  ProgressiveMesh();
  // `record` must be the record of simplifying `input` (validated: usage error if an index is out
  // of range). Starts fully refined (the input).
  ProgressiveMesh(Mesh input, SimplifyRecord record);
  ~ProgressiveMesh();
  ProgressiveMesh(ProgressiveMesh&&) noexcept;
  ProgressiveMesh& operator=(ProgressiveMesh&&) noexcept;

  size_t collapse_count() const;     // collapses in the record
  size_t collapses_applied() const;  // 0: the input, collapse_count(): the base mesh
  uint32_t max_positions() const;    // unique positions of the input
  uint32_t min_positions() const;    // of the base mesh
  uint32_t positions() const;        // now

  // Applies or undoes collapses until `collapses_applied() == k` (clamped to the record).
  void set_collapses(size_t k);
  // To `n` unique positions, clamped to [min_positions(), max_positions()]. refine_to never
  // coarsens and coarsen_to never refines: they leave a mesh already past `n` as it is.
  void refine_to(uint32_t n);
  void coarsen_to(uint32_t n);

  // The current mesh, compacted as the simplifier's output: live triangles in input order and the
  // vertices they use in order of first use.
  Mesh mesh() const;

  const Mesh& input() const;
  const SimplifyRecord& record() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// `.lpm`: a versioned little-endian binary file holding a progressive mesh (its input mesh and
// collapse record) with a CRC-32 of the payload. The reader rejects wrong magic, unknown versions,
// truncation, counts that exceed the bytes present, bad checksums and records that do not belong to
// the mesh, with the byte offset; it never allocates more than the file's size implies.
void write_progressive_mesh(const ProgressiveMesh& pm, const std::filesystem::path& path);
std::string encode_progressive_mesh(const ProgressiveMesh& pm);
ProgressiveMesh read_progressive_mesh(const std::filesystem::path& path);
ProgressiveMesh decode_progressive_mesh(std::span<const uint8_t> bytes, const std::string& name);

}  // namespace lod
