// libFuzzer harness for the PLY reader: read_ply, validate, then write_ply -> read_ply with
// binary (bit-exact) and ASCII (exact value) round trips. The oracle lives in fuzz_common.h.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const lod::fuzz::MeshFormat format = {
      .name = "ply", .file_name = "fuzz.ply", .read = &lod::read_ply, .write = &lod::write_ply, .has_binary = true};
  return lod::fuzz::fuzz_mesh_format(format, {data, size});
}
