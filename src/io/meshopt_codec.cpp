// KHR_meshopt_compression's vertex codec (decoding versions 0 and 1, encoding version 1) and COLOR
// filter, from the extension's specification (see meshopt_codec.h).
#include "io/meshopt_codec.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace lod::io {

namespace {

constexpr size_t group_elements = 16;
// Bits per delta by a group's 2-bit mode: version 0, then version 1 under control modes 0 and 1.
constexpr uint8_t bits_by_mode[3][4] = {{0, 2, 4, 8}, {0, 1, 2, 4}, {1, 2, 4, 8}};

uint8_t unzigzag8(uint8_t v) { return uint8_t((v >> 1) ^ uint8_t(0u - (v & 1u))); }
uint16_t unzigzag16(uint16_t v) { return uint16_t((v >> 1) ^ uint16_t(0u - (v & 1u))); }
uint32_t rotate_right(uint32_t v, unsigned r) { return r ? (v >> r) | (v << (32 - r)) : v; }

std::string at(size_t offset, const std::string& what) { return "byte " + std::to_string(offset) + ": " + what; }

std::string hex(unsigned byte) {
  constexpr char digits[] = "0123456789abcdef";
  return std::string("0x") + digits[(byte >> 4) & 15] + digits[byte & 15];
}

}  // namespace

std::string decode_meshopt_vertices(uint8_t* out, size_t count, size_t stride, std::span<const uint8_t> in) {
  if (stride == 0 || stride % 4 != 0 || stride > 256) return "byteStride " + std::to_string(stride) + " is not a multiple of 4 in 4..256";
  if (in.empty()) return "no bytes";
  if (in[0] != 0xa0 && in[0] != 0xa1) return at(0, "header " + hex(in[0]) + " is not 0xa0 or 0xa1 (vertex codec version 0 or 1)");
  const bool v1 = in[0] == 0xa1;
  // The tail: the baseline element, then (version 1) one channel mode per 4 bytes, padded before it
  // with zeros to at least 24 (version 1) or 32 bytes.
  const size_t tail = stride + (v1 ? stride / 4 : 0);
  const size_t padded = std::max<size_t>(tail, v1 ? 24 : 32);
  if (in.size() < 1 + padded)
    return "the stream's " + std::to_string(in.size()) + " bytes cannot hold its header and a tail of " + std::to_string(padded);
  const size_t end = in.size() - padded;  // where the blocks must end, exactly
  const uint8_t* const baseline = in.data() + in.size() - tail;
  const uint8_t* const channels = baseline + stride;
  if (v1)
    for (size_t c = 0; c < stride / 4; ++c) {
      const unsigned mode = channels[c] & 15u, rotation = channels[c] >> 4;
      if (mode > 2 || (mode < 2 && rotation != 0))
        return at(size_t(channels + c - in.data()), "channel mode " + hex(channels[c]) + " is not 0x00, 0x01 or 0xR2 (XOR, rotated by R)");
    }

  std::array<uint8_t, 256> last{};  // the previous element: deltas chain across blocks
  std::memcpy(last.data(), baseline, stride);
  const size_t block_max = std::min<size_t>((8192 / stride) & ~(group_elements - 1), 256);
  std::vector<uint8_t> deltas(block_max * stride);  // per byte position, a row of block_max deltas
  size_t pos = 1;
  const auto take = [&](size_t bytes) { return bytes <= end - pos; };  // (pos <= end throughout)
  const std::string ends_early = "the blocks run into the tail (the stream ends early)";

  for (size_t first = 0; first < count; first += block_max) {
    const size_t elements = std::min(count - first, block_max);
    const size_t groups = (elements + group_elements - 1) / group_elements;
    const size_t control_at = pos;
    if (v1) {
      if (!take(stride / 4)) return at(pos, ends_early);
      pos += stride / 4;
    }
    for (size_t k = 0; k < stride; ++k) {
      uint8_t* row = deltas.data() + k * block_max;
      const unsigned control = v1 ? (in[control_at + k / 4] >> (2 * (k % 4))) & 3u : 0u;
      if (control == 2) {  // every delta 0
        std::memset(row, 0, elements);
        continue;
      }
      if (control == 3) {  // literal deltas, one byte per element, no group headers
        if (!take(elements)) return at(pos, ends_early);
        std::memcpy(row, in.data() + pos, elements);
        pos += elements;
        continue;
      }
      const size_t header_at = pos, header_bytes = (groups + 3) / 4;
      if (!take(header_bytes)) return at(pos, ends_early);
      pos += header_bytes;
      for (size_t g = 0; g < groups; ++g) {
        const unsigned mode = (in[header_at + g / 4] >> (2 * (g % 4))) & 3u;
        const unsigned bits = bits_by_mode[v1 ? control + 1 : 0][mode];
        uint8_t* group = row + g * group_elements;  // (rows hold whole groups: block_max is a multiple of 16)
        if (bits == 0) {
          std::memset(group, 0, group_elements);
        } else if (bits == 8) {
          if (!take(group_elements)) return at(pos, ends_early);
          std::memcpy(group, in.data() + pos, group_elements);
          pos += group_elements;
        } else {
          // 16 packed deltas (1-bit ones from the low bit up, 2- and 4-bit ones from the high bits
          // down); a delta of all ones stands for a whole byte, which follows in order.
          const size_t packed_at = pos, packed = 2 * bits;
          if (!take(packed)) return at(pos, ends_early);
          pos += packed;
          // Unpacked first (a loop per width), the escaped bytes then filled in.
          const uint8_t* p = in.data() + packed_at;
          if (bits == 1)
            for (size_t m = 0; m < group_elements; ++m) group[m] = uint8_t((p[m / 8] >> (m % 8)) & 1u);
          else if (bits == 2)
            for (size_t m = 0; m < group_elements; ++m) group[m] = uint8_t((p[m / 4] >> (6 - 2 * (m % 4))) & 3u);
          else
            for (size_t m = 0; m < group_elements; ++m) group[m] = uint8_t((p[m / 2] >> (4 - 4 * (m % 2))) & 15u);
          const uint8_t sentinel = uint8_t((1u << bits) - 1);
          for (size_t m = 0; m < group_elements; ++m)
            if (group[m] == sentinel) {
              if (!take(1)) return at(pos, ends_early);
              group[m] = in[pos++];
            }
        }
      }
    }
    // The deltas onto the previous element, by channel (4 bytes): zigzag byte deltas, zigzag 16-bit
    // deltas, or a 32-bit XOR rotated right by the mode's high 4 bits. Channel by channel, each a
    // tight loop over the block's elements.
    uint8_t* const block_out = out + first * stride;
    for (size_t c = 0; c < stride; c += 4) {
      const unsigned mode = v1 ? channels[c / 4] : 0u;
      const uint8_t* row[4];
      for (size_t b = 0; b < 4; ++b) row[b] = deltas.data() + (c + b) * block_max;
      if ((mode & 15u) == 0) {
        for (size_t b = 0; b < 4; ++b) {
          uint8_t v = last[c + b];
          uint8_t* o = block_out + c + b;
          for (size_t e = 0; e < elements; ++e) v = uint8_t(v + unzigzag8(row[b][e])), o[e * stride] = v;
          last[c + b] = v;
        }
      } else if ((mode & 15u) == 1) {
        for (size_t b = 0; b < 4; b += 2) {
          uint16_t v = uint16_t(last[c + b] | last[c + b + 1] << 8);
          uint8_t* o = block_out + c + b;
          for (size_t e = 0; e < elements; ++e) {
            v = uint16_t(v + unzigzag16(uint16_t(row[b][e] | row[b + 1][e] << 8)));
            o[e * stride] = uint8_t(v), o[e * stride + 1] = uint8_t(v >> 8);
          }
          last[c + b] = uint8_t(v), last[c + b + 1] = uint8_t(v >> 8);
        }
      } else {
        uint32_t v = 0;
        for (size_t b = 0; b < 4; ++b) v |= uint32_t(last[c + b]) << (8 * b);
        uint8_t* o = block_out + c;
        for (size_t e = 0; e < elements; ++e) {
          v ^= rotate_right(uint32_t(row[0][e]) | uint32_t(row[1][e]) << 8 | uint32_t(row[2][e]) << 16 | uint32_t(row[3][e]) << 24, mode >> 4);
          for (size_t b = 0; b < 4; ++b) o[e * stride + b] = uint8_t(v >> (8 * b));
        }
        for (size_t b = 0; b < 4; ++b) last[c + b] = uint8_t(v >> (8 * b));
      }
    }
  }
  if (pos != end) return at(pos, std::to_string(end - pos) + " byte(s) left over between the blocks and the tail");
  return {};
}

namespace {

// Component k of a filter's element: four 8-bit components, or four 16-bit little-endian ones.
uint32_t filter_component(const uint8_t* e, size_t k, bool wide) { return wide ? uint32_t(e[2 * k] | e[2 * k + 1] << 8) : e[k]; }
void set_filter_component(uint8_t* e, size_t k, bool wide, uint32_t u) {
  if (wide) e[2 * k] = uint8_t(u), e[2 * k + 1] = uint8_t(u >> 8);
  else e[k] = uint8_t(u);
}
int32_t signed_filter_component(const uint8_t* e, size_t k, bool wide) {
  const uint32_t u = filter_component(e, k, wide);
  return wide ? int32_t(int16_t(uint16_t(u))) : int32_t(int8_t(uint8_t(u)));
}

}  // namespace

void decode_meshopt_color_filter(uint8_t* data, size_t count, size_t stride) {
  const bool wide = stride == 8;
  const float top = wide ? 65535.0f : 255.0f;
  for (size_t i = 0; i < count; ++i) {
    uint8_t* e = data + i * stride;
    int32_t c[4];
    // Co and Cg are signed; luma and alpha unsigned.
    for (size_t k = 0; k < 4; ++k) c[k] = (k == 1 || k == 2) ? signed_filter_component(e, k, wide) : int32_t(filter_component(e, k, wide));
    // The alpha's highest set bit marks the precision K: its top value is 2^K - 1.
    const int k_bits = c[3] ? std::bit_width(uint32_t(c[3])) : 1;
    const int32_t full = (1 << k_bits) - 1;
    int32_t a = c[3] & (full >> 1);
    a = (a << 1) | (a & 1);  // K-1 bits of alpha widened to K, the last bit repeated
    const int32_t y = c[0], co = c[1], cg = c[2];
    const int32_t rgba[4] = {y + co - cg, y + cg, y - co - cg, a};
    const float scale = top / float(full);
    for (size_t k = 0; k < 4; ++k) {
      const float v = std::clamp(std::round(float(rgba[k]) * scale), 0.0f, top);  // (a malformed stream may leave the range)
      set_filter_component(e, k, wide, uint32_t(v));
    }
  }
}

void decode_meshopt_octahedral_filter(uint8_t* data, size_t count, size_t stride) {
  const bool wide = stride == 8;
  const float top = wide ? 32767.0f : 127.0f;
  for (size_t i = 0; i < count; ++i) {
    uint8_t* e = data + i * stride;
    // The specification's steps, in its order and precision.
    const float one = float(signed_filter_component(e, 2, wide));
    float x = float(signed_filter_component(e, 0, wide)) / one, y = float(signed_filter_component(e, 1, wide)) / one;
    const float z = 1.0f - std::fabs(x) - std::fabs(y);
    const float t = std::min(z, 0.0f);  // the negative hemisphere folds back
    x -= std::copysign(t, x);
    y -= std::copysign(t, y);
    const float len = std::sqrt(x * x + y * y + z * z);
    const float v[3] = {x / len, y / len, z / len};
    for (size_t k = 0; k < 3; ++k) {
      float q = std::round(v[k] * top);
      q = q == q ? std::clamp(q, -top, top) : 0.0f;  // NaN and infinities only from a malformed element
      set_filter_component(e, k, wide, uint32_t(int32_t(q)));
    }
  }
}

namespace {

uint8_t zigzag8(uint8_t v) { return uint8_t((v << 1) ^ uint8_t(0u - (v >> 7))); }
uint16_t zigzag16(uint16_t v) { return uint16_t((v << 1) ^ uint16_t(0u - (v >> 15))); }
uint32_t rotate_left(uint32_t v, unsigned r) { return r ? (v << r) | (v >> (32 - r)) : v; }

constexpr size_t no_fit = SIZE_MAX / 4;

// Bytes of one group of 16 deltas coded with `bits` each: the packed bits, and a whole byte for
// each delta that does not fit below the all-ones sentinel.
size_t group_bytes(const uint8_t* d, unsigned bits) {
  if (bits == 8) return group_elements;
  if (bits == 0) {
    for (size_t m = 0; m < group_elements; ++m)
      if (d[m]) return no_fit;
    return 0;
  }
  const unsigned sentinel = (1u << bits) - 1;
  size_t escaped = 0;
  for (size_t m = 0; m < group_elements; ++m) escaped += d[m] >= sentinel;
  return 2 * bits + escaped;
}

// One byte position's deltas over a block (`groups` whole groups, zero past the elements), coded
// with control mode `control` (version 1): its size, and with `out` its bytes appended.
size_t code_row(const uint8_t* row, size_t elements, size_t groups, unsigned control, std::vector<uint8_t>* out) {
  if (control == 2) {
    for (size_t e = 0; e < elements; ++e)
      if (row[e]) return no_fit;
    return 0;
  }
  if (control == 3) {
    if (out) out->insert(out->end(), row, row + elements);
    return elements;
  }
  const size_t header_bytes = (groups + 3) / 4;
  size_t size = header_bytes, header_at = 0;
  if (out) header_at = out->size(), out->resize(out->size() + header_bytes, 0);
  for (size_t g = 0; g < groups; ++g) {
    const uint8_t* d = row + g * group_elements;
    unsigned best = 0;
    size_t best_size = no_fit;
    for (unsigned mode = 0; mode < 4; ++mode) {
      const size_t s = group_bytes(d, bits_by_mode[control + 1][mode]);
      if (s < best_size) best = mode, best_size = s;
    }
    size += best_size;
    if (!out) continue;
    (*out)[header_at + g / 4] |= uint8_t(best << (2 * (g % 4)));
    const unsigned bits = bits_by_mode[control + 1][best];
    if (bits == 0) continue;
    if (bits == 8) {
      out->insert(out->end(), d, d + group_elements);
      continue;
    }
    const unsigned sentinel = (1u << bits) - 1;
    const size_t packed_at = out->size();
    out->resize(out->size() + 2 * bits, 0);
    for (size_t m = 0; m < group_elements; ++m) {
      const unsigned v = std::min<unsigned>(d[m], sentinel);
      uint8_t& byte = (*out)[packed_at + m * bits / 8];
      if (bits == 1) byte |= uint8_t(v << (m % 8));
      else if (bits == 2) byte |= uint8_t(v << (6 - 2 * (m % 4)));
      else byte |= uint8_t(v << (4 - 4 * (m % 2)));
    }
    for (size_t m = 0; m < group_elements; ++m)
      if (d[m] >= sentinel) out->push_back(d[m]);
  }
  return size;
}

// A row's cheapest control mode and its size.
std::pair<unsigned, size_t> best_control(const uint8_t* row, size_t elements, size_t groups) {
  std::pair<unsigned, size_t> best{3, elements};
  for (const unsigned control : {2u, 0u, 1u}) {
    const size_t s = code_row(row, elements, groups, control, nullptr);
    if (s < best.second) best = {control, s};
  }
  return best;
}

// The deltas of channel c (bytes 4c..4c+3) of elements [first, first + elements) under channel mode
// `mode` (low 4 bits; XOR's rotation in the high 4), into rows k = 0..3 of `rows` (block_max apart).
void channel_deltas(const uint8_t* data, size_t stride, size_t c, size_t first, size_t elements, unsigned mode,
                    uint8_t* rows, size_t block_max) {
  for (size_t e = 0; e < elements; ++e) {
    const size_t i = first + e;
    const uint8_t* v = data + i * stride + 4 * c;
    const uint8_t* p = i == 0 ? v : v - stride;  // the baseline is the first element
    uint8_t d[4];
    if ((mode & 15u) == 0) {
      for (size_t k = 0; k < 4; ++k) d[k] = zigzag8(uint8_t(v[k] - p[k]));
    } else if ((mode & 15u) == 1) {
      for (size_t k = 0; k < 4; k += 2) {
        const uint16_t z = zigzag16(uint16_t((v[k] | v[k + 1] << 8) - (p[k] | p[k + 1] << 8)));
        d[k] = uint8_t(z), d[k + 1] = uint8_t(z >> 8);
      }
    } else {
      uint32_t x = 0;
      for (size_t k = 0; k < 4; ++k) x |= uint32_t(v[k] ^ p[k]) << (8 * k);
      x = rotate_left(x, mode >> 4);
      for (size_t k = 0; k < 4; ++k) d[k] = uint8_t(x >> (8 * k));
    }
    for (size_t k = 0; k < 4; ++k) rows[k * block_max + e] = d[k];
  }
}

}  // namespace

std::vector<uint8_t> encode_meshopt_vertices(const uint8_t* data, size_t count, size_t stride) {
  const size_t channels = stride / 4;
  const size_t block_max = std::min<size_t>((8192 / stride) & ~(group_elements - 1), 256);
  const size_t blocks = (count + block_max - 1) / block_max;
  std::vector<uint8_t> rows(4 * block_max, 0);
  // The size a channel would take under a mode, over the blocks sampled (every one up to 64 blocks,
  // else 64 spread evenly: the choice stays linear in the stream's size).
  const size_t step = std::max<size_t>(1, blocks / 64);
  const auto channel_size = [&](size_t c, unsigned mode) {
    size_t size = 0;
    for (size_t b = 0; b < blocks; b += step) {
      const size_t first = b * block_max, elements = std::min(count - first, block_max);
      const size_t groups = (elements + group_elements - 1) / group_elements;
      std::fill(rows.begin(), rows.end(), 0);
      channel_deltas(data, stride, c, first, elements, mode, rows.data(), block_max);
      for (size_t k = 0; k < 4; ++k) size += best_control(rows.data() + k * block_max, elements, groups).second;
    }
    return size;
  };
  // Channel modes: byte deltas, 16-bit deltas, or XOR under each rotation; the smallest wins (the
  // earlier on a tie).
  std::vector<uint8_t> mode(channels, 0);
  for (size_t c = 0; c < channels; ++c) {
    size_t best = channel_size(c, 0);
    for (unsigned m = 1; m < 2 + 16; ++m) {
      const unsigned candidate = m == 1 ? 1u : 2u | (m - 2) << 4;
      const size_t s = channel_size(c, candidate);
      if (s < best) best = s, mode[c] = uint8_t(candidate);
    }
  }

  std::vector<uint8_t> out{0xa1};
  std::vector<uint8_t> block_rows(stride * block_max);
  for (size_t first = 0; first < count; first += block_max) {
    const size_t elements = std::min(count - first, block_max);
    const size_t groups = (elements + group_elements - 1) / group_elements;
    std::fill(block_rows.begin(), block_rows.end(), 0);
    for (size_t c = 0; c < channels; ++c)
      channel_deltas(data, stride, c, first, elements, mode[c], block_rows.data() + 4 * c * block_max, block_max);
    const size_t control_at = out.size();
    out.resize(out.size() + channels, 0);
    for (size_t k = 0; k < stride; ++k) {
      const uint8_t* row = block_rows.data() + k * block_max;
      const unsigned control = best_control(row, elements, groups).first;
      out[control_at + k / 4] |= uint8_t(control << (2 * (k % 4)));
      code_row(row, elements, groups, control, &out);
    }
  }
  // The tail: zeros up to 24 bytes, the baseline (the first element), the channel modes.
  const size_t tail = stride + channels;
  out.resize(out.size() + (tail < 24 ? 24 - tail : 0), 0);
  if (count) out.insert(out.end(), data, data + stride);
  else out.resize(out.size() + stride, 0);
  out.insert(out.end(), mode.begin(), mode.end());
  return out;
}

}  // namespace lod::io
