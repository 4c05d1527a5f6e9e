// libFuzzer harness for lodkit's meshopt vertex codec (src/io/meshopt_codec.cpp: decoding versions 0
// and 1, encoding version 1) and its COLOR and OCTAHEDRAL filters (on whatever bytes decode).
// Input: one byte for the stride (4 * (1 + b % 64)), two for the element count (1 to 4096), then
// the stream. The decoder may refuse anything, with a message; it must never read or write out of
// bounds (ASan). What it decodes, lodkit's version 1 encoder must encode so that it decodes to the
// same bytes. On version 0 streams the decoder is also held to Debian's meshoptimizer: both accept
// the same streams and decode them to the same bytes, else abort().
#include <meshoptimizer.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "io/meshopt_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const size_t stride = 4 * (1 + data[0] % 64), count = 1 + (size_t(data[1]) | size_t(data[2]) << 8) % 4096;
  const std::span<const uint8_t> stream(data + 3, size - 3);
  std::vector<uint8_t> mine(count * stride);
  const std::string why = lod::io::decode_meshopt_vertices(mine.data(), count, stride, stream);
  if (why.empty()) {
    // What decodes, lodkit's version 1 encoder must give back exactly.
    const std::vector<uint8_t> encoded = lod::io::encode_meshopt_vertices(mine.data(), count, stride);
    std::vector<uint8_t> back(count * stride);
    const std::string again = lod::io::decode_meshopt_vertices(back.data(), count, stride, encoded);
    if (!again.empty() || back != mine) {
      std::fprintf(stderr, "fuzz_meshopt: the version 1 encoding does not round-trip (%s)\n", again.c_str());
      std::abort();
    }
    if (stride == 4 || stride == 8) {
      std::vector<uint8_t> octahedral = mine;
      lod::io::decode_meshopt_octahedral_filter(octahedral.data(), count, stride);
      lod::io::decode_meshopt_color_filter(mine.data(), count, stride);
    }
  }
  if (!stream.empty() && stream[0] == 0xa0) {
    std::vector<uint8_t> theirs(count * stride), again(count * stride);
    const bool their_ok = meshopt_decodeVertexBuffer(theirs.data(), count, stride, stream.data(), stream.size()) == 0;
    const bool ok = lod::io::decode_meshopt_vertices(again.data(), count, stride, stream).empty();
    if (ok != their_ok || (ok && again != theirs)) {
      std::fprintf(stderr, "fuzz_meshopt: lodkit %s, meshoptimizer %s (%s)\n", ok ? "accepts" : "refuses",
                   their_ok ? "accepts" : "refuses", ok == their_ok ? "different bytes" : why.c_str());
      std::abort();
    }
  }
  return 0;
}
