// Internal to the glTF reader and writer: the parts of KHR_meshopt_compression that Debian's
// meshoptimizer (0.18) predates, written from the extension's specification (Appendix A and B):
//  - the vertex codec's version 1 (a control mode per byte position, 1-bit groups, literal bytes,
//    and 2-byte and XOR channel deltas), which meshoptimizer 0.23 and later write;
//  - the COLOR filter (YCoCg);
//  - the OCTAHEDRAL filter, which 0.18 has, but not the same on every processor.
// Version 0 streams are decoded here too (its groups are version 1's with a fixed control mode):
// the reader gives them to meshoptimizer's SIMD decoder, and the tests and fuzz_meshopt hold the two
// decoders to the same output on them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace lod::io {

// Decodes a meshopt ATTRIBUTES stream of `count` elements of `stride` bytes (a multiple of 4 in
// 4..256) into `out` (count * stride bytes). Returns an empty string, or what is wrong and at which
// byte of `in` (header, a group running past the tail, bytes left over, an invalid channel mode).
// Reads only `in` and writes only `out`, whatever the bytes.
std::string decode_meshopt_vertices(uint8_t* out, size_t count, size_t stride, std::span<const uint8_t> in);

// Encodes `count` elements of `stride` bytes (a multiple of 4 in 4..256) as a version 1 stream
// (KHR_meshopt_compression). Each 4-byte channel takes the delta mode (bytes, 16-bit, or XOR under
// one of 16 rotations) that codes smallest over up to 64 blocks spread over the stream, and each
// byte position of each block the cheapest control mode, each group of 16 the cheapest bit width;
// the baseline is the first element. Deterministic; decode_meshopt_vertices gives the bytes back.
std::vector<uint8_t> encode_meshopt_vertices(const uint8_t* data, size_t count, size_t stride);

// The COLOR filter in place: `count` elements of `stride` 4 (four 8-bit components) or 8 (16-bit),
// YCoCg with the alpha's top bit giving the precision, into unsigned normalized RGBA. An alpha of
// 0 (no precision bit, which no encoder writes) decodes as if the precision were 1 bit.
void decode_meshopt_color_filter(uint8_t* data, size_t count, size_t stride);

// The OCTAHEDRAL filter in place: `count` elements of `stride` 4 (8-bit components) or 8 (16-bit),
// octahedral x, y and the K-bit encoding of 1 into a unit vector as signed normalized integers,
// the fourth component kept. Debian's meshoptimizer has it, but its SSE path scales by rsqrtps, an
// approximation whose bits differ between processors: the same file then read as different normals
// on different machines. This follows the specification's float32 arithmetic with an exact square
// root, so that every machine reads the same bytes (as meshoptimizer's JavaScript decoder does).
// A malformed element (a zero "one") decodes to zeros rather than undefined conversions.
void decode_meshopt_octahedral_filter(uint8_t* data, size_t count, size_t stride);

}  // namespace lod::io
