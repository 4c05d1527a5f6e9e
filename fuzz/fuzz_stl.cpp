// libFuzzer harness for the STL reader: read_stl, validate, then write_stl -> read_stl with
// binary (bit-exact) and ASCII (exact value) round trips. The oracle lives in fuzz_common.h.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const lod::fuzz::MeshFormat format = {
      .name = "stl", .file_name = "fuzz.stl", .read = &lod::read_stl, .write = &lod::write_stl, .has_binary = true};
  return lod::fuzz::fuzz_mesh_format(format, {data, size});
}
