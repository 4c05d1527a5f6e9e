// libFuzzer harness for the OFF reader: read_off, validate, then write_off -> read_off with
// a text round trip (exact values). The oracle lives in fuzz_common.h.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const lod::fuzz::MeshFormat format = {
      .name = "off", .file_name = "fuzz.off", .read = &lod::read_off, .write = &lod::write_off, .has_binary = false};
  return lod::fuzz::fuzz_mesh_format(format, {data, size});
}
