// libFuzzer harness for the .lpm reader: decode; a file that decodes must play its whole record
// forwards and backwards without fault, come back to its input, and re-encode to the same bytes. A
// file of an older version (still read) re-encodes in the current one: that encoding must decode to
// the same mesh and re-encode to itself.
// A mutated file almost always fails its CRC-32, which would keep the fuzzer at the header: each
// input is therefore decoded twice, as it is and with its header's payload size and checksum made
// to match the bytes that follow, so that mutations reach the mesh and the collapse record.
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "lodkit/error.h"
#include "lodkit/lod.h"

namespace {

void decode_and_check(const uint8_t* data, size_t size) {
  lod::ProgressiveMesh pm;
  try {
    pm = lod::decode_progressive_mesh({data, size}, "fuzz.lpm");
  } catch (const lod::Error& e) {
    if (e.category() != lod::ErrorCategory::bad_input) std::abort();  // only "bad input" is a clean rejection
    return;
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
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  decode_and_check(data, size);
  // Header: magic (4), version (4), payload size (8), CRC-32 of the payload (4).
  constexpr size_t header = 20;
  if (size < header) return 0;
  std::string fixed(reinterpret_cast<const char*>(data), size);
  const uint64_t payload = size - header;
  const uint32_t crc = uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(fixed.data() + header), uInt(payload)));
  std::memcpy(fixed.data() + 8, &payload, sizeof payload);
  std::memcpy(fixed.data() + 16, &crc, sizeof crc);
  if (fixed.compare(0, header, reinterpret_cast<const char*>(data), header) != 0)
    decode_and_check(reinterpret_cast<const uint8_t*>(fixed.data()), fixed.size());
  return 0;
}
