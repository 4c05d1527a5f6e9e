// libFuzzer harness for the OBJ reader: read_obj, validate, then write_obj -> read_obj with
// a text round trip (exact values). The oracle lives in fuzz_common.h.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const lod::fuzz::MeshFormat format = {
      .name = "obj", .file_name = "fuzz.obj", .read = &lod::read_obj, .write = &lod::write_obj, .has_binary = false};
  return lod::fuzz::fuzz_mesh_format(format, {data, size});
}
