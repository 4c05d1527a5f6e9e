// libFuzzer harness for the .lpm reader: decode; a file that decodes must play its whole record
// forwards and backwards without fault, come back to its input, and re-encode to the same bytes. A
// file of an older version (still read) re-encodes in the current one: that encoding must decode to
// the same mesh and re-encode to itself.
#include <cstdint>
#include <cstdlib>
#include <cstring>
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
  const std::string encoded = lod::encode_progressive_mesh(pm);
  const std::string input(reinterpret_cast<const char*>(data), size);
  // The version follows the 4-byte magic (the decoder read it, so the bytes are there).
  uint32_t version = 0, current = 0;
  std::memcpy(&version, data + 4, sizeof version);
  std::memcpy(&current, encoded.data() + 4, sizeof current);
  if (version == current) {
    if (encoded != input) std::abort();
  } else {
    lod::ProgressiveMesh again = lod::decode_progressive_mesh({reinterpret_cast<const uint8_t*>(encoded.data()), encoded.size()}, "again.lpm");
    if (!(again.mesh() == start) || lod::encode_progressive_mesh(again) != encoded) std::abort();
  }
  return 0;
}
