// libFuzzer harness for the PLY reader: read_ply, validate, then write_ply -> read_ply with
// binary (bit-exact) and ASCII (exact value) round trips. The oracle lives in fuzz_common.h.
#include "fuzz_common.h"

namespace {
// read_ply without its TextureFile list (the file layer's business).
lod::Mesh read_ply(std::span<const uint8_t> bytes, const std::string& name, const lod::ReadOptions& options) {
  return lod::read_ply(bytes, name, options);
}
// write_ply with its texture paths from the current folder.
void write_ply(const lod::Mesh& mesh, std::string& out, const lod::WriteOptions& options) { lod::write_ply(mesh, out, options); }
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const lod::fuzz::MeshFormat format = {
      .name = "ply", .file_name = "fuzz.ply", .read = &read_ply, .write = &write_ply, .has_binary = true};
  return lod::fuzz::fuzz_mesh_format(format, {data, size});
}
