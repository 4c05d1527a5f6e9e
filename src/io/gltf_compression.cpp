// glTF compression extensions, decoded at load (see gltf_compression.h). Every field, byte range and
// count is checked before a decoder runs or anything is allocated: a decoded size is bounded by the
// compressed bytes actually present (meshopt) or must equal the accessors' counts (Draco).
#include "io/gltf_compression.h"
#include "io/meshopt_codec.h"

#include <draco/compression/decode.h>
#include <draco/compression/expert_encode.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <new>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <unordered_map>

#include "io/gltf_types.h"
#include "lodkit/error.h"

namespace lod::io {
namespace {

namespace tg = tinygltf;
using Json = nlohmann::json;

constexpr std::array<const char*, 2> meshopt_names = {"EXT_meshopt_compression", "KHR_meshopt_compression"};
constexpr const char* draco_name = draco_extension;
// 3 zero bytes: the smallest data: URI tinygltf accepts for a buffer.
constexpr const char* stand_in_uri = "data:application/octet-stream;base64,AAAA";
constexpr uint64_t stand_in_length = 3;
// A meshopt stream spends at least 2 header bits per 16 decoded bytes (attributes, version 0), a
// byte per triangle (triangles) or per index (indices): no valid stream decodes to more than 64
// times its size. Version 1 attributes spend at least 2 control bits per byte position of a block
// of up to 256 elements (a constant stream): 1024 times.
constexpr uint64_t max_meshopt_ratio = 64, max_meshopt_v1_ratio = 1024;

std::string str(uint64_t v) { return std::to_string(v); }

// The meshopt extension object of a JSON bufferView or buffer, or nullptr.
const Json* meshopt_json(const Json& object) {
  if (!object.is_object()) return nullptr;
  auto extensions = object.find("extensions");
  if (extensions == object.end() || !extensions->is_object()) return nullptr;
  for (const char* ext : meshopt_names)
    if (auto it = extensions->find(ext); it != extensions->end()) return &*it;
  return nullptr;
}

// The meshopt extension object of a loaded bufferView (and its name), or nullptr.
const tg::Value* meshopt_value(const tg::ExtensionMap& extensions, const char** which) {
  for (const char* ext : meshopt_names)
    if (auto it = extensions.find(ext); it != extensions.end()) {
      *which = ext;
      return &it->second;
    }
  return nullptr;
}

class Decoder {
 public:
  Decoder(tg::Model& model, const std::vector<uint64_t>& fallback_lengths, const std::string& name)
      : model_(model), fallback_(fallback_lengths), name_(name) {}

  void run() {
    for (size_t v = 0; v < model_.bufferViews.size(); ++v) decode_meshopt_view(v);
    add_buffer();
    for (size_t m = 0; m < model_.meshes.size(); ++m)
      for (size_t p = 0; p < model_.meshes[m].primitives.size(); ++p) decode_draco_primitive(m, p);
    add_buffer();
    for (const char* ext : meshopt_names) forget_extension(ext);
    forget_extension(draco_name);
    for (tg::Buffer& buffer : model_.buffers)
      for (const char* ext : meshopt_names) buffer.extensions.erase(ext);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw_bad_input(name_, what); }

  bool is_stand_in(int buffer) const { return buffer >= 0 && size_t(buffer) < fallback_.size() && fallback_[size_t(buffer)] > 0; }

  uint64_t field(const tg::Value& object, const char* key, const std::string& where, bool required, uint64_t otherwise = 0) const {
    if (!object.Has(key)) {
      if (required) fail(where + " has no '" + key + "'");
      return otherwise;
    }
    const tg::Value& value = object.Get(key);
    const double d = value.IsNumber() ? value.GetNumberAsDouble() : -1.0;
    if (!(d >= 0.0 && d <= 9007199254740992.0 && d == std::floor(d)))
      fail(where + "." + key + " is not a non-negative integer");
    return uint64_t(d);
  }

  std::string text_field(const tg::Value& object, const char* key, const std::string& where, const char* otherwise) const {
    if (!object.Has(key)) {
      if (!otherwise) fail(where + " has no '" + key + "'");
      return otherwise;
    }
    const tg::Value& value = object.Get(key);
    if (!value.IsString()) fail(where + "." + key + " is not a string");
    return value.Get<std::string>();
  }

  // The bytes [offset, offset + length) of a loaded buffer.
  const uint8_t* buffer_range(uint64_t buffer, uint64_t offset, uint64_t length, const std::string& what) const {
    if (buffer >= model_.buffers.size()) fail(what + " refers to buffers[" + str(buffer) + "], which does not exist");
    if (is_stand_in(int(buffer)))
      fail(what + " refers to buffers[" + str(buffer) + "], which only stands for decoded data and holds no bytes");
    const std::vector<unsigned char>& data = model_.buffers[buffer].data;
    if (offset > data.size() || length > data.size() - offset)
      fail(what + " (bytes " + str(offset) + ".." + str(offset + length) + ") runs past the end of buffers[" + str(buffer) + "] (" +
           str(data.size()) + " bytes)");
    return data.data() + offset;
  }

  // Room for `bytes` decoded bytes at a 4-byte aligned offset of the buffer being filled.
  size_t reserve(uint64_t bytes) {
    decoded_.resize((decoded_.size() + 3) & ~size_t(3), 0);
    const size_t offset = decoded_.size();
    decoded_.resize(offset + size_t(bytes), 0);
    return offset;
  }

  // The buffer being filled joins the document (nothing when empty).
  void add_buffer() {
    if (decoded_.empty()) return;
    tg::Buffer buffer;
    buffer.data = std::move(decoded_);
    decoded_.clear();
    model_.buffers.push_back(std::move(buffer));
  }
  // The index the buffer being filled will have once added.
  int filling_buffer() const { return int(model_.buffers.size()); }

  void forget_extension(const std::string& ext) {
    std::erase(model_.extensionsUsed, ext);
    std::erase(model_.extensionsRequired, ext);
  }

  void decode_meshopt_view(size_t v) {
    tg::BufferView& view = model_.bufferViews[v];
    const std::string view_where = "bufferViews[" + str(v) + "]";
    const char* ext_name = nullptr;
    const tg::Value* ext = meshopt_value(view.extensions, &ext_name);
    if (!ext) return;  // (a stand-in buffer has compressed users only)
    const std::string where = view_where + ".extensions." + ext_name;
    if (!ext->IsObject()) fail(where + " is not an object");
    const uint64_t buffer = field(*ext, "buffer", where, true);
    const uint64_t offset = field(*ext, "byteOffset", where, false);
    const uint64_t length = field(*ext, "byteLength", where, true);
    const uint64_t stride = field(*ext, "byteStride", where, true);
    const uint64_t count = field(*ext, "count", where, true);
    const std::string mode = text_field(*ext, "mode", where, nullptr);
    const std::string filter = text_field(*ext, "filter", where, "NONE");

    if (mode == "ATTRIBUTES") {
      if (stride == 0 || stride % 4 != 0 || stride > 256) fail(where + ": byteStride " + str(stride) + " is not a multiple of 4 in 4..256");
    } else if (mode == "TRIANGLES" || mode == "INDICES") {
      if (stride != 2 && stride != 4) fail(where + ": byteStride " + str(stride) + " is not 2 or 4 (mode " + mode + ")");
      if (mode == "TRIANGLES" && count % 3 != 0) fail(where + ": count " + str(count) + " is not a multiple of 3 (mode TRIANGLES)");
      if (filter != "NONE") fail(where + ": filter " + filter + " needs mode ATTRIBUTES, not " + mode);
    } else {
      fail(where + ": mode '" + mode + "' is not ATTRIBUTES, TRIANGLES or INDICES");
    }
    if (filter == "OCTAHEDRAL") {
      if (stride != 4 && stride != 8) fail(where + ": filter OCTAHEDRAL needs byteStride 4 or 8, not " + str(stride));
    } else if (filter == "QUATERNION") {
      if (stride != 8) fail(where + ": filter QUATERNION needs byteStride 8, not " + str(stride));
    } else if (filter == "COLOR") {
      if (stride != 4 && stride != 8) fail(where + ": filter COLOR needs byteStride 4 or 8, not " + str(stride));
    } else if (filter != "NONE" && filter != "EXPONENTIAL") {
      fail(where + ": filter '" + filter + "' is not NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL or COLOR");
    }
    if (count == 0) fail(where + ": count is 0");
    const uint64_t bytes = count * stride;  // count < 2^53 and stride <= 256: no overflow
    if (view.byteLength != bytes)
      fail(view_where + ".byteLength " + str(view.byteLength) + " is not byteStride " + str(stride) + " times count " + str(count));
    if (view.byteStride != 0 && view.byteStride != stride)
      fail(view_where + ".byteStride " + str(view.byteStride) + " differs from its " + ext_name + " byteStride " + str(stride));
    const uint8_t* source = buffer_range(buffer, offset, length, where);
    const bool v1 = mode == "ATTRIBUTES" && length > 0 && source[0] == 0xa1;
    if (bytes > (v1 ? max_meshopt_v1_ratio : max_meshopt_ratio) * length)
      fail(where + ": " + str(count) + " elements of " + str(stride) + " bytes cannot come from " + str(length) +
           " bytes of compressed data");

    const size_t at = reserve(bytes);
    unsigned char* out = decoded_.data() + at;
    const std::string bytes_where = where + ": bytes " + str(offset) + ".." + str(offset + length) + " of buffers[" + str(buffer) + "]";
    const std::span<const uint8_t> stream(source, size_t(length));
    if (mode == "ATTRIBUTES" && length > 0 && source[0] != 0xa0) {
      // Vertex codec version 1 (KHR_meshopt_compression, meshoptimizer 0.23 and later), newer than
      // Debian's meshoptimizer 0.18: lodkit's own decoder (a header it does not know fails there).
      const std::string why = decode_meshopt_vertices(out, size_t(count), size_t(stride), stream);
      if (!why.empty()) fail(bytes_where + " do not decode as ATTRIBUTES data: " + why);
    } else {
      // meshoptimizer's SIMD decoders; a vertex stream they refuse is decoded again by lodkit's,
      // which says where it goes wrong.
      int rc = 0;
      if (mode == "ATTRIBUTES") rc = meshopt_decodeVertexBuffer(out, size_t(count), size_t(stride), source, size_t(length));
      else if (mode == "TRIANGLES") rc = meshopt_decodeIndexBuffer(out, size_t(count), size_t(stride), source, size_t(length));
      else rc = meshopt_decodeIndexSequence(out, size_t(count), size_t(stride), source, size_t(length));
      if (rc != 0) {
        std::string why = mode == "ATTRIBUTES" ? decode_meshopt_vertices(out, size_t(count), size_t(stride), stream) : "";
        if (why.empty()) why = "corrupt";
        fail(bytes_where + " do not decode as " + mode + " data (meshoptimizer error " + std::to_string(rc) + ": " + why + ")");
      }
    }
    if (filter == "OCTAHEDRAL") decode_meshopt_octahedral_filter(out, size_t(count), size_t(stride));  // (the same on every processor)
    else if (filter == "QUATERNION") meshopt_decodeFilterQuat(out, size_t(count), size_t(stride));
    else if (filter == "EXPONENTIAL") meshopt_decodeFilterExp(out, size_t(count), size_t(stride));
    else if (filter == "COLOR") decode_meshopt_color_filter(out, size_t(count), size_t(stride));  // (newer than 0.18 too)

    view.buffer = filling_buffer();
    view.byteOffset = at;
    view.extensions.erase(ext_name);
  }

  template <class T>
  void convert_attribute(const draco::PointAttribute& attribute, size_t points, int components, unsigned char* out,
                         const std::string& what) const {
    T value[4];
    for (size_t i = 0; i < points; ++i) {
      const draco::AttributeValueIndex index = attribute.mapped_index(draco::PointIndex(uint32_t(i)));
      if (index.value() >= attribute.size()) fail(what + ": point " + str(i) + " maps to a value the Draco stream does not have");
      if (!attribute.ConvertValue<T>(index, int8_t(components), value))
        fail(what + ": value " + str(index.value()) + " does not convert to the accessor's component type");
      std::memcpy(out + i * sizeof(T) * size_t(components), value, sizeof(T) * size_t(components));
    }
  }

  // A new bufferView of `bytes` decoded bytes for accessor `a`; returns where to write them.
  unsigned char* give_view(int a, uint64_t bytes) {
    const size_t at = reserve(bytes);
    tg::BufferView view;
    view.buffer = filling_buffer();
    view.byteOffset = at;
    view.byteLength = size_t(bytes);
    model_.bufferViews.push_back(std::move(view));
    tg::Accessor& acc = model_.accessors[size_t(a)];
    acc.bufferView = int(model_.bufferViews.size() - 1);
    acc.byteOffset = 0;
    return decoded_.data() + at;
  }

  // Checks accessor `a` for a Draco stream (by bufferView) and returns false when that same stream
  // has already filled it (primitives sharing accessors and stream).
  bool claim_accessor(int a, int stream, const std::string& what) {
    if (a < 0 || size_t(a) >= model_.accessors.size()) fail(what + " refers to accessors[" + std::to_string(a) + "], which does not exist");
    filled_by_.resize(model_.accessors.size(), -1);
    int& owner = filled_by_[size_t(a)];
    if (owner == stream) return false;
    if (owner >= 0) fail(what + ": accessors[" + std::to_string(a) + "] is also filled from another Draco stream");
    owner = stream;
    const tg::Accessor& acc = model_.accessors[size_t(a)];
    if (acc.sparse.isSparse) fail(what + ": accessors[" + std::to_string(a) + "] is sparse, which a Draco-compressed accessor cannot be");
    return true;
  }

  void decode_draco_primitive(size_t m, size_t p) {
    tg::Primitive& prim = model_.meshes[m].primitives[p];
    auto found = prim.extensions.find(draco_name);
    if (found == prim.extensions.end()) return;
    const std::string prim_where = "meshes[" + str(m) + "].primitives[" + str(p) + "]";
    const std::string where = prim_where + ".extensions." + draco_name;
    const tg::Value& ext = found->second;
    if (!ext.IsObject()) fail(where + " is not an object");
    const uint64_t view_index = field(ext, "bufferView", where, true);
    if (view_index >= model_.bufferViews.size())
      fail(where + ".bufferView refers to bufferViews[" + str(view_index) + "], which does not exist");
    if (prim.mode != TINYGLTF_MODE_TRIANGLES)
      fail(prim_where + " has mode " + std::to_string(prim.mode) + "; lodkit decodes Draco triangle lists (mode 4) only");
    if (!ext.Has("attributes") || !ext.Get("attributes").IsObject()) fail(where + " has no 'attributes' object");
    // A view that the meshopt step decoded lives in a buffer already added. (A copy: give_view below
    // adds bufferViews.)
    const tg::BufferView view = model_.bufferViews[view_index];
    const uint8_t* bytes = buffer_range(uint64_t(std::max(view.buffer, 0)), view.byteOffset, view.byteLength,
                                        where + "'s bufferViews[" + str(view_index) + "]");

    draco::DecoderBuffer input;
    input.Init(reinterpret_cast<const char*>(bytes), view.byteLength);
    std::unique_ptr<draco::Mesh> mesh;
    try {
      draco::Decoder decoder;
      auto decoded = decoder.DecodeMeshFromBuffer(&input);
      if (!decoded.ok())
        fail(where + ": bufferViews[" + str(view_index) + "] does not decode as a Draco mesh (" + decoded.status().error_msg_string() + ")");
      mesh = std::move(decoded).value();
    } catch (const std::bad_alloc&) {
      fail(where + ": bufferViews[" + str(view_index) + "] declares a Draco mesh too large to decode");
    }
    const size_t points = mesh->num_points(), faces = mesh->num_faces();
    const int stream = int(view_index);

    const tg::Value& attributes = ext.Get("attributes");
    for (const std::string& semantic : attributes.Keys()) {
      const std::string what = where + ".attributes." + semantic;
      const uint64_t id = field(attributes, semantic.c_str(), where + ".attributes", true);
      auto accessor = prim.attributes.find(semantic);
      if (accessor == prim.attributes.end()) fail(what + ": the primitive has no " + semantic + " attribute");
      const draco::PointAttribute* attribute = id <= std::numeric_limits<uint32_t>::max() ? mesh->GetAttributeByUniqueId(uint32_t(id)) : nullptr;
      if (!attribute) fail(what + ": the Draco stream has no attribute with unique id " + str(id));
      if (!claim_accessor(accessor->second, stream, what)) continue;
      const tg::Accessor& acc = model_.accessors[size_t(accessor->second)];
      const std::string acc_where = what + " (accessors[" + std::to_string(accessor->second) + "])";
      const int components = int(type_components(acc.type));
      const size_t size = component_bytes(acc.componentType);
      if (components == 0 || size == 0) fail(acc_where + " has a type or componentType that Draco attributes cannot have");
      if (components != attribute->num_components())
        fail(acc_where + " has " + std::to_string(components) + " components, the Draco attribute " + std::to_string(attribute->num_components()));
      if (acc.count != points)
        fail(acc_where + " has count " + str(acc.count) + " but the Draco mesh has " + str(points) + " points");
      unsigned char* out = give_view(accessor->second, uint64_t(points) * size * size_t(components));
      switch (acc.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: convert_attribute<float>(*attribute, points, components, out, acc_where); break;
        case TINYGLTF_COMPONENT_TYPE_BYTE: convert_attribute<int8_t>(*attribute, points, components, out, acc_where); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: convert_attribute<uint8_t>(*attribute, points, components, out, acc_where); break;
        case TINYGLTF_COMPONENT_TYPE_SHORT: convert_attribute<int16_t>(*attribute, points, components, out, acc_where); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: convert_attribute<uint16_t>(*attribute, points, components, out, acc_where); break;
        default: convert_attribute<uint32_t>(*attribute, points, components, out, acc_where); break;
      }
    }

    const std::string what = prim_where + ".indices";
    if (prim.indices < 0) fail(what + " is missing; a Draco-compressed primitive is indexed");
    if (claim_accessor(prim.indices, stream, what)) {
      const tg::Accessor& acc = model_.accessors[size_t(prim.indices)];
      const std::string acc_where = what + " (accessors[" + std::to_string(prim.indices) + "])";
      const size_t size = component_bytes(acc.componentType);
      if (acc.type != TINYGLTF_TYPE_SCALAR || size == 0 || acc.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
          acc.componentType == TINYGLTF_COMPONENT_TYPE_BYTE || acc.componentType == TINYGLTF_COMPONENT_TYPE_SHORT)
        fail(acc_where + " is not a SCALAR of unsigned integers");
      if (acc.count != uint64_t(faces) * 3)
        fail(acc_where + " has count " + str(acc.count) + " but the Draco mesh has " + str(faces) + " triangles");
      if (size < 4 && points > (uint64_t(1) << (8 * size)))
        fail(acc_where + ": " + str(points) + " points do not fit its " + str(8 * size) + "-bit indices");
      unsigned char* out = give_view(prim.indices, uint64_t(faces) * 3 * size);
      for (size_t f = 0; f < faces; ++f) {
        const draco::Mesh::Face& face = mesh->face(draco::FaceIndex(uint32_t(f)));
        for (size_t c = 0; c < 3; ++c) {
          const uint32_t index = face[c].value();
          if (index >= points) fail(acc_where + ": Draco triangle " + str(f) + " refers to point " + str(index) + " of " + str(points));
          std::memcpy(out + (f * 3 + c) * size, &index, size);  // little-endian: the low bytes
        }
      }
    }
    prim.extensions.erase(found);
  }

  tg::Model& model_;
  const std::vector<uint64_t>& fallback_;
  const std::string& name_;
  std::vector<unsigned char> decoded_;  // the buffer being filled
  std::vector<int> filled_by_;          // per accessor: the Draco stream (bufferView) that filled it
};

}  // namespace

CompressedJson prepare_compressed_json(Json& doc, bool glb) {
  CompressedJson out;
  auto buffers = doc.find("buffers");
  auto views = doc.find("bufferViews");
  if (buffers != doc.end() && buffers->is_array() && views != doc.end() && views->is_array()) {
    const size_t n = buffers->size();
    std::vector<size_t> compressed_users(n, 0), plain_users(n, 0);
    for (const Json& view : *views) {
      if (!view.is_object()) continue;
      auto buffer = view.find("buffer");
      if (buffer == view.end() || !buffer->is_number_unsigned() || buffer->get<uint64_t>() >= n) continue;
      ++(meshopt_json(view) ? compressed_users : plain_users)[buffer->get<size_t>()];
    }
    out.fallback_lengths.assign(n, 0);
    for (size_t b = 0; b < n; ++b) {
      Json& buffer = (*buffers)[b];
      if (!buffer.is_object() || compressed_users[b] == 0 || plain_users[b] != 0) continue;
      const Json* ext = meshopt_json(buffer);
      // (Only `true` marks a fallback; any other value, malformed, leaves the buffer as it is.)
      const bool fallback = ext && ext->is_object() && ext->contains("fallback") && (*ext)["fallback"] == true;
      // A GLB's buffer 0 without a URI is its BIN chunk, which holds real bytes.
      if (!fallback && (buffer.contains("uri") || (glb && b == 0))) continue;
      auto length = buffer.find("byteLength");
      if (length == buffer.end() || !length->is_number_unsigned() || length->get<uint64_t>() == 0) continue;  // tinygltf reports it
      out.fallback_lengths[b] = length->get<uint64_t>();
      buffer["uri"] = stand_in_uri;
      buffer["byteLength"] = stand_in_length;
      out.changed = true;
    }
  }
  // tinygltf 2.7 refuses an indices accessor without a bufferView, which a Draco primitive's has:
  // it borrows the Draco stream's view until the decoder gives it its own.
  auto meshes = doc.find("meshes");
  auto accessors = doc.find("accessors");
  if (meshes == doc.end() || !meshes->is_array() || accessors == doc.end() || !accessors->is_array()) return out;
  for (const Json& mesh : *meshes) {
    auto primitives = mesh.is_object() ? mesh.find("primitives") : mesh.end();
    if (primitives == mesh.end() || !primitives->is_array()) continue;
    for (const Json& primitive : *primitives) {
      if (!primitive.is_object()) continue;
      auto extensions = primitive.find("extensions");
      auto indices = primitive.find("indices");
      if (extensions == primitive.end() || !extensions->is_object() || indices == primitive.end() ||
          !indices->is_number_unsigned() || indices->get<uint64_t>() >= accessors->size())
        continue;
      auto draco = extensions->find(draco_name);
      if (draco == extensions->end() || !draco->is_object()) continue;
      auto view = draco->find("bufferView");
      Json& accessor = (*accessors)[indices->get<size_t>()];
      if (view == draco->end() || !view->is_number_unsigned() || !accessor.is_object() || accessor.contains("bufferView")) continue;
      accessor["bufferView"] = *view;
      out.changed = true;
    }
  }
  return out;
}

void decode_compressed_geometry(tg::Model& model, const std::vector<uint64_t>& fallback_lengths, const std::string& name) {
  Decoder(model, fallback_lengths, name).run();
}

namespace {

size_t element_size(const Json& accessor) {
  return type_components(accessor.value("type", std::string())) * component_bytes(accessor.value("componentType", 0));
}

// Mantissa bits of animation translation and scale keys under -c -q (gltfpack's -at and -as default).
constexpr int animation_exp_bits = 16;
// Bits of the three smaller components of rotation keys under -c -q: the most the QUATERNION filter
// takes, finer (by sqrt 2) than the normalized shorts -q writes, so it adds no more than their own
// rounding.
constexpr int animation_quat_bits = 16;

// A filter for a view of animation keys or of directions (under -q only: each is lossy).
enum class ViewFilter { none, exponential, quaternion, octahedral };

// How a bufferView may be encoded, from the accessors that use it.
struct ViewUse {
  bool indices = false, attributes = false, excluded = false;
  // Every accessor of the view holds animation translation or scale keys (float VEC3), or every one
  // rotation keys (normalized short VEC4), or every one a primitive's normals or tangents (normalized
  // bytes, or every one normalized shorts: `direction_bytes`): with -q they may go through the
  // EXPONENTIAL, QUATERNION or OCTAHEDRAL filter.
  bool keys = false, rotations = false, directions = false, other = false;
  uint64_t direction_bytes = 0;
  uint64_t stride = 0;  // element (or byteStride) size shared by its accessors
};

std::vector<ViewUse> view_uses(const Json& doc) {
  const Json& views = doc["bufferViews"];
  std::vector<ViewUse> use(views.size());
  static const Json none = Json::array();
  const Json& accessors = doc.contains("accessors") ? doc["accessors"] : none;
  // Per accessor: indices of triangle lists (1), of other topologies (2: strips stay plain), or not (0).
  std::vector<int> indices(accessors.size(), 0);
  for (const Json& mesh : doc.value("meshes", Json::array()))
    for (const Json& primitive : mesh.value("primitives", Json::array()))
      if (primitive.contains("indices"))
        indices.at(primitive["indices"].get<size_t>()) |= primitive.value("mode", 4) == 4 ? 1 : 2;
  // Per accessor: the output of a translation or scale channel's sampler (1), of a rotation's (2), a
  // primitive's NORMAL or TANGENT (3); -1: two of those.
  std::vector<int> kinds(accessors.size(), 0);
  const auto mark = [&](const Json& accessor, int kind) {
    int& k = kinds.at(accessor.get<size_t>());
    k = k && k != kind ? -1 : kind;
  };
  for (const Json& mesh : doc.value("meshes", Json::array()))
    for (const Json& primitive : mesh.value("primitives", Json::array()))
      for (const char* name : {"NORMAL", "TANGENT"})
        if (primitive.contains("attributes") && primitive["attributes"].contains(name)) mark(primitive["attributes"][name], 3);
  for (const Json& animation : doc.value("animations", Json::array())) {
    const Json samplers = animation.value("samplers", Json::array());
    for (const Json& channel : animation.value("channels", Json::array())) {
      const std::string path = channel.value("target", Json::object()).value("path", std::string());
      const size_t sampler = channel.value("sampler", size_t(0));
      const int kind = path == "translation" || path == "scale" ? 1 : path == "rotation" ? 2 : 0;
      if (kind && sampler < samplers.size() && samplers[sampler].contains("output")) mark(samplers[sampler]["output"], kind);
    }
  }
  for (size_t k = 0; k < accessors.size(); ++k) {
    const Json& accessor = accessors[k];
    if (accessor.contains("sparse"))  // its sparse parts stay plain (small, and of two kinds)
      for (const char* part : {"indices", "values"}) use.at(accessor["sparse"][part]["bufferView"].get<size_t>()).excluded = true;
    if (!accessor.contains("bufferView")) continue;
    ViewUse& u = use.at(accessor["bufferView"].get<size_t>());
    const Json& view = views[accessor["bufferView"].get<size_t>()];
    const uint64_t element = element_size(accessor), count = accessor.value("count", uint64_t(0));
    if (indices[k] != 0) {
      u.indices = true;
      // TRIANGLES mode: the whole view is one list (merge_views may have put several accessors'
      // lists in it), 16- or 32-bit, each accessor on whole triangles.
      u.excluded |= indices[k] != 1 || !(element == 2 || element == 4) || accessor.value("byteOffset", uint64_t(0)) % (3 * element) != 0 ||
                    view.contains("byteStride") || count % 3 != 0 || view.value("byteLength", uint64_t(0)) % (3 * element) != 0 ||
                    (u.stride && u.stride != element);
      u.stride = element;
    } else {
      u.attributes = true;
      const int type = accessor.value("componentType", 0);
      const bool normalized = accessor.value("normalized", false);
      const std::string vec = accessor.value("type", std::string());
      if (kinds[k] == 1 && type == TINYGLTF_COMPONENT_TYPE_FLOAT && vec == "VEC3" && !normalized) u.keys = true;
      else if (kinds[k] == 2 && type == TINYGLTF_COMPONENT_TYPE_SHORT && vec == "VEC4" && normalized) u.rotations = true;
      else if (kinds[k] == 3 && (type == TINYGLTF_COMPONENT_TYPE_BYTE || type == TINYGLTF_COMPONENT_TYPE_SHORT) &&
               (vec == "VEC3" || vec == "VEC4") && normalized) {
        const uint64_t bytes = type == TINYGLTF_COMPONENT_TYPE_BYTE ? 1 : 2;
        if (u.direction_bytes && u.direction_bytes != bytes) u.other = true;
        u.directions = true, u.direction_bytes = bytes;
      } else {
        u.other = true;
      }
      const uint64_t stride = view.value("byteStride", element);
      u.excluded |= stride == 0 || stride % 4 != 0 || stride > 256 || (u.stride && u.stride != stride);
      u.stride = stride;
    }
  }
  return use;
}

// The view's bytes encoded (vertex streams at version 1 with `khr`) after `filter`, or nothing when
// that is not smaller. `normal_bits`: the octahedral filter's bits on shorts (bytes take 8);
// `given`: its input, 4 floats per element, where the caller has them (else the stored integers).
std::vector<uint8_t> encode_view(const uint8_t* data, uint64_t length, const ViewUse& u, bool khr, ViewFilter filter, int normal_bits,
                                 std::span<const float> given) {
  const size_t count = size_t(length / u.stride);
  std::vector<uint8_t> out;
  if (u.indices) {
    std::vector<uint32_t> indices(count);
    uint32_t largest = 0;
    for (size_t i = 0; i < count; ++i) {
      if (u.stride == 2) {
        uint16_t v;
        std::memcpy(&v, data + 2 * i, 2);
        indices[i] = v;
      } else {
        std::memcpy(&indices[i], data + 4 * i, 4);
      }
      largest = std::max(largest, indices[i]);
    }
    meshopt_encodeIndexVersion(1);  // the version EXT_meshopt_compression's TRIANGLES mode requires (0.18 writes 0)
    out.resize(meshopt_encodeIndexBufferBound(count, size_t(largest) + 1));
    out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), indices.data(), count));
  } else {
    std::vector<uint8_t> filtered;
    if (filter == ViewFilter::exponential) {
      std::vector<float> values(size_t(length) / 4);
      std::memcpy(values.data(), data, values.size() * 4);
      filtered.resize(size_t(length));
      meshopt_encodeFilterExp(filtered.data(), count, size_t(u.stride), animation_exp_bits, values.data());
      data = filtered.data();
    } else if (filter == ViewFilter::quaternion) {
      // The filter keeps the three smaller components and drops the sign (the decoder makes the
      // largest positive): glTF interpolates rotations along the shorter arc, so q and -q animate
      // alike.
      std::vector<float> values(size_t(length) / 2);
      for (size_t i = 0; i < values.size(); ++i) {
        int16_t v;
        std::memcpy(&v, data + 2 * i, 2);
        values[i] = std::max(float(v) / 32767.0f, -1.0f);  // (normalized shorts, as glTF decodes them)
      }
      filtered.resize(size_t(length));
      meshopt_encodeFilterQuat(filtered.data(), count, size_t(u.stride), animation_quat_bits, values.data());
      data = filtered.data();
    } else if (filter == ViewFilter::octahedral) {
      // Normalized bytes or shorts in (a normal's fourth component is padding; a tangent's w, its
      // handedness, the filter keeps).
      const bool wide = u.stride == 8;
      std::vector<float> values(static_cast<size_t>(length) / (wide ? 2 : 1));
      if (given.size() == values.size()) std::copy(given.begin(), given.end(), values.begin());
      for (size_t i = 0; i < values.size(); ++i) {
        if (given.size() == values.size() && !std::isnan(given[i])) continue;
        if (wide) {
          int16_t v;
          std::memcpy(&v, data + 2 * i, 2);
          values[i] = std::max(float(v) / 32767.0f, -1.0f);
        } else {
          values[i] = std::max(float(int8_t(data[i])) / 127.0f, -1.0f);
        }
      }
      filtered.resize(size_t(length));
      meshopt_encodeFilterOct(filtered.data(), count, size_t(u.stride), wide ? normal_bits : 8, values.data());
      data = filtered.data();
    }
    if (khr) {
      out = encode_meshopt_vertices(data, count, size_t(u.stride));
    } else {
      meshopt_encodeVertexVersion(0);  // the only one EXT_meshopt_compression admits (later releases default to 1)
      out.resize(meshopt_encodeVertexBufferBound(count, size_t(u.stride)));
      out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), data, count, size_t(u.stride)));
    }
  }
  if (out.empty() || out.size() >= length) return {};
  return out;
}

// What each accessor holds, for merge_views: a mesh attribute or a morph target's by name (without
// its set number), indices, inverse bind matrices, a sampler's times, its keys by the path they
// animate, an instancing attribute; "" for anything else.
std::vector<std::string> accessor_roles(const Json& doc) {
  std::vector<std::string> role(doc.value("accessors", Json::array()).size());
  const auto set = [&](const Json& index, const std::string& what) {
    if (!index.is_number_unsigned() || index.get<size_t>() >= role.size()) return;
    std::string& r = role[index.get<size_t>()];
    r = r.empty() || r == what ? what : "mixed";
  };
  const auto base = [](const std::string& name) { return name.substr(0, name.find_last_not_of("0123456789") + 1); };
  for (const Json& mesh : doc.value("meshes", Json::array()))
    for (const Json& primitive : mesh.value("primitives", Json::array())) {
      const Json attributes = primitive.value("attributes", Json::object());
      for (const auto& [name, index] : attributes.items()) set(index, "attribute " + base(name));
      if (primitive.contains("indices")) set(primitive["indices"], "indices");
      for (const Json& target : primitive.value("targets", Json::array()))
        for (const auto& [name, index] : target.items()) set(index, "target " + base(name));
    }
  for (const Json& skin : doc.value("skins", Json::array()))
    if (skin.contains("inverseBindMatrices")) set(skin["inverseBindMatrices"], "inverse bind matrices");
  for (const Json& animation : doc.value("animations", Json::array())) {
    const Json samplers = animation.value("samplers", Json::array());
    for (const Json& sampler : samplers)
      if (sampler.contains("input")) set(sampler["input"], "times");
    for (const Json& channel : animation.value("channels", Json::array())) {
      const size_t sampler = channel.value("sampler", samplers.size());
      if (sampler < samplers.size() && samplers[sampler].contains("output"))
        set(samplers[sampler]["output"], "keys " + channel.value("target", Json::object()).value("path", std::string()));
    }
  }
  for (const Json& node : doc.value("nodes", Json::array()))
    if (node.contains("extensions") && node["extensions"].contains("EXT_mesh_gpu_instancing"))
      for (const Json attributes = node["extensions"]["EXT_mesh_gpu_instancing"].value("attributes", Json::object());
           const auto& [name, index] : attributes.items())
        set(index, "instances " + name);
  for (std::string& r : role)
    if (r == "mixed") r.clear();
  return role;
}

// Calls f on every "bufferView" index in `json` (an accessor's, its sparse parts', an image's, an
// extension's).
template <class F>
void for_each_view_reference(Json& json, F&& f) {
  if (json.is_array()) {
    for (Json& item : json) for_each_view_reference(item, f);
    return;
  }
  if (!json.is_object()) return;
  for (auto& [key, value] : json.items()) {
    if (key == "bufferView" && value.is_number_unsigned()) f(value);
    else for_each_view_reference(value, f);
  }
}

// Merges the views that hold the same kind of data (one vertex stream, indices, a sampler's times,
// one path's keys: accessor_roles), with one stride and filter, into one view each, as gltfpack
// lays them out: every compressed view costs a header, a tail and its JSON (a LOD chain's or a
// clip's dozens of small views), and meshopt codes the concatenation in about the parts' bytes.
// Views that something other than an accessor uses, or that carry extensions or extras, stay.
void merge_views(Json& doc, std::vector<uint8_t>& bin, const std::vector<ViewUse>& use, const std::vector<ViewFilter>& filters) {
  Json& views = doc["bufferViews"];
  Json& accessors = doc["accessors"];
  const std::vector<std::string> roles = accessor_roles(doc);
  std::vector<std::string> kind(views.size());  // its accessors' one role ("" for none or unknown)
  std::vector<bool> shared(views.size(), false), used(views.size(), false);
  for (size_t a = 0; a < accessors.size(); ++a) {
    if (!accessors[a].contains("bufferView")) continue;
    const size_t v = accessors[a]["bufferView"].get<size_t>();
    if (v >= views.size()) return;
    if (used[v] && kind[v] != roles[a]) shared[v] = true;  // accessors of two roles: it stays
    used[v] = true;
    kind[v] = roles[a];
  }
  // Views something else uses (a sparse accessor's parts, an image, an extension) stay as they are.
  const auto hold = [&](const Json& index) {
    if (index.get<size_t>() < shared.size()) shared[index.get<size_t>()] = true;
  };
  for (Json& accessor : accessors)
    if (accessor.contains("sparse")) for_each_view_reference(accessor["sparse"], hold);
  for (auto& [key, value] : doc.items())
    if (key != "accessors" && key != "bufferViews") for_each_view_reference(value, hold);
  // Groups in order of their first view; a view that cannot merge is a group of its own.
  std::map<std::tuple<bool, uint64_t, int, std::string, int>, size_t> group_of;
  std::vector<std::vector<size_t>> groups;
  std::vector<size_t> group(views.size());
  for (size_t v = 0; v < views.size(); ++v) {
    const ViewUse& u = use[v];
    const uint64_t length = views[v]["byteLength"].get<uint64_t>();
    const bool can = !shared[v] && !kind[v].empty() && !u.excluded && u.stride != 0 && !(u.indices && u.attributes) &&
                     length % u.stride == 0 && views[v].value("buffer", 0) == 0 && !views[v].contains("extensions") &&
                     !views[v].contains("extras") && !views[v].contains("name");
    if (can) {
      const auto key = std::tuple{u.indices, u.stride, int(filters[v]), kind[v], views[v].value("target", 0)};
      const auto [at, fresh] = group_of.try_emplace(key, groups.size());
      if (!fresh) {
        group[v] = at->second;
        groups[at->second].push_back(v);
        continue;
      }
    }
    group[v] = groups.size();
    groups.push_back({v});
  }
  if (groups.size() == views.size()) return;
  // The new buffer: each group's views one after another (whole elements: strides of attributes
  // are multiples of 4, index lists whole triangles), groups 4-aligned.
  std::vector<uint8_t> packed;
  std::vector<uint64_t> moved(views.size());  // a view's offset within its group's view
  Json merged = Json::array();
  for (const std::vector<size_t>& members : groups) {
    packed.resize((packed.size() + 3) & ~size_t(3), 0);
    Json view = views[members[0]];
    const uint64_t start = packed.size();
    for (const size_t v : members) {
      const uint64_t offset = views[v].value("byteOffset", uint64_t(0)), length = views[v]["byteLength"].get<uint64_t>();
      moved[v] = packed.size() - start;
      packed.insert(packed.end(), bin.begin() + ptrdiff_t(offset), bin.begin() + ptrdiff_t(offset + length));
    }
    view["byteOffset"] = start;
    view["byteLength"] = packed.size() - start;
    // A view several vertex attributes share must give its stride (glTF).
    if (members.size() > 1 && (kind[members[0]].starts_with("attribute ") || kind[members[0]].starts_with("target ")))
      view["byteStride"] = use[members[0]].stride;
    merged.push_back(std::move(view));
  }
  for (Json& accessor : accessors)
    if (accessor.contains("bufferView")) {
      const size_t v = accessor["bufferView"].get<size_t>();
      if (moved[v]) accessor["byteOffset"] = accessor.value("byteOffset", uint64_t(0)) + moved[v];
    }
  for (auto& [key, value] : doc.items())
    if (key != "bufferViews") for_each_view_reference(value, [&](Json& index) { index = group[index.get<size_t>()]; });
  views = std::move(merged);
  bin = std::move(packed);
  doc["buffers"][0]["byteLength"] = bin.size();
}

// The octahedral filter's input for view v (`count` elements of `stride` bytes): 4 floats per
// element, from `directions` for the elements of accessors found there, NaN for the others (which
// encode_view reads from the stored integers); empty when no accessor of the view is found there.
std::vector<float> direction_input(const Json& doc, size_t v, uint64_t count, uint64_t stride, const DirectionFloats& directions) {
  std::vector<float> out;
  if (directions.empty()) return out;
  const Json& accessors = doc["accessors"];
  for (const auto& [index, floats] : directions) {
    if (index >= accessors.size()) continue;
    const Json& accessor = accessors[index];
    if (accessor.value("bufferView", uint64_t(-1)) != v) continue;
    const uint64_t offset = accessor.value("byteOffset", uint64_t(0)), n = accessor.value("count", uint64_t(0));
    if (offset % stride != 0 || offset / stride + n > count || floats.size() != 4 * n) continue;  // (never, as written)
    if (out.empty()) out.assign(4 * count, std::numeric_limits<float>::quiet_NaN());
    std::copy(floats.begin(), floats.end(), out.begin() + ptrdiff_t(4 * (offset / stride)));
  }
  return out;
}

}  // namespace

void compress_meshopt(Json& doc, std::vector<uint8_t>& bin, const WriteOptions& options, const DirectionFloats& directions) {
  const bool khr = options.meshopt_khr;
  const char* const extension = meshopt_names[khr ? 1 : 0];
  if (bin.empty() || !doc.contains("bufferViews") || doc["buffers"].size() != 1) return;
  Json& views = doc["bufferViews"];
  std::vector<ViewUse> use = view_uses(doc);
  // Under -q (lossy already), views of translation and scale keys only go through the exponential
  // filter, as gltfpack -c does: 16-bit mantissas, one exponent per key; views of rotation keys only
  // through the quaternion filter (gltfpack -c leaves them plain: it codes them in 61% of the
  // bytes, a baked character's file 9% smaller).
  // With compress_more, views of normals and tangents through the octahedral filter: bytes in 8 bits,
  // shorts (-q's above 8 normal bits) in normal_bits.
  const auto filter = [&](size_t v) {
    const ViewUse& u = use[v];
    if (!options.quantize || u.other || int(u.keys) + int(u.rotations) + int(u.directions) != 1) return ViewFilter::none;
    if (u.keys && u.stride == 12) return ViewFilter::exponential;
    if (u.rotations && u.stride == 8) return ViewFilter::quaternion;
    const bool bytes = u.direction_bytes == 1 && u.stride == 4, shorts = u.direction_bytes == 2 && u.stride == 8 && options.normal_bits > 8;
    if (u.directions && (bytes || shorts) && options.compress_more) return ViewFilter::octahedral;
    return ViewFilter::none;
  };
  std::vector<ViewFilter> filters(views.size());
  for (size_t v = 0; v < views.size(); ++v) filters[v] = filter(v);
  merge_views(doc, bin, use, filters);
  use = view_uses(doc);
  std::vector<std::vector<uint8_t>> encoded(views.size());
  bool any = false;
  std::vector<float> given;
  for (size_t v = 0; v < views.size(); ++v) {
    const ViewUse& u = use[v];
    const uint64_t length = views[v]["byteLength"].get<uint64_t>();
    if (u.excluded || u.stride == 0 || (u.indices && u.attributes) || length % u.stride != 0) continue;
    given.clear();
    if (filter(v) == ViewFilter::octahedral) given = direction_input(doc, v, length / u.stride, u.stride, directions);
    encoded[v] = encode_view(bin.data() + views[v].value("byteOffset", uint64_t(0)), length, u, khr, filter(v), options.normal_bits, given);
    any = any || !encoded[v].empty();
  }
  if (!any) return;
  // Buffer 0 (the GLB's BIN chunk, or the .bin) holds the compressed views and the plain ones, in
  // view order; buffer 1 is the fallback, where the compressed views keep a place.
  const auto align = [](uint64_t n) { return (n + 3) & ~uint64_t(3); };
  std::vector<uint8_t> packed;
  uint64_t fallback = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    Json& view = views[v];
    const uint64_t length = view["byteLength"].get<uint64_t>();
    packed.resize(align(packed.size()), 0);
    if (encoded[v].empty()) {
      const uint8_t* data = bin.data() + view.value("byteOffset", uint64_t(0));
      view["byteOffset"] = packed.size();
      packed.insert(packed.end(), data, data + length);
      continue;
    }
    const uint64_t stride = use[v].stride;
    view["extensions"][extension] = {{"buffer", 0},
                                     {"byteOffset", packed.size()},
                                     {"byteLength", encoded[v].size()},
                                     {"byteStride", stride},
                                     {"count", length / stride},
                                     {"mode", use[v].indices ? "TRIANGLES" : "ATTRIBUTES"}};
    if (const ViewFilter f = filter(v); f != ViewFilter::none)
      view["extensions"][extension]["filter"] = f == ViewFilter::exponential ? "EXPONENTIAL" : f == ViewFilter::quaternion ? "QUATERNION" : "OCTAHEDRAL";
    packed.insert(packed.end(), encoded[v].begin(), encoded[v].end());
    fallback = align(fallback);
    view["buffer"] = 1;
    view["byteOffset"] = fallback;
    fallback += length;
  }
  bin = std::move(packed);
  doc["buffers"][0]["byteLength"] = bin.size();
  doc["buffers"].push_back({{"byteLength", fallback}, {"extensions", {{extension, {{"fallback", true}}}}}});
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    Json& names = doc[list];
    if (!names.is_array()) names = Json::array();
    if (std::find(names.begin(), names.end(), extension) == names.end()) names.push_back(extension);
  }
}

std::optional<DracoPrimitive> encode_draco(const Mesh& mesh, const DracoBits& bits, bool track_points,
                                           std::span<const uint16_t> grid_positions) {
  const size_t n = mesh.vertex_count(), faces = mesh.triangle_count();
  draco::Mesh dm;
  dm.set_num_points(uint32_t(n));
  dm.SetNumFaces(faces);
  for (size_t f = 0; f < faces; ++f) {
    draco::Mesh::Face face;
    for (size_t c = 0; c < 3; ++c) face[c] = draco::PointIndex(mesh.indices[3 * f + c]);
    dm.SetFace(draco::FaceIndex(uint32_t(f)), face);
  }
  DracoPrimitive out;
  // Each stream as a Draco attribute of the n points (identity mapping), described for its glTF
  // accessor. Float streams are quantized to `bits` where Draco can: it quantizes over the largest
  // per-component range, which must be a finite float (libdraco 1.5.5 crashes on a stream spanning
  // more, coordinates near +-3e38), so such a stream is stored exactly instead.
  std::vector<std::pair<int, int>> quantized;  // (Draco attribute id, bits)
  const auto add = [&](const std::string& semantic, draco::GeometryAttribute::Type kind, int gltf_type, int components,
                       const auto* values, int quantization_bits) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(values)>>;
    constexpr bool is_float = std::is_same_v<T, float>;
    draco::GeometryAttribute attribute;
    attribute.Init(kind, nullptr, uint8_t(components),
                   is_float ? draco::DT_FLOAT32 : sizeof(T) == 1 ? draco::DT_UINT8 : draco::DT_UINT16, false,
                   int64_t(sizeof(T)) * components, 0);
    const int id = dm.AddAttribute(attribute, true, uint32_t(n));
    if (id < 0) throw_internal("Draco: could not add an attribute");
    draco::PointAttribute* a = dm.attribute(id);
    for (size_t i = 0; i < n; ++i) a->SetAttributeValue(draco::AttributeValueIndex(uint32_t(i)), values + i * size_t(components));
    const int component_type = is_float         ? TINYGLTF_COMPONENT_TYPE_FLOAT
                               : sizeof(T) == 1 ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE
                                                : TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    out.attributes[semantic] = {a->unique_id(), component_type, gltf_type};
    if constexpr (is_float) {
      bool finite_range = true;
      for (int c = 0; c < components; ++c) {
        float lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < n; ++i) lo = std::min(lo, values[i * size_t(components) + size_t(c)]), hi = std::max(hi, values[i * size_t(components) + size_t(c)]);
        finite_range = finite_range && std::isfinite(hi - lo);
      }
      if (finite_range) quantized.emplace_back(id, quantization_bits);
    }
  };
  using GA = draco::GeometryAttribute;
  const auto floats = [](const auto& v) { return reinterpret_cast<const float*>(v.data()); };
  if (!grid_positions.empty()) {
    if (grid_positions.size() != 3 * n) throw_internal("Draco: grid positions for another vertex count");
    add("POSITION", GA::POSITION, TINYGLTF_TYPE_VEC3, 3, grid_positions.data(), 0);  // (integers: exact)
  } else {
    add("POSITION", GA::POSITION, TINYGLTF_TYPE_VEC3, 3, floats(mesh.positions), bits.position);
  }
  if (!mesh.normals.empty()) add("NORMAL", GA::NORMAL, TINYGLTF_TYPE_VEC3, 3, floats(mesh.normals), bits.normal);
  if (!mesh.tangents.empty()) add("TANGENT", GA::GENERIC, TINYGLTF_TYPE_VEC4, 4, floats(mesh.tangents), 12);
  for (size_t k = 0; k < max_uv_sets; ++k)
    if (!mesh.uvs[k].empty()) add("TEXCOORD_" + std::to_string(k), GA::TEX_COORD, TINYGLTF_TYPE_VEC2, 2, floats(mesh.uvs[k]), bits.uv);
  if (!mesh.colors.empty()) add("COLOR_0", GA::COLOR, TINYGLTF_TYPE_VEC4, 4, floats(mesh.colors), 8);
  const bool byte_joints = joints_fit_bytes(mesh);
  const std::vector<ushort4>* joints[2] = {&mesh.joints, &mesh.joints1};
  const std::vector<float4>* weights[2] = {&mesh.weights, &mesh.weights1};
  for (size_t set = 0; set < 2; ++set) {
    const std::string suffix = set == 0 ? "_0" : "_1";
    if (!joints[set]->empty()) {  // (integers: exact)
      if (byte_joints) {
        std::vector<uint8_t> narrow(4 * n);
        for (size_t v = 0; v < n; ++v)
          for (size_t k = 0; k < 4; ++k) narrow[4 * v + k] = uint8_t((*joints[set])[v][k]);
        add("JOINTS" + suffix, GA::GENERIC, TINYGLTF_TYPE_VEC4, 4, narrow.data(), 0);
      } else {
        add("JOINTS" + suffix, GA::GENERIC, TINYGLTF_TYPE_VEC4, 4, reinterpret_cast<const uint16_t*>(joints[set]->data()), 0);
      }
    }
    if (!weights[set]->empty()) add("WEIGHTS" + suffix, GA::GENERIC, TINYGLTF_TYPE_VEC4, 4, floats(*weights[set]), 12);
  }

  // One encoding and its stream decoded again: what a loader will see.
  struct Encoded {
    std::vector<uint8_t> bytes;
    std::unique_ptr<draco::Mesh> back;
  };
  const auto encode = [&](bool sequential, bool quantize) -> std::optional<Encoded> {
    draco::ExpertEncoder encoder(dm);
    if (quantize)
      for (const auto& [id, attribute_bits] : quantized) encoder.SetAttributeQuantization(id, attribute_bits);
    // Draco's own default, compression level 7 (draco_encoder, draco_transcoder): 7-9% smaller
    // than level 5 on the bench's meshes, 20% on the skinned humanoid.
    encoder.SetSpeedOptions(3, 3);
    encoder.SetEncodingMethod(sequential ? draco::MESH_SEQUENTIAL_ENCODING : draco::MESH_EDGEBREAKER_ENCODING);
    draco::EncoderBuffer buffer;
    if (!encoder.EncodeToBuffer(&buffer).ok()) return std::nullopt;
    draco::DecoderBuffer input;
    input.Init(buffer.data(), buffer.size());
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&input);
    if (!decoded.ok()) return std::nullopt;
    Encoded e{std::vector<uint8_t>(buffer.data(), buffer.data() + buffer.size()), std::move(decoded).value()};
    if (sequential && (e.back->num_points() != n || e.back->num_faces() != faces)) return std::nullopt;  // (it must keep both in place)
    return e;
  };
  // Edgebreaker's numbering of the points, for `track_points`. A first encoding carries each
  // vertex's index as one more, exact, stream; it changes libdraco's traversal, so the stream
  // written (encoded again without it) is matched to it by the points' decoded values, which do
  // not depend on the traversal. Two input vertices that decode to the same values cannot be told
  // apart: the caller then gets sequential encoding.
  const auto encode_tracked = [&]() -> std::optional<Encoded> {
    draco::GeometryAttribute index;
    index.Init(draco::GeometryAttribute::GENERIC, nullptr, 1, draco::DT_UINT32, false, 4, 0);
    const int id = dm.AddAttribute(index, true, uint32_t(n));
    if (id < 0) return std::nullopt;
    const uint32_t unique = dm.attribute(id)->unique_id();
    for (uint32_t v = 0; v < n; ++v) dm.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(v), &v);
    std::optional<Encoded> with = encode(false, true);
    dm.DeleteAttribute(id);  // (the last one: the others keep their ids)
    if (!with) return std::nullopt;
    std::optional<Encoded> without = encode(false, true);
    if (!without) return std::nullopt;
    const draco::PointAttribute* sources = with->back->GetAttributeByUniqueId(unique);
    if (!sources) return std::nullopt;
    // A point's key: its decoded values, every stream of the written encoding in turn.
    const auto key = [](const std::vector<const draco::PointAttribute*>& streams, uint32_t p) {
      std::string k;
      for (const draco::PointAttribute* a : streams)
        k.append(reinterpret_cast<const char*>(a->GetAddress(a->mapped_index(draco::PointIndex(p)))), size_t(a->byte_stride()));
      return k;
    };
    std::vector<const draco::PointAttribute*> mine, theirs;
    for (int32_t k = 0; k < without->back->num_attributes(); ++k) {
      mine.push_back(without->back->attribute(k));
      theirs.push_back(with->back->GetAttributeByUniqueId(mine.back()->unique_id()));
      if (!theirs.back() || theirs.back()->byte_stride() != mine.back()->byte_stride()) return std::nullopt;
    }
    constexpr uint32_t ambiguous = UINT32_MAX;
    std::unordered_map<std::string, uint32_t> source_of;
    source_of.reserve(with->back->num_points());
    for (uint32_t p = 0; p < with->back->num_points(); ++p) {
      uint32_t v = 0;
      sources->GetValue(sources->mapped_index(draco::PointIndex(p)), &v);
      if (v >= n) return std::nullopt;
      const auto [it, added] = source_of.emplace(key(theirs, p), v);
      if (!added && it->second != v) it->second = ambiguous;
    }
    const uint32_t points = without->back->num_points();
    std::vector<uint32_t> source(points);
    for (uint32_t p = 0; p < points; ++p) {
      const auto it = source_of.find(key(mine, p));
      if (it == source_of.end() || it->second == ambiguous) return std::nullopt;
      source[p] = it->second;
    }
    bool identity = points == n;
    for (uint32_t p = 0; identity && p < points; ++p) identity = source[p] == p;
    if (!identity) out.point_source = std::move(source);
    return without;
  };

  // libdraco 1.5.5 does not take every mesh it is given: Edgebreaker refuses one whose triangles all
  // repeat a corner, and a stream it writes of a triangle with three equal corners does not decode
  // (both found by fuzz_gltf). Each stream is decoded again, and a failure falls back to sequential
  // encoding, then to sequential encoding without quantization; if none decodes, the caller writes
  // the primitive plain.
  std::optional<Encoded> chosen = track_points ? encode_tracked() : encode(false, true);
  if (!chosen) out.point_source.clear(), out.sequential = true, chosen = encode(true, true);
  if (!chosen) chosen = encode(true, false);
  if (!chosen) return std::nullopt;
  out.bytes = std::move(chosen->bytes);
  const std::unique_ptr<draco::Mesh>& back = chosen->back;
  out.points = back->num_points(), out.triangles = back->num_faces();
  const draco::PointAttribute* position = back->GetAttributeByUniqueId(out.attributes["POSITION"].unique_id);
  if (!position) throw_internal("Draco: the decoded stream has no positions");
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t i = 0; i < out.points; ++i) {
    float p[3];
    position->ConvertValue<float>(position->mapped_index(draco::PointIndex(i)), 3, p);
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], p[c]), hi[c] = std::max(hi[c], p[c]);
  }
  out.position_min = {lo[0], lo[1], lo[2]}, out.position_max = {hi[0], hi[1], hi[2]};
  return out;
}

}  // namespace lod::io
