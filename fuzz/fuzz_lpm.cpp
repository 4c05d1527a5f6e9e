// libFuzzer harness for the .lpm reader: decode; a file that decodes must play its whole record
// forwards and backwards without fault, come back to its input, and re-encode to the same bytes.
#include <cstdlib>
#include <string>

#include "lodkit/error.h"
#include "lodkit/lod.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  lod::ProgressiveMesh pm;
  try {
    pm = lod::decode_progressive_mesh({data, size}, "fuzz.lpm");
  } catch (const lod::Error& e) {
    if (e.category() != lod::ErrorCategory::bad_input) std::abort();  // only "bad input" is a clean rejection
    return 0;
  }
  const lod::Mesh start = pm.mesh();
  pm.set_collapses(pm.collapse_count());
  pm.set_collapses(pm.collapse_count() / 2);
  pm.set_collapses(0);
  if (!(pm.mesh() == start)) std::abort();
  if (lod::encode_progressive_mesh(pm) != std::string(reinterpret_cast<const char*>(data), size)) std::abort();
  return 0;
}
