// libFuzzer harness for the OBJ reader: read_obj, validate, then write_obj -> read_obj with
// a text round trip (exact values). The oracle lives in fuzz_common.h.
#include "fuzz_common.h"

namespace {
// read_obj without its mtllib list (the file layer's business, fuzzed as fuzz_mtl).
lod::Mesh read_obj(std::span<const uint8_t> bytes, const std::string& name, const lod::ReadOptions& options) {
  return lod::read_obj(bytes, name, options);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const lod::fuzz::MeshFormat format = {
      .name = "obj", .file_name = "fuzz.obj", .read = &read_obj, .write = &lod::write_obj, .has_binary = false};
  return lod::fuzz::fuzz_mesh_format(format, {data, size});
}
