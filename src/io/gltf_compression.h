// Internal to the glTF reader: the two compression extensions real files use for geometry,
// decoded at load so that everything after the reader sees plain accessors.
//  - EXT_meshopt_compression (gltfpack -c, and its KHR_meshopt_compression successor): whole
//    bufferViews, decoded with meshoptimizer's decoders and filters;
//  - KHR_draco_mesh_compression (Draco, e.g. draco_transcoder, gltf-transform draco): a primitive's
//    attributes and indices, decoded with Draco.
// The decoded bytes go into one new buffer; the extensions are then removed from the document, so a
// file written from it is uncompressed glTF that any viewer reads.
#pragma once

#include <tiny_gltf.h>

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lodkit/io.h"
#include "lodkit/mesh.h"

namespace lod::io {

// Before tinygltf, on the parsed JSON:
//  - a buffer that only stands for meshopt-decoded data (a "fallback" buffer, or one without a URI
//    that only compressed bufferViews use) has no bytes to load, yet tinygltf 2.7 would read it from
//    the GLB's BIN chunk or a missing file and fail: each gets a small data: URI stand-in;
//  - a Draco primitive's indices accessor has no bufferView, which tinygltf 2.7 refuses: it borrows
//    the Draco stream's until decoding.
struct CompressedJson {
  std::vector<uint64_t> fallback_lengths;  // per buffer: a stand-in's declared byteLength, else 0
  bool changed = false;                    // whether tinygltf must read the rewritten JSON
};
CompressedJson prepare_compressed_json(nlohmann::json& doc, bool glb);

// After tinygltf, before any accessor is read: decodes every compressed bufferView and Draco
// primitive into plain data (`fallback_lengths` from above), checking every field,
// range and count first, and removes the extensions. Throws lod::Error (bad input) naming `name`.
void decode_compressed_geometry(tinygltf::Model& model, const std::vector<uint64_t>& fallback_lengths,
                                const std::string& name);

// Writing (WriteOptions::meshopt_compression), on the serialized document before it is dumped: its
// one buffer's bufferViews (`bin`) are encoded with meshoptimizer as EXT_meshopt_compression
// describes, without quantization or filters: a triangle list's index view in TRIANGLES mode (the
// codec may start a triangle at another corner, winding and triangle order kept), a view of
// accessors whose elements (or byteStride) take a multiple of 4 bytes up to 256 in ATTRIBUTES mode
// (vertex streams, morph targets, skins, animation: bit-exact); each only where the encoding is
// smaller. Compressed views keep their place in a fallback buffer without bytes (the extension is
// then required); `bin` holds the compressed views and the others (images, sparse data). The codec
// versions are set to the ones the extension admits (vertex 0, index 1) before each encoding:
// meshoptimizer keeps them in globals. With `meshopt_khr`, KHR_meshopt_compression, its vertex
// streams at version 1 by lodkit's own encoder (meshopt_codec.h). With `quantize` (lossy already),
// animation translation and scale keys go through the EXPONENTIAL filter (16-bit mantissas, one
// exponent per key), as gltfpack -c does, and rotation keys through the QUATERNION filter (16 bits);
// with `compress_more` too, normals and tangents through the OCTAHEDRAL filter (8 bits in bytes,
// `normal_bits` in shorts). Nothing
// changes when no view gets smaller. `directions`: the float values of normal and tangent accessors
// the writer quantized, by accessor index, 4 per element (a normal's fourth 0): the octahedral
// filter codes those, not the bytes or shorts, so the normals are quantized once, not twice.
using DirectionFloats = std::map<size_t, std::vector<float>>;
void compress_meshopt(nlohmann::json& doc, std::vector<uint8_t>& bin, const WriteOptions& options, const DirectionFloats& directions = {});

// Writing (WriteOptions::draco): a triangle mesh's vertex streams and indices as one Draco stream
// for KHR_draco_mesh_compression. Positions are quantized to `bits.position`, normals to
// `bits.normal` (octahedral), UVs to `bits.uv`, colours to 8, and the other float streams (tangents, skin weights) to 12;
// joint indices and the connectivity are exact. The stream is decoded again to describe the
// accessors, which must match what a loader decodes.
// Edgebreaker, the smaller encoding, may renumber both vertices and triangles. Streams kept outside
// the Draco stream (morph targets, attributes lodkit does not model) must line up with the decoded
// vertices: with `track_points` the caller gathers them through `point_source`.
inline constexpr const char* draco_extension = "KHR_draco_mesh_compression";
struct DracoAttribute {
  uint32_t unique_id = 0;  // in the Draco stream
  int component_type = 0;  // the accessor's
  int type = 0;            // the accessor's (TINYGLTF_TYPE_VEC2 ...)
};
struct DracoPrimitive {
  std::vector<uint8_t> bytes;
  std::map<std::string, DracoAttribute> attributes;  // by glTF semantic
  uint64_t points = 0, triangles = 0;
  float3 position_min, position_max;  // of the decoded positions
  // With `track_points`: the input vertex of each decoded point, when they differ; empty when the
  // points are the input's vertices in their order.
  std::vector<uint32_t> point_source;
  bool sequential = false;  // encoded in place, not by Edgebreaker
};
// `grid_positions` (3 per vertex, or empty): the positions already on -q's grid, stored exactly as
// unsigned shorts (KHR_mesh_quantization) instead of quantized to `bits.position`; the position
// bounds are then in grid steps.
// Nothing when libdraco cannot encode the mesh so that it decodes again (a triangle with three
// equal corners): the primitive is then written plain.
struct DracoBits {
  int position = 14, normal = 10, uv = 12;  // draco_transcoder's defaults but the positions' (11)
};
std::optional<DracoPrimitive> encode_draco(const Mesh& mesh, const DracoBits& bits, bool track_points,
                                           std::span<const uint16_t> grid_positions = {});

}  // namespace lod::io
