// glTF 2.0 (.gltf + .bin / data: URIs, and .glb).
//
// tinygltf parses and serializes the document; lodkit does everything that touches bytes itself:
// the GLB container, every bufferView / accessor / sparse range (checked before any decoding or
// allocation), and the geometry it regenerates on write. Writing starts from the source document,
// so materials, textures, images, nodes, cameras, skins and animations pass through; only the
// triangle primitives' attributes and indices are replaced, and the buffer is repacked from the
// bufferViews something still references plus the new geometry.
//
// tinygltf 2.7 pitfalls handled here:
//  - it decodes images with stb_image on read and re-encodes them on write (and rewrites external
//    URIs to their bare file name): an image loader keeps the encoded bytes untouched, and an image
//    writer keeps external URIs verbatim and writes data: URIs back from the original bytes;
//  - it hands an image's bufferView to the image loader without checking the view lies inside its
//    buffer (heap over-read), and converts extras/extensions recursively (a deeply nested JSON
//    overflows the stack): both are checked on the raw JSON before tinygltf sees it;
//  - it looks for external files in "." as well as the base dir: file callbacks keep it in base_dir.
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "core/quaternion.h"
#include "core/vec3d.h"
#include "io/gltf_compression.h"
#include "io/gltf_types.h"
#include "io/scene_world.h"
#include "io/text_reader.h"
#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

// The parsed source document. Encoded images from data: URIs are kept in Image::image (as_is);
// images in bufferViews stay in the buffers, which are kept whole.
struct GltfSource {
  tinygltf::Model model;
  std::filesystem::path base_dir;  // where its external files are (relative URIs resolve here)
};

namespace {

namespace tg = tinygltf;
using Json = nlohmann::json;

constexpr uint32_t glb_magic = 0x46546C67;       // "glTF"
constexpr uint32_t glb_chunk_json = 0x4E4F534A;  // "JSON"
constexpr uint32_t glb_chunk_bin = 0x004E4942;   // "BIN\0"
// tinygltf converts extras/extensions recursively; real files nest a handful of levels.
constexpr size_t max_json_depth = 64;
// An accessor without a bufferView reads as zeros: cap it so a tiny file cannot ask for gigabytes.
constexpr uint64_t max_zero_accessor_count = uint64_t(1) << 24;

std::string str(uint64_t value) { return std::to_string(value); }
using io::component_bytes;
using io::type_components;
using io::type_name;

constexpr const char* gpu_instancing = "EXT_mesh_gpu_instancing";
constexpr const char* node_visibility = "KHR_node_visibility";

// tinygltf::Value -> nlohmann::json (a node's extras, read into Node::extras_json). tinygltf has
// already dropped nulls and empty objects and arrays; binary values do not occur in JSON.
Json value_to_json(const tg::Value& v) {
  switch (v.Type()) {
    case tg::OBJECT_TYPE: {
      Json object = Json::object();
      for (const auto& [key, value] : v.Get<tg::Value::Object>()) object[key] = value_to_json(value);
      return object;
    }
    case tg::ARRAY_TYPE: {
      Json array = Json::array();
      for (const tg::Value& value : v.Get<tg::Value::Array>()) array.push_back(value_to_json(value));
      return array;
    }
    case tg::STRING_TYPE: return v.Get<std::string>();
    case tg::BOOL_TYPE: return v.Get<bool>();
    case tg::INT_TYPE: return v.Get<int>();
    case tg::REAL_TYPE: return v.Get<double>();
    default: return nullptr;
  }
}

// Declares `ext` in `list` (extensionsUsed or extensionsRequired) once.
void declare_extension(std::vector<std::string>& list, const std::string& ext) {
  if (std::find(list.begin(), list.end(), ext) == list.end()) list.push_back(ext);
}

// Extensions lodkit knows: it reads and writes them (compression, quantization, MSFT_lod,
// instancing, visibility, texture transforms, animation pointers), or they concern only materials,
// textures, lights or metadata, so a changed mesh still agrees with them. None refers to a node by
// index in a way erase_nodes would break (it renumbers MSFT_lod and KHR_animation_pointer's).
bool known_extension(const std::string& ext) {
  static const std::set<std::string> known = {
      "EXT_mesh_gpu_instancing", "EXT_meshopt_compression", "EXT_texture_avif", "EXT_texture_webp",
      "KHR_animation_pointer", "KHR_draco_mesh_compression", "KHR_lights_punctual", "KHR_mesh_quantization",
      "KHR_meshopt_compression", "KHR_node_visibility", "KHR_texture_basisu", "KHR_texture_transform",
      "KHR_xmp_json_ld", "MSFT_lod", "MSFT_texture_dds"};
  return known.count(ext) > 0 || ext.starts_with("KHR_materials_");
}

// The MSFT_lod extension of a node: its ids array (null when the node has none, or an empty one).
const tg::Value& msft_lod_ids(const tg::Node& node) {
  static const tg::Value none;
  const auto lod = node.extensions.find("MSFT_lod");
  return lod != node.extensions.end() && lod->second.IsObject() ? lod->second.Get("ids") : none;
}

// ---- KHR_animation_pointer -----------------------------------------------------------------------

constexpr const char* animation_pointer = "KHR_animation_pointer";

// A JSON pointer "/<list>/<index>/<rest>" split; index -1 when the pointer does not start with an
// index into that list (RFC 6901: an array index has no leading zero).
struct PointerTarget {
  int index = -1;
  std::string_view rest;
};
PointerTarget split_pointer(std::string_view pointer, std::string_view list) {
  if (pointer.size() < list.size() + 2 || pointer[0] != '/' || pointer.substr(1, list.size()) != list ||
      pointer[list.size() + 1] != '/')
    return {};
  pointer.remove_prefix(list.size() + 2);
  const size_t digits = pointer.find('/');
  if (digits == 0 || digits == std::string_view::npos || digits > 9 || (pointer[0] == '0' && digits > 1)) return {};
  int index = 0;
  for (size_t i = 0; i < digits; ++i) {
    if (pointer[i] < '0' || pointer[i] > '9') return {};
    index = index * 10 + (pointer[i] - '0');
  }
  return {index, pointer.substr(digits + 1)};
}

// A channel's KHR_animation_pointer pointer ("" when it has none).
std::string channel_pointer(const tg::AnimationChannel& ch) {
  const auto ext = ch.target_extensions.find(animation_pointer);
  if (ext == ch.target_extensions.end() || !ext->second.IsObject()) return {};
  const tg::Value& pointer = ext->second.Get("pointer");
  return pointer.IsString() ? pointer.Get<std::string>() : std::string();
}

// What a channel animates in a node or a mesh: `list` "nodes" or "meshes", the index (-1 when
// neither) and the property. A core channel's node and path, or a KHR_animation_pointer's
// "/nodes/N/<property>" (one the reader left a pointer: its output is not what the core allows
// there) or "/meshes/M/weights".
struct ChannelTarget {
  std::string_view list;
  int index = -1;
  std::string property;
};
ChannelTarget channel_target(const tg::AnimationChannel& ch) {
  if (ch.target_node >= 0) return {"nodes", ch.target_node, ch.target_path};
  const std::string pointer = channel_pointer(ch);
  for (const std::string_view list : {"nodes", "meshes"})
    if (const PointerTarget t = split_pointer(pointer, list); t.index >= 0) return {list, t.index, std::string(t.rest)};
  return {};
}
// Whether a channel switches a node's KHR_node_visibility (a KHR_animation_pointer to
// "/nodes/N/extensions/KHR_node_visibility/...").
bool switches_visibility(const ChannelTarget& t) {
  return t.list == "nodes" && t.property.starts_with(std::string("extensions/") + node_visibility + "/");
}
// Points a channel at another node or mesh (`list` as channel_target gave), the property kept.
void retarget_channel(tg::AnimationChannel& ch, std::string_view list, int index) {
  if (ch.target_node >= 0) {
    ch.target_node = index;
    return;
  }
  const std::string pointer = "/" + std::string(list) + "/" + str(uint64_t(index)) + "/" + channel_target(ch).property;
  ch.target_extensions[animation_pointer].Get<tg::Value::Object>()["pointer"] = tg::Value(pointer);
}

// A node channel's glTF path, and the accessor type its keys take.
const char* path_name(AnimationPath path) {
  constexpr const char* names[] = {"translation", "rotation", "scale", "weights"};  // (AnimationPath's order)
  return names[int(path)];
}
int path_output_type(AnimationPath path) {
  return path == AnimationPath::rotation ? TINYGLTF_TYPE_VEC4 : path == AnimationPath::weights ? TINYGLTF_TYPE_SCALAR : TINYGLTF_TYPE_VEC3;
}

// tinygltf 2.7 drops a channel whose target has no node: KHR_animation_pointer's, and a core one
// left to an extension. A pointer to a node's translation, rotation, scale or weights is the same
// animation as a core channel (the extension's README gives the pair) and becomes one, so the grid,
// -q and the morph weights treat it as they treat node channels; its output must be what the core
// allows there. Any other such channel gets node -1, a stand-in the writer leaves out again, and
// passes through. Returns whether the document changed.
bool prepare_animation_targets(Json& doc) {
  const auto list = [&](const Json& object, const char* key) -> const Json* {
    return object.is_object() && object.contains(key) && object[key].is_array() ? &object[key] : nullptr;
  };
  const Json* animations = list(doc, "animations");
  if (!animations) return false;
  const Json *nodes = list(doc, "nodes"), *accessors = list(doc, "accessors");
  // The output accessor of channel `ch` of `anim` holds what the core path wants.
  const auto output_fits = [&](const Json& anim, const Json& ch, const std::string& path) {
    const Json* samplers = list(anim, "samplers");
    if (!samplers || !accessors || !ch.contains("sampler") || !ch["sampler"].is_number_unsigned()) return false;
    const size_t s = ch["sampler"].get<size_t>();
    if (s >= samplers->size() || !(*samplers)[s].is_object()) return false;
    const Json& sampler = (*samplers)[s];
    if (!sampler.contains("output") || !sampler["output"].is_number_unsigned()) return false;
    const size_t a = sampler["output"].get<size_t>();
    if (a >= accessors->size() || !(*accessors)[a].is_object()) return false;
    const Json& accessor = (*accessors)[a];
    const std::string type = path == "rotation" ? "VEC4" : path == "weights" ? "SCALAR" : "VEC3";
    if (!accessor.contains("type") || accessor["type"] != type || !accessor.contains("componentType")) return false;
    const Json& component = accessor["componentType"];
    if (component == TINYGLTF_COMPONENT_TYPE_FLOAT) return true;
    const bool normalized = accessor.contains("normalized") && accessor["normalized"] == true;
    return normalized && (path == "rotation" || path == "weights") &&
           (component == TINYGLTF_COMPONENT_TYPE_BYTE || component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
            component == TINYGLTF_COMPONENT_TYPE_SHORT || component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  };
  bool changed = false;
  for (Json& anim : doc["animations"]) {
    if (!list(anim, "channels")) continue;
    for (Json& ch : anim["channels"]) {
      if (!ch.is_object() || !ch.contains("target") || !ch["target"].is_object() || ch["target"].contains("node")) continue;
      Json& target = ch["target"];
      target["node"] = -1;
      changed = true;
      if (!target.contains("path") || target["path"] != "pointer" || !target.contains("extensions") ||
          !target["extensions"].is_object() || !target["extensions"].contains(animation_pointer))
        continue;
      const Json& ext = target["extensions"][animation_pointer];
      if (!ext.is_object() || !ext.contains("pointer") || !ext["pointer"].is_string()) continue;
      const std::string pointer = ext["pointer"].get<std::string>();
      const PointerTarget t = split_pointer(pointer, "nodes");
      const std::string path(t.rest);
      if (t.index < 0 || !nodes || size_t(t.index) >= nodes->size() ||
          (path != "translation" && path != "rotation" && path != "scale" && path != "weights") || !output_fits(anim, ch, path))
        continue;
      target["node"] = t.index;
      target["path"] = path;
      target["extensions"].erase(animation_pointer);
      if (target["extensions"].empty()) target.erase("extensions");
    }
  }
  return changed;
}

// ---- accessor layout -----------------------------------------------------------------------------

// Calls f with a value of the C++ type a glTF component type stores (float for FLOAT, and for any
// other code: the readers have refused those by then).
template <class F>
decltype(auto) with_component_type(int component_type, F&& f) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return f(int8_t{});
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return f(uint8_t{});
    case TINYGLTF_COMPONENT_TYPE_SHORT: return f(int16_t{});
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return f(uint16_t{});
    case TINYGLTF_COMPONENT_TYPE_INT: return f(int32_t{});
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return f(uint32_t{});
    default: return f(float{});
  }
}

// One component's value as stored (integers not normalized: accessor bounds are in stored units).
double component_value(const uint8_t* p, int component_type) {
  return with_component_type(component_type, [p](auto v) {
    std::memcpy(&v, p, sizeof v);
    return double(v);
  });
}

// A component's value as a reader sees it: integers divided out when normalized (glTF's rule:
// signed ones clamped at -1), else as stored.
template <class T>
float component_to_float(T v, bool normalized) {
  if constexpr (std::is_same_v<T, float>) {
    return v;
  } else {
    if (!normalized) return float(v);
    if constexpr (std::is_same_v<T, int8_t>) return std::max(float(v) / 127.0f, -1.0f);
    if constexpr (std::is_same_v<T, uint8_t>) return float(v) / 255.0f;
    if constexpr (std::is_same_v<T, int16_t>) return std::max(float(v) / 32767.0f, -1.0f);
    if constexpr (std::is_same_v<T, uint16_t>) return float(v) / 65535.0f;
    return float(v);  // 32-bit integers are never normalized in glTF
  }
}
float component_float(const uint8_t* p, int component_type, bool normalized) {
  return with_component_type(component_type, [&](auto v) {
    std::memcpy(&v, p, sizeof v);
    return component_to_float(v, normalized);
  });
}

// Stores a value in one component, rounded and clamped to an integer type's range.
void store_component(double value, uint8_t* p, int component_type) {
  with_component_type(component_type, [&](auto v) {
    using T = decltype(v);
    if constexpr (std::is_floating_point_v<T>) {
      v = T(value);
    } else {
      const double lo = double(std::numeric_limits<T>::min()), hi = double(std::numeric_limits<T>::max());
      v = T(std::clamp(std::round(value), lo, hi));
    }
    std::memcpy(p, &v, sizeof v);
  });
}

// Matrix columns start on 4-byte boundaries, which pads 1- and 2-byte MAT2/MAT3 elements.
size_t element_bytes(int component_type, int type) {
  const size_t c = component_bytes(component_type);
  if (type == TINYGLTF_TYPE_MAT2 && c == 1) return 8;
  if (type == TINYGLTF_TYPE_MAT3 && c == 1) return 12;
  if (type == TINYGLTF_TYPE_MAT3 && c == 2) return 24;
  return c * type_components(type);
}

// ---- the raw JSON checks that must happen before tinygltf parses ---------------------------------

void check_json_depth(std::span<const uint8_t> text, const std::string& name, size_t base_offset) {
  size_t depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const uint8_t c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_json_depth)
        throw_bad_input_at_byte(name, base_offset + i,
                                "JSON nested deeper than " + str(max_json_depth) + " levels");
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
}

class JsonChecker {
 public:
  JsonChecker(const Json& doc, const std::string& name) : doc_(doc), name_(name) {}

  void run() {
    if (!doc_.is_object()) fail("the JSON root is not an object");
    const Json* meshes = array("meshes");
    for (size_t m = 0; meshes && m < meshes->size(); ++m) {
      const Json& mesh = (*meshes)[m];
      if (!mesh.is_object()) fail("meshes[" + str(m) + "] is not an object");
      auto primitives = mesh.find("primitives");
      if (primitives == mesh.end() || !primitives->is_array() || primitives->empty())
        fail("meshes[" + str(m) + "] has no primitives");
      // tinygltf silently drops a primitive without attributes, which would shift every index after it.
      for (size_t p = 0; p < primitives->size(); ++p) {
        const Json& primitive = (*primitives)[p];
        const std::string where = "meshes[" + str(m) + "].primitives[" + str(p) + "]";
        auto attributes = primitive.is_object() ? primitive.find("attributes") : primitive.end();
        if (!primitive.is_object() || attributes == primitive.end() || !attributes->is_object())
          fail(where + " has no attributes object");
        // tinygltf checks the indices accessor itself, but names neither it nor the primitive. (Its
        // bufferView may be absent: Draco's accessors have none.)
        if (auto indices = primitive.find("indices"); indices != primitive.end())
          element(array("accessors"), *indices, where + ".indices", "accessors");
      }
    }
    check_extension_integers();
    check_data_uris();
    // tinygltf passes &buffer.data[view.byteOffset] with view.byteLength to the image loader unchecked.
    const Json* images = array("images");
    for (size_t i = 0; images && i < images->size(); ++i) {
      const Json& image = (*images)[i];
      if (!image.is_object()) continue;  // tinygltf reports it
      auto view_ref = image.find("bufferView");
      if (view_ref == image.end()) continue;
      const std::string where = "images[" + str(i) + "]";
      const Json* views = array("bufferViews");
      const Json& view = element(views, *view_ref, where + ".bufferView", "bufferViews");
      const std::string view_where = "bufferViews[" + view_ref->dump() + "]";
      const Json* buffers = array("buffers");
      const Json& buffer = element(buffers, member(view, "buffer", view_where), view_where + ".buffer", "buffers");
      const uint64_t offset = view.contains("byteOffset") ? unsigned_value(view["byteOffset"], view_where + ".byteOffset") : 0;
      const uint64_t length = unsigned_value(member(view, "byteLength", view_where), view_where + ".byteLength");
      const uint64_t buffer_length = unsigned_value(member(buffer, "byteLength", "buffers"), "buffers[].byteLength");
      if (length == 0) fail(where + " uses the empty " + view_where);
      if (offset > buffer_length || length > buffer_length - offset)
        fail(view_where + " (bytes " + str(offset) + ".." + str(offset + length) + ") runs past the end of its buffer (" +
             str(buffer_length) + " bytes)");
    }
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw_bad_input(name_, what); }
  const Json* array(const char* key) const {
    auto it = doc_.find(key);
    if (it == doc_.end()) return nullptr;
    if (!it->is_array()) fail(std::string("'") + key + "' is not an array");
    return &*it;
  }
  const Json& member(const Json& object, const char* key, const std::string& where) const {
    auto it = object.find(key);
    if (it == object.end()) fail(where + " has no '" + key + "'");
    return *it;
  }
  uint64_t unsigned_value(const Json& value, const std::string& where) const {
    if (!value.is_number_unsigned()) fail(where + " is not a non-negative integer");
    return value.get<uint64_t>();
  }
  const Json& element(const Json* list, const Json& index, const std::string& where, const char* list_name) const {
    const uint64_t i = unsigned_value(index, where);
    if (!list || i >= list->size()) fail(where + " refers to " + list_name + "[" + str(i) + "], which does not exist");
    const Json& e = (*list)[i];
    if (!e.is_object()) fail(std::string(list_name) + "[" + str(i) + "] is not an object");
    return e;
  }

  // A buffer's base64 data: URI must hold its byteLength (tinygltf's message names neither).
  void check_data_uris() const {
    const Json* buffers = array("buffers");
    for (size_t b = 0; buffers && b < buffers->size(); ++b) {
      const Json& buffer = (*buffers)[b];
      if (!buffer.is_object()) continue;  // tinygltf reports it
      auto uri = buffer.find("uri"), length = buffer.find("byteLength");
      if (uri == buffer.end() || !uri->is_string() || length == buffer.end() || !length->is_number_unsigned()) continue;
      const std::string& text = uri->get_ref<const std::string&>();
      const size_t comma = text.find(',');
      if (text.rfind("data:", 0) != 0 || comma == std::string::npos || text.rfind(";base64", comma) == std::string::npos)
        continue;
      // Decoded bytes: 3 per 4 characters, less the padding.
      size_t chars = text.size() - comma - 1, pad = 0;
      while (pad < 2 && chars > pad && text[text.size() - 1 - pad] == '=') ++pad;
      const uint64_t holds = chars / 4 * 3 + (chars % 4 ? chars % 4 - 1 : 0) - (chars % 4 ? 0 : pad);
      if (holds < length->get<uint64_t>())
        fail("buffers[" + str(b) + "]: its data: URI holds " + str(holds) + " bytes, fewer than its byteLength (" +
             length->dump() + ")");
    }
  }

  // tinygltf 2.7 keeps an extension's integers as int, wrapping larger ones (2^32 + 5 reads as 5):
  // the ones lodkit follows are checked here (meshopt and Draco compression, GPU instancing).
  void check_extension_integers() const {
    const auto check = [&](const Json& object, const std::string& key, const std::string& where) {
      auto it = object.find(key);
      if (it == object.end()) return;
      if (!it->is_number_unsigned() || it->get<uint64_t>() > uint64_t(std::numeric_limits<int>::max()))
        fail(where + "." + key + " is " + it->dump() + ", not an integer in 0.." + std::to_string(std::numeric_limits<int>::max()));
    };
    // The object of extension `name` on a JSON element, or nullptr.
    const auto extension = [&](const Json& element, const char* name) -> const Json* {
      auto extensions = element.is_object() ? element.find("extensions") : element.end();
      if (extensions == element.end() || !extensions->is_object()) return nullptr;
      auto ext = extensions->find(name);
      return ext != extensions->end() && ext->is_object() ? &*ext : nullptr;
    };
    const auto each_key = [&](const Json& ext, const char* member, const std::string& where) {
      auto object = ext.find(member);
      if (object == ext.end() || !object->is_object()) return;
      for (auto it = object->begin(); it != object->end(); ++it) check(*object, it.key(), where + "." + member);
    };
    if (const Json* views = array("bufferViews"))
      for (size_t v = 0; v < views->size(); ++v)
        for (const char* name : {"EXT_meshopt_compression", "KHR_meshopt_compression"})
          if (const Json* ext = extension((*views)[v], name))
            for (const char* key : {"buffer", "byteOffset", "byteLength", "byteStride", "count"})
              check(*ext, key, "bufferViews[" + str(v) + "].extensions." + name);
    if (const Json* nodes = array("nodes"))
      for (size_t n = 0; n < nodes->size(); ++n)
        if (const Json* ext = extension((*nodes)[n], "EXT_mesh_gpu_instancing"))
          each_key(*ext, "attributes", "nodes[" + str(n) + "].extensions.EXT_mesh_gpu_instancing");
    const Json* meshes = array("meshes");
    for (size_t m = 0; meshes && m < meshes->size(); ++m) {
      const Json& primitives = (*meshes)[m]["primitives"];  // run() has checked the structure
      for (size_t p = 0; p < primitives.size(); ++p)
        if (const Json* ext = extension(primitives[p], "KHR_draco_mesh_compression")) {
          const std::string where = "meshes[" + str(m) + "].primitives[" + str(p) + "].extensions.KHR_draco_mesh_compression";
          check(*ext, "bufferView", where);
          each_key(*ext, "attributes", where);
        }
    }
  }

  const Json& doc_;
  const std::string& name_;
};

// ---- GLB container -------------------------------------------------------------------------------

struct GlbParts {
  size_t json_offset = 0, json_size = 0;
  size_t bin_offset = 0, bin_size = 0;  // the BIN chunk's data (size 0: none)
  size_t length = 0;  // declared total length (bytes after it are ignored)
};

GlbParts check_glb(std::span<const uint8_t> bytes, const std::string& name) {
  io::BinaryReader in(bytes, name);
  if (bytes.size() < 12) in.fail("truncated GLB header (" + str(bytes.size()) + " bytes, need 12)");
  if (in.read<uint32_t>(false, "GLB magic") != glb_magic) throw_bad_input_at_byte(name, 0, "wrong GLB magic (expected 'glTF')");
  const uint32_t version = in.read<uint32_t>(false, "GLB version");
  if (version != 2) throw_bad_input_at_byte(name, 4, "unsupported GLB version " + str(version) + " (expected 2)");
  const uint32_t length = in.read<uint32_t>(false, "GLB length");
  if (length > bytes.size())
    throw_bad_input_at_byte(name, 8, "GLB header declares " + str(length) + " bytes but the file has only " + str(bytes.size()) +
                                         " (truncated file?)");
  io::BinaryReader chunks(bytes.first(length), name, 12);
  if (chunks.remaining() < 8) chunks.fail("truncated GLB: no JSON chunk header");
  GlbParts parts;
  parts.length = length;
  const uint32_t json_size = chunks.read<uint32_t>(false, "JSON chunk length");
  if (chunks.read<uint32_t>(false, "JSON chunk type") != glb_chunk_json)
    throw_bad_input_at_byte(name, 16, "the first GLB chunk is not JSON");
  if (json_size == 0 || json_size > chunks.remaining())
    throw_bad_input_at_byte(name, 12, "JSON chunk length " + str(json_size) + " does not fit the " + str(chunks.remaining()) +
                                          " bytes left in the GLB");
  parts.json_offset = 20;
  parts.json_size = json_size;
  chunks.seek(20 + size_t(json_size));
  if (chunks.remaining() == 0) return parts;
  if (chunks.remaining() < 8) chunks.fail("truncated GLB chunk header");
  const size_t bin_header = chunks.offset();
  const uint32_t bin_size = chunks.read<uint32_t>(false, "BIN chunk length");
  if (chunks.read<uint32_t>(false, "BIN chunk type") != glb_chunk_bin)
    throw_bad_input_at_byte(name, bin_header + 4, "the second GLB chunk is not BIN");
  if (bin_size > chunks.remaining())
    throw_bad_input_at_byte(name, bin_header, "BIN chunk length " + str(bin_size) + " runs past the end of the GLB (" +
                                                  str(chunks.remaining()) + " bytes left)");
  parts.bin_offset = bin_header + 8;
  parts.bin_size = bin_size;
  return parts;
}

// ---- tinygltf callbacks --------------------------------------------------------------------------

// External files resolve against base_dir only (tinygltf would also try the working directory).
struct FileAccess {
  std::string prefix;  // base_dir joined the way tinygltf joins paths; empty: no external files
};

bool inside_base(const std::string& path, const FileAccess& access) {
  return !access.prefix.empty() && path.compare(0, access.prefix.size(), access.prefix) == 0;
}
bool file_exists(const std::string& path, void* user) {
  std::error_code ec;
  return inside_base(path, *static_cast<const FileAccess*>(user)) && std::filesystem::is_regular_file(path, ec);
}
std::string expand_path(const std::string& path, void*) { return path; }
bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  if (!inside_base(path, *static_cast<const FileAccess*>(user))) {
    if (err) *err = "outside the glTF file's folder";
    return false;
  }
  try {
    const FileBytes bytes = read_file_bytes(path);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const std::exception& e) {
    if (err) *err = e.what();
    return false;
  }
}
bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err = "lodkit writes files itself";
  return false;
}

// Keeps encoded images as they are. bufferView images stay in the buffers (copied on write); data:
// URI images keep their bytes, and so do external ones, which a .glb written elsewhere embeds.
bool keep_encoded_image(tg::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                        int size, void*) {
  image->as_is = true;
  if (image->bufferView < 0 && bytes && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

std::string base64(const std::vector<unsigned char>& bytes) {
  static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8 | bytes[i + 2];
    out += {digits[v >> 18], digits[(v >> 12) & 63], digits[(v >> 6) & 63], digits[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(bytes[i]) << 16;
    out += {digits[v >> 18], digits[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8;
    out += {digits[v >> 18], digits[(v >> 12) & 63], digits[(v >> 6) & 63], '='};
  }
  return out;
}

// The glTF image type of encoded bytes, by their signature ("" for none glTF knows).
std::string image_mime_type(const std::vector<unsigned char>& b) {
  const auto starts = [&](std::initializer_list<unsigned> sig, size_t at = 0) {
    if (b.size() < at + sig.size()) return false;
    size_t i = at;
    for (const unsigned c : sig)
      if (b[i++] != c) return false;
    return true;
  };
  if (starts({0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) return "image/png";
  if (starts({0xFF, 0xD8, 0xFF})) return "image/jpeg";
  if (starts({'R', 'I', 'F', 'F'}) && starts({'W', 'E', 'B', 'P'}, 8)) return "image/webp";
  if (starts({0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, 0x0D, 0x0A, 0x1A, 0x0A})) return "image/ktx2";
  return "";
}

// Replaces tinygltf's writer, which re-encodes decoded pixels. External URIs: return false, so
// tinygltf writes Image::uri verbatim. data: URI images: the original bytes, base64 again.
bool write_image_uri(const std::string*, const std::string*, const tg::Image* image, bool, std::string* out_uri, void*) {
  if (!image->uri.empty() || image->image.empty()) return false;
  const std::string mime = image->mimeType.empty() ? "application/octet-stream" : image->mimeType;
  *out_uri = "data:" + mime + ";base64," + base64(image->image);
  return true;
}

// ---- the loaded document: validation and decoding -----------------------------------------------

class Document {
 public:
  Document(const tg::Model& model, const std::string& name) : model_(model), name_(name) {}

  [[noreturn]] void fail(const std::string& what) const { throw_bad_input(name_, what); }
  const tg::Model& model() const { return model_; }
  const tg::Accessor& accessor(int index) const { return model_.accessors[size_t(index)]; }

  // Every byte range and every index the reader or writer follows; nothing is decoded before this.
  void validate() const {
    validate_buffer_views();
    for (size_t a = 0; a < model_.accessors.size(); ++a) validate_accessor(a);
    validate_references();
  }

  // Calls at(k, element) for each sparse substitution k of an accessor (none when dense): the
  // element it replaces, checked against the count.
  template <class At>
  void for_each_sparse(int index, At&& at) const {
    const tg::Accessor& acc = accessor(index);
    if (!acc.sparse.isSparse) return;
    const auto& sparse = acc.sparse;
    const uint8_t* indices = view_bytes(sparse.indices.bufferView) + sparse.indices.byteOffset;
    const size_t index_bytes = component_bytes(sparse.indices.componentType);
    for (size_t k = 0; k < size_t(sparse.count); ++k) {
      uint32_t target = 0;
      if (index_bytes == 1) {
        target = indices[k];
      } else if (index_bytes == 2) {
        uint16_t v;
        std::memcpy(&v, indices + 2 * k, 2);
        target = v;
      } else {
        std::memcpy(&target, indices + 4 * k, 4);
      }
      if (target >= acc.count)
        fail("accessors[" + str(size_t(index)) + "]: sparse index " + str(target) + " is out of range (count " +
             str(acc.count) + ")");
      at(k, target);
    }
  }

  // The sparse substitutions' values (after for_each_sparse's checks, only where there are some).
  const uint8_t* sparse_values(int index) const {
    const auto& sparse = accessor(index).sparse;
    return view_bytes(sparse.values.bufferView) + sparse.values.byteOffset;
  }

  // Every element of an accessor as tightly packed bytes of its own type, sparse substitutions made.
  std::vector<uint8_t> packed_elements(int index) const {
    const tg::Accessor& acc = accessor(index);
    const size_t element = element_bytes(acc.componentType, acc.type);
    std::vector<uint8_t> out(acc.count * element, 0);
    if (acc.bufferView >= 0) {
      const tg::BufferView& view = model_.bufferViews[size_t(acc.bufferView)];
      const uint8_t* base = view_bytes(acc.bufferView) + acc.byteOffset;
      const size_t stride = view.byteStride ? view.byteStride : element;
      for (size_t i = 0; i < acc.count; ++i) std::memcpy(out.data() + i * element, base + i * stride, element);
    }
    for_each_sparse(index, [&](size_t k, uint32_t target) {
      std::memcpy(out.data() + target * element, sparse_values(index) + k * element, element);
    });
    return out;
  }

  // Reads every element of an accessor as N components of its component type (dense data or zeros,
  // then the sparse substitutions) and calls store(element_index, const T* components).
  template <size_t N, class Store>
  void read_elements(int index, Store&& store) const {
    const tg::Accessor& acc = accessor(index);
    auto run = [&](auto tag) {
      using T = decltype(tag);
      if (acc.bufferView >= 0) {
        const tg::BufferView& view = model_.bufferViews[size_t(acc.bufferView)];
        const uint8_t* base = view_bytes(acc.bufferView) + acc.byteOffset;
        const size_t stride = view.byteStride ? view.byteStride : element_bytes(acc.componentType, acc.type);
        for (size_t i = 0; i < acc.count; ++i) {
          T raw[N];
          std::memcpy(raw, base + i * stride, sizeof raw);
          store(i, static_cast<const T*>(raw));
        }
      } else {
        const T zeros[N] = {};
        for (size_t i = 0; i < acc.count; ++i) store(i, static_cast<const T*>(zeros));
      }
      for_each_sparse(index, [&](size_t k, uint32_t target) {
        T raw[N];
        std::memcpy(raw, sparse_values(index) + k * sizeof raw, sizeof raw);
        store(target, static_cast<const T*>(raw));
      });
    };
    with_component_type(acc.componentType, run);
  }

  // Out is float, float2, float3, float4 or std::array<float, 16>; its size must match the type.
  // Integer components are normalized when the accessor says so or `normalize` is set.
  template <class Out>
  std::vector<Out> decode_floats(int index, bool normalize = false) const {
    constexpr size_t n = sizeof(Out) / sizeof(float);
    static_assert(sizeof(Out) == n * sizeof(float), "Out must be tightly packed floats");
    const tg::Accessor& acc = accessor(index);
    const bool normalized = acc.normalized || normalize;
    std::vector<Out> out(acc.count);
    read_elements<n>(index, [&](size_t i, const auto* raw) {
      float values[n];
      for (size_t c = 0; c < n; ++c) values[c] = component_to_float(raw[c], normalized);
      std::memcpy(&out[i], values, sizeof values);
    });
    return out;
  }

  // An animation sampler's output, `components` (1 to 4) floats an element, flattened. Integer
  // animation outputs are normalized by definition.
  std::vector<float> decode_animation_output(int index, size_t components) const {
    std::vector<float> out;
    auto flatten = [&](const auto& typed) {
      out.resize(typed.size() * components);
      if (!typed.empty()) std::memcpy(out.data(), typed.data(), out.size() * sizeof(float));
    };
    switch (components) {
      case 1: flatten(decode_floats<float>(index, true)); break;
      case 2: flatten(decode_floats<float2>(index, true)); break;
      case 3: flatten(decode_floats<float3>(index, true)); break;
      default: flatten(decode_floats<float4>(index, true)); break;
    }
    return out;
  }

  std::vector<uint32_t> decode_indices(int index) const {
    std::vector<uint32_t> out(accessor(index).count);
    read_elements<1>(index, [&](size_t i, const auto* raw) { out[i] = uint32_t(raw[0]); });
    return out;
  }

  std::vector<ushort4> decode_joints(int index) const {
    std::vector<ushort4> out(accessor(index).count);
    read_elements<4>(index, [&](size_t i, const auto* raw) {
      out[i] = {uint16_t(raw[0]), uint16_t(raw[1]), uint16_t(raw[2]), uint16_t(raw[3])};
    });
    return out;
  }

 private:
  const uint8_t* view_bytes(int view_index) const {
    const tg::BufferView& view = model_.bufferViews[size_t(view_index)];
    return model_.buffers[size_t(view.buffer)].data.data() + view.byteOffset;
  }

  void validate_buffer_views() const {
    for (size_t v = 0; v < model_.bufferViews.size(); ++v) {
      const tg::BufferView& view = model_.bufferViews[v];
      const std::string where = "bufferViews[" + str(v) + "]";
      if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
        fail(where + " refers to buffers[" + std::to_string(view.buffer) + "], which does not exist");
      const size_t size = model_.buffers[size_t(view.buffer)].data.size();
      if (view.byteOffset > size || view.byteLength > size - view.byteOffset)
        fail(where + " (bytes " + str(view.byteOffset) + ".." + str(view.byteOffset + view.byteLength) +
             ") runs past the end of buffers[" + std::to_string(view.buffer) + "] (" + str(size) + " bytes)");
    }
  }

  // `bytes` at `offset` must fit in bufferView `view_index`.
  void check_view_range(int view_index, int64_t offset, uint64_t bytes, const std::string& what) const {
    if (view_index < 0 || size_t(view_index) >= model_.bufferViews.size())
      fail(what + " refers to bufferViews[" + std::to_string(view_index) + "], which does not exist");
    const size_t length = model_.bufferViews[size_t(view_index)].byteLength;
    if (offset < 0 || uint64_t(offset) > length || bytes > length - uint64_t(offset))
      fail(what + " needs " + str(bytes) + " bytes at offset " + std::to_string(offset) + " but bufferViews[" +
           std::to_string(view_index) + "] has " + str(length));
  }

  void validate_accessor(size_t a) const {
    const tg::Accessor& acc = model_.accessors[a];
    const std::string where = "accessors[" + str(a) + "]";
    if (component_bytes(acc.componentType) == 0) fail(where + " has unsupported componentType " + std::to_string(acc.componentType));
    if (type_components(acc.type) == 0) fail(where + " has an unknown type");
    const size_t element = element_bytes(acc.componentType, acc.type);
    if (acc.bufferView >= 0) {
      if (size_t(acc.bufferView) >= model_.bufferViews.size())
        fail(where + " refers to bufferViews[" + std::to_string(acc.bufferView) + "], which does not exist");
      const tg::BufferView& view = model_.bufferViews[size_t(acc.bufferView)];
      if (view.byteStride != 0 && view.byteStride < element)
        fail(where + ": bufferViews[" + std::to_string(acc.bufferView) + "].byteStride " + str(view.byteStride) +
             " is smaller than the element size " + str(element) + " (accessor stride overlaps its elements)");
      const size_t stride = view.byteStride ? view.byteStride : element;
      const size_t length = view.byteLength;
      // offset + stride * (count - 1) + element <= length, without overflow.
      const bool fits = acc.count == 0 || (acc.byteOffset <= length && element <= length - acc.byteOffset &&
                                           acc.count - 1 <= (length - acc.byteOffset - element) / stride);
      if (!fits)
        fail(where + " declares " + str(acc.count) + " elements of " + str(element) + " bytes (stride " + str(stride) +
             ") from offset " + str(acc.byteOffset) + ", which do not fit in bufferViews[" +
             std::to_string(acc.bufferView) + "] (" + str(length) + " bytes)");
    } else if (acc.count > max_zero_accessor_count) {
      fail(where + " has no bufferView and declares " + str(acc.count) + " elements");
    }
    if (!acc.sparse.isSparse) return;
    const auto& sparse = acc.sparse;
    if (sparse.count < 1 || uint64_t(sparse.count) > acc.count)
      fail(where + ": sparse count " + std::to_string(sparse.count) + " is not in 1.." + str(acc.count));
    const int index_type = sparse.indices.componentType;
    if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail(where + ": sparse indices have componentType " + std::to_string(index_type) + " (expected an unsigned integer type)");
    check_view_range(sparse.indices.bufferView, sparse.indices.byteOffset,
                     uint64_t(sparse.count) * component_bytes(index_type), where + " sparse indices");
    check_view_range(sparse.values.bufferView, sparse.values.byteOffset,
                     uint64_t(sparse.count) * component_bytes(acc.componentType) * type_components(acc.type),
                     where + " sparse values");
  }

  void check_index(int index, size_t size, const std::string& what, const char* list, bool optional = true) const {
    if (optional && index == -1) return;
    if (index < 0 || size_t(index) >= size)
      fail(what + " refers to " + list + "[" + std::to_string(index) + "], which does not exist");
  }

  void validate_references() const {
    const tg::Model& m = model_;
    const size_t accessors = m.accessors.size();
    for (size_t i = 0; i < m.meshes.size(); ++i) {
      for (size_t p = 0; p < m.meshes[i].primitives.size(); ++p) {
        const tg::Primitive& prim = m.meshes[i].primitives[p];
        const std::string where = "meshes[" + str(i) + "].primitives[" + str(p) + "]";
        for (const auto& [semantic, index] : prim.attributes) check_index(index, accessors, where + " " + semantic, "accessors", false);
        check_index(prim.indices, accessors, where + " indices", "accessors");
        for (const auto& target : prim.targets)
          for (const auto& [semantic, index] : target) check_index(index, accessors, where + " morph target " + semantic, "accessors", false);
        check_index(prim.material, m.materials.size(), where, "materials");
        if (prim.mode < 0 || prim.mode > TINYGLTF_MODE_TRIANGLE_FAN) fail(where + " has unknown mode " + std::to_string(prim.mode));
      }
    }
    for (size_t i = 0; i < m.nodes.size(); ++i) {
      const tg::Node& node = m.nodes[i];
      const std::string where = "nodes[" + str(i) + "]";
      check_index(node.mesh, m.meshes.size(), where, "meshes");
      check_index(node.skin, m.skins.size(), where, "skins");
      check_index(node.camera, m.cameras.size(), where, "cameras");
      for (int child : node.children) check_index(child, m.nodes.size(), where + " child", "nodes", false);
      const tg::Value& lod_ids = msft_lod_ids(node);
      if (lod_ids.Type() != tg::NULL_TYPE && !lod_ids.IsArray()) fail(where + " MSFT_lod ids is not an array");
      for (size_t k = 0; k < lod_ids.ArrayLen(); ++k) {
        const tg::Value& id = lod_ids.Get(int(k));
        if (!id.IsInt()) fail(where + " MSFT_lod ids[" + str(k) + "] is not a node index");
        check_index(id.Get<int>(), m.nodes.size(), where + " MSFT_lod", "nodes", false);
      }
    }
    for (size_t i = 0; i < m.skins.size(); ++i) {
      const std::string where = "skins[" + str(i) + "]";
      check_index(m.skins[i].inverseBindMatrices, accessors, where + " inverseBindMatrices", "accessors");
      check_index(m.skins[i].skeleton, m.nodes.size(), where + " skeleton", "nodes");
      for (int joint : m.skins[i].joints) check_index(joint, m.nodes.size(), where + " joint", "nodes", false);
    }
    for (size_t i = 0; i < m.animations.size(); ++i) {
      const tg::Animation& anim = m.animations[i];
      for (size_t s = 0; s < anim.samplers.size(); ++s) {
        const std::string where = "animations[" + str(i) + "].samplers[" + str(s) + "]";
        check_index(anim.samplers[s].input, accessors, where + " input", "accessors", false);
        check_index(anim.samplers[s].output, accessors, where + " output", "accessors", false);
      }
      for (size_t c = 0; c < anim.channels.size(); ++c) {
        const std::string where = "animations[" + str(i) + "].channels[" + str(c) + "]";
        check_index(anim.channels[c].sampler, anim.samplers.size(), where, "samplers", false);
        check_index(anim.channels[c].target_node, m.nodes.size(), where + " target", "nodes");
      }
    }
    for (size_t i = 0; i < m.scenes.size(); ++i)
      for (int node : m.scenes[i].nodes) check_index(node, m.nodes.size(), "scenes[" + str(i) + "]", "nodes", false);
    check_index(m.defaultScene, m.scenes.size(), "'scene'", "scenes");
    for (size_t i = 0; i < m.images.size(); ++i)
      check_index(m.images[i].bufferView, m.bufferViews.size(), "images[" + str(i) + "]", "bufferViews");
  }

  const tg::Model& model_;
  const std::string& name_;
};

// ---- glTF -> lod::Scene --------------------------------------------------------------------------

class SceneBuilder {
 public:
  explicit SceneBuilder(const Document& doc) : doc_(doc), model_(doc.model()) {}

  Scene build() {
    Scene scene;
    for (size_t m = 0; m < model_.meshes.size(); ++m) {
      for (size_t p = 0; p < model_.meshes[m].primitives.size(); ++p) {
        const tg::Primitive& prim = model_.meshes[m].primitives[p];
        // Points and lines stay in the source document and are written back unchanged.
        if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            prim.mode != TINYGLTF_MODE_TRIANGLE_FAN)
          continue;
        Primitive out;
        out.gltf_mesh = uint32_t(m);
        out.gltf_primitive = uint32_t(p);
        out.material = prim.material;
        out.mesh = decode_primitive(prim, "meshes[" + str(m) + "].primitives[" + str(p) + "]");
        scene.primitives.push_back(std::move(out));
      }
    }
    build_nodes(scene);
    build_skins(scene);
    build_animations(scene);
    for (const tg::Material& material : model_.materials) scene.material_names.push_back(material.name);
    scene.image_count = uint32_t(model_.images.size());
    scene.texture_count = uint32_t(model_.textures.size());
    scene.gltf_mesh_count = uint32_t(model_.meshes.size());
    return scene;
  }

 private:
  const tg::Accessor& expect(int index, std::initializer_list<int> types, const std::string& what) const {
    const tg::Accessor& acc = doc_.accessor(index);
    if (std::find(types.begin(), types.end(), acc.type) == types.end()) {
      std::string expected;
      for (int t : types) expected += (expected.empty() ? "" : " or ") + std::string(type_name(t));
      doc_.fail(what + " is " + type_name(acc.type) + ", expected " + expected);
    }
    return acc;
  }

  template <class T>
  void check_finite(const std::vector<T>& values, const std::string& what) const {
    constexpr size_t n = sizeof(T) / sizeof(float);
    for (size_t i = 0; i < values.size(); ++i) {
      float v[n];
      std::memcpy(v, &values[i], sizeof v);
      for (size_t c = 0; c < n; ++c)
        if (!std::isfinite(v[c])) doc_.fail(what + " of vertex " + str(i) + " is not finite");
    }
  }

  Mesh decode_primitive(const tg::Primitive& prim, const std::string& where) const {
    auto attribute = [&](const std::string& semantic) {
      auto it = prim.attributes.find(semantic);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    Mesh mesh;
    const int position = attribute("POSITION");
    if (position < 0) doc_.fail(where + " has no POSITION attribute");
    const size_t vertex_count = expect(position, {TINYGLTF_TYPE_VEC3}, where + " POSITION").count;
    if (vertex_count > std::numeric_limits<uint32_t>::max()) doc_.fail(where + " has more than 2^32 vertices");
    mesh.positions = doc_.decode_floats<float3>(position);
    for (size_t i = 0; i < vertex_count; ++i) {
      const float3& p = mesh.positions[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        doc_.fail(where + " POSITION of vertex " + str(i) + " is not finite");
    }
    // Every other stream must have one entry per vertex.
    auto stream = [&](const std::string& semantic, std::initializer_list<int> types) {
      const int index = attribute(semantic);
      if (index < 0) return -1;
      const tg::Accessor& acc = expect(index, types, where + " " + semantic);
      if (acc.count != vertex_count)
        doc_.fail(where + " " + semantic + " has " + str(acc.count) + " entries for " + str(vertex_count) + " vertices");
      return index;
    };
    if (int index = stream("NORMAL", {TINYGLTF_TYPE_VEC3}); index >= 0) {
      mesh.normals = doc_.decode_floats<float3>(index);
      check_finite(mesh.normals, where + " NORMAL");
    }
    if (int index = stream("TANGENT", {TINYGLTF_TYPE_VEC4}); index >= 0) {
      mesh.tangents = doc_.decode_floats<float4>(index);
      check_finite(mesh.tangents, where + " TANGENT");
    }
    for (size_t k = 0; k < max_uv_sets; ++k) {
      const std::string semantic = "TEXCOORD_" + str(k);
      if (int index = stream(semantic, {TINYGLTF_TYPE_VEC2}); index >= 0) {
        mesh.uvs[k] = doc_.decode_floats<float2>(index);
        check_finite(mesh.uvs[k], where + " " + semantic);
      }
    }
    if (int index = stream("COLOR_0", {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4}); index >= 0) {
      // Integer colors are normalized by definition (the flag is required by the spec).
      if (doc_.accessor(index).type == TINYGLTF_TYPE_VEC4) {
        mesh.colors = doc_.decode_floats<float4>(index, true);
      } else {
        const std::vector<float3> rgb = doc_.decode_floats<float3>(index, true);
        mesh.colors.resize(rgb.size());
        for (size_t i = 0; i < rgb.size(); ++i) mesh.colors[i] = {rgb[i].x, rgb[i].y, rgb[i].z, 1.0f};
      }
      check_finite(mesh.colors, where + " COLOR_0");
    }
    // Influence sets 0 and 1 (up to eight influences), by the same rules: JOINTS_n unsigned byte or
    // short; WEIGHTS_n as floats, integer ones normalized.
    std::vector<ushort4>* joint_sets[2] = {&mesh.joints, &mesh.joints1};
    std::vector<float4>* weight_sets[2] = {&mesh.weights, &mesh.weights1};
    for (size_t set = 0; set < 2; ++set) {
      const std::string joints = "JOINTS_" + str(set), weights = "WEIGHTS_" + str(set);
      if (int index = stream(joints, {TINYGLTF_TYPE_VEC4}); index >= 0) {
        const int type = doc_.accessor(index).componentType;
        if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)
          doc_.fail(where + " " + joints + " must be unsigned byte or unsigned short");
        *joint_sets[set] = doc_.decode_joints(index);
      }
      if (int index = stream(weights, {TINYGLTF_TYPE_VEC4}); index >= 0) {
        *weight_sets[set] = doc_.decode_floats<float4>(index, true);
        check_finite(*weight_sets[set], where + " " + weights);
      }
    }
    if ((!mesh.joints1.empty() || !mesh.weights1.empty()) && (mesh.joints.empty() || mesh.weights.empty()))
      doc_.fail(where + " has JOINTS_1 or WEIGHTS_1 without JOINTS_0 and WEIGHTS_0");
    // The streams lodkit does not decode (other attributes, morph targets) are written back through
    // the vertices (Primitive::source_vertices): one entry per vertex as well, as glTF requires.
    const auto one_per_vertex = [&](int index, const std::string& what) {
      const size_t count = doc_.accessor(index).count;
      if (count != vertex_count) doc_.fail(where + " " + what + " has " + str(count) + " entries for " + str(vertex_count) + " vertices");
    };
    for (const auto& [semantic, index] : prim.attributes) one_per_vertex(index, semantic);
    for (size_t k = 0; k < prim.targets.size(); ++k)
      for (const auto& [semantic, index] : prim.targets[k]) {
        one_per_vertex(index, "morph target " + str(k) + " " + semantic);
        // Displacements of the three-component attributes are three-component too (glTF 3.7.2.2).
        if ((semantic == "POSITION" || semantic == "NORMAL" || semantic == "TANGENT") && doc_.accessor(index).type != TINYGLTF_TYPE_VEC3)
          doc_.fail(where + " morph target " + str(k) + " " + semantic + " must be VEC3");
      }

    std::vector<uint32_t> corners;
    if (prim.indices >= 0) {
      const tg::Accessor& acc = expect(prim.indices, {TINYGLTF_TYPE_SCALAR}, where + " indices");
      const int type = acc.componentType;
      if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        doc_.fail(where + " indices must be unsigned byte, short or int");
      corners = doc_.decode_indices(prim.indices);
      for (size_t i = 0; i < corners.size(); ++i)
        if (corners[i] >= vertex_count)
          doc_.fail(where + " index " + str(i) + " is " + str(corners[i]) + ", out of range for " + str(vertex_count) +
                    " vertices");
    } else {
      corners.resize(vertex_count);
      for (size_t i = 0; i < vertex_count; ++i) corners[i] = uint32_t(i);
    }
    mesh.indices = triangle_list(prim.mode, std::move(corners), where);
    // The spec asks unit normals and tangents, but files break it (exporters write unnormalized
    // ones, quantized ones drift by their step); an output must not carry that on.
    make_unit_directions(mesh);
    return mesh;
  }

  std::vector<uint32_t> triangle_list(int mode, std::vector<uint32_t> corners, const std::string& where) const {
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (corners.size() % 3 != 0)
        doc_.fail(where + " has " + str(corners.size()) + " triangle corners, not a multiple of 3");
      return corners;
    }
    std::vector<uint32_t> out;
    const size_t n = corners.size();
    if (n < 3) return out;
    out.reserve((n - 2) * 3);
    for (size_t i = 0; i + 2 < n; ++i) {
      uint32_t a, b, c;
      if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        // Every other triangle is flipped so that the whole strip keeps one winding.
        a = corners[i];
        b = corners[i + 1 + i % 2];
        c = corners[i + 2 - i % 2];
      } else {
        a = corners[i + 1];
        b = corners[i + 2];
        c = corners[0];
      }
      // Strips join runs with repeated indices; those zero-area triangles are padding, not geometry.
      if (a == b || b == c || a == c) continue;
      out.insert(out.end(), {a, b, c});
    }
    return out;
  }

  void build_nodes(Scene& scene) const {
    const size_t count = model_.nodes.size();
    scene.nodes.resize(count);
    for (size_t i = 0; i < count; ++i) {
      const tg::Node& in = model_.nodes[i];
      Node& out = scene.nodes[i];
      const std::string where = "nodes[" + str(i) + "]";
      out.name = in.name;
      out.mesh = in.mesh;
      out.skin = in.skin;
      out.children.assign(in.children.begin(), in.children.end());
      const tg::Value& lod_ids = msft_lod_ids(in);
      for (size_t k = 0; k < lod_ids.ArrayLen(); ++k) out.lod_ids.push_back(lod_ids.Get(int(k)).Get<int>());
      if (in.extras.Type() != tg::NULL_TYPE) out.extras_json = value_to_json(in.extras).dump();
      read_gpu_instances(in, out, where);
      if (const auto ext = in.extensions.find(node_visibility); ext != in.extensions.end()) {
        out.has_visibility = true;
        if (!ext->second.IsObject()) doc_.fail(where + ".extensions." + node_visibility + " must be an object");
        if (ext->second.Has("visible")) {
          const tg::Value& visible = ext->second.Get("visible");
          if (!visible.IsBool()) doc_.fail(where + ".extensions." + node_visibility + ".visible must be true or false");
          out.visible = visible.Get<bool>();
        }
      }
      for (int child : in.children) {
        if (size_t(child) == i) doc_.fail(where + " is its own child");
        if (scene.nodes[size_t(child)].parent != -1)
          doc_.fail("nodes[" + std::to_string(child) + "] has two parents (nodes[" +
                    std::to_string(scene.nodes[size_t(child)].parent) + "] and " + where + ")");
        scene.nodes[size_t(child)].parent = int32_t(i);
      }
      auto copy = [&](const std::vector<double>& values, size_t expected, float* dst, const char* what) {
        if (values.empty()) return;
        if (values.size() != expected)
          doc_.fail(where + "." + what + " has " + str(values.size()) + " numbers, expected " + str(expected));
        for (size_t k = 0; k < expected; ++k) dst[k] = float(values[k]);
      };
      if (!in.matrix.empty()) {
        out.has_matrix = true;
        copy(in.matrix, 16, out.matrix.data(), "matrix");
      } else {
        float t[3] = {0, 0, 0}, r[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
        copy(in.translation, 3, t, "translation");
        copy(in.rotation, 4, r, "rotation");
        copy(in.scale, 3, s, "scale");
        out.translation = {t[0], t[1], t[2]};
        out.rotation = {r[0], r[1], r[2], r[3]};
        out.scale = {s[0], s[1], s[2]};
      }
    }
    // A parent chain that never reaches a root is a cycle.
    std::vector<uint8_t> state(count, 0);  // 0 unknown, 1 on the current walk, 2 reaches a root
    std::vector<size_t> walk;
    for (size_t i = 0; i < count; ++i) {
      walk.clear();
      int32_t n = int32_t(i);
      while (n != -1 && state[size_t(n)] == 0) {
        state[size_t(n)] = 1;
        walk.push_back(size_t(n));
        n = scene.nodes[size_t(n)].parent;
      }
      if (n != -1 && state[size_t(n)] == 1) doc_.fail("nodes[" + std::to_string(n) + "] is part of a node cycle");
      for (size_t w : walk) state[w] = 2;
    }
    if (!model_.scenes.empty()) {
      const size_t s = model_.defaultScene >= 0 ? size_t(model_.defaultScene) : 0;
      scene.roots.assign(model_.scenes[s].nodes.begin(), model_.scenes[s].nodes.end());
    } else {
      // No scene: every parentless node is a root.
      for (size_t i = 0; i < count; ++i)
        if (scene.nodes[i].parent == -1) scene.roots.push_back(int32_t(i));
    }
  }

  // EXT_mesh_gpu_instancing: TRANSLATION, ROTATION and SCALE accessors of one count (floats, or
  // normalized integers as KHR_mesh_quantization allows), any of them absent.
  void read_gpu_instances(const tg::Node& in, Node& out, const std::string& where) const {
    auto found = in.extensions.find(gpu_instancing);
    if (found == in.extensions.end()) return;
    const std::string ext_where = where + ".extensions." + gpu_instancing;
    if (!found->second.IsObject() || !found->second.Has("attributes") || !found->second.Get("attributes").IsObject())
      doc_.fail(ext_where + " has no 'attributes' object");
    const tg::Value& attributes = found->second.Get("attributes");
    // Every attribute (custom "_NAME" ones included, which the writer keeps) names an accessor.
    for (const std::string& semantic : attributes.Keys()) {
      const tg::Value& value = attributes.Get(semantic);
      if (!value.IsInt() || value.Get<int>() < 0 || size_t(value.Get<int>()) >= model_.accessors.size())
        doc_.fail(ext_where + ".attributes." + semantic + " is not an index of accessors");
    }
    size_t count = 0;
    bool any = false;
    auto read = [&](const char* semantic, int type) -> std::vector<float> {
      if (!attributes.Has(semantic)) return {};
      const std::string what = ext_where + ".attributes." + semantic;
      const tg::Value& value = attributes.Get(semantic);
      const int index = value.IsInt() ? value.Get<int>() : -1;
      if (index < 0 || size_t(index) >= model_.accessors.size()) doc_.fail(what + " is not an index of accessors");
      const tg::Accessor& acc = expect(index, {type}, what);
      if (any && acc.count != count) doc_.fail(what + " has " + str(acc.count) + " elements, the other attributes " + str(count));
      count = acc.count;
      any = true;
      // Integers are normalized only where the accessor says so (quantized translations are not).
      const size_t n = type == TINYGLTF_TYPE_VEC4 ? 4 : 3;
      std::vector<float> values(acc.count * n);
      auto copy = [&](const auto& typed) {
        if (!typed.empty()) std::memcpy(values.data(), typed.data(), values.size() * sizeof(float));
      };
      if (n == 4) copy(doc_.decode_floats<float4>(index));
      else copy(doc_.decode_floats<float3>(index));
      for (size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i])) doc_.fail(what + " of instance " + str(i / n) + " is not finite");
      return values;
    };
    const std::vector<float> t = read("TRANSLATION", TINYGLTF_TYPE_VEC3), r = read("ROTATION", TINYGLTF_TYPE_VEC4),
                             s = read("SCALE", TINYGLTF_TYPE_VEC3);
    if (!any) doc_.fail(ext_where + " has no TRANSLATION, ROTATION or SCALE");
    out.gpu_instances.resize(count);
    for (size_t i = 0; i < count; ++i) {
      Node::GpuInstance& g = out.gpu_instances[i];
      if (!t.empty()) g.translation = {t[3 * i], t[3 * i + 1], t[3 * i + 2]};
      if (!r.empty()) g.rotation = {r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]};
      if (!s.empty()) g.scale = {s[3 * i], s[3 * i + 1], s[3 * i + 2]};
    }
  }

  void build_skins(Scene& scene) const {
    for (size_t i = 0; i < model_.skins.size(); ++i) {
      const tg::Skin& in = model_.skins[i];
      Skin out;
      out.name = in.name;
      out.joints.assign(in.joints.begin(), in.joints.end());
      out.skeleton = in.skeleton;
      if (in.inverseBindMatrices >= 0) {
        const std::string where = "skins[" + str(i) + "].inverseBindMatrices";
        const tg::Accessor& acc = expect(in.inverseBindMatrices, {TINYGLTF_TYPE_MAT4}, where);
        if (acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) doc_.fail(where + " must be float");
        if (acc.count < in.joints.size())
          doc_.fail(where + " has " + str(acc.count) + " matrices for " + str(in.joints.size()) + " joints");
        out.inverse_bind_matrices = doc_.decode_floats<std::array<float, 16>>(in.inverseBindMatrices);
        out.inverse_bind_matrices.resize(in.joints.size());
      } else {
        out.inverse_bind_matrices.assign(in.joints.size(), {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
      }
      scene.skins.push_back(std::move(out));
    }
  }

  // Each clip's node channels; a KHR_animation_pointer to a mesh's weights ("/meshes/M/weights")
  // as well, as the weights channel of each node drawing M without weights of its own (what a
  // viewer shows: a node's weights override its mesh's), after the clip's core channels so that a
  // node's own channel comes first (weights_channel). Other pointers are kept in the source only.
  void build_animations(Scene& scene) const {
    for (size_t a = 0; a < model_.animations.size(); ++a) {
      const tg::Animation& in = model_.animations[a];
      Animation out;
      out.name = in.name;
      std::vector<AnimationChannel> mesh_weights;
      for (size_t c = 0; c < in.channels.size(); ++c) {
        const tg::AnimationChannel& channel = in.channels[c];
        const std::string where = "animations[" + str(a) + "].channels[" + str(c) + "]";
        if (channel.target_node >= 0) {
          for (const AnimationPath path : {AnimationPath::translation, AnimationPath::rotation, AnimationPath::scale, AnimationPath::weights})
            if (channel.target_path == path_name(path)) {
              out.channels.push_back(decode_channel(in.samplers[size_t(channel.sampler)], path, where));
              out.channels.back().node = channel.target_node;
            }
          continue;  // (any other path: an extension's target, kept in the source only)
        }
        const ChannelTarget t = channel_target(channel);
        if (switches_visibility(t) && size_t(t.index) < scene.nodes.size())
          scene.nodes[size_t(t.index)].has_visibility = true;
        if (t.list != "meshes" || t.property != "weights") continue;
        std::optional<AnimationChannel> keys;  // decoded once a node draws the mesh
        for (size_t n = 0; n < model_.nodes.size(); ++n) {
          if (model_.nodes[n].mesh != t.index || !model_.nodes[n].weights.empty()) continue;
          if (!keys) keys = decode_channel(in.samplers[size_t(channel.sampler)], AnimationPath::weights, where);
          mesh_weights.push_back(*keys);
          mesh_weights.back().node = int32_t(n);
        }
      }
      out.channels.insert(out.channels.end(), std::make_move_iterator(mesh_weights.begin()), std::make_move_iterator(mesh_weights.end()));
      scene.animations.push_back(std::move(out));
    }
  }

  // A sampler's keys as a channel of `path` (its node left for the caller).
  AnimationChannel decode_channel(const tg::AnimationSampler& sampler, AnimationPath path, const std::string& where) const {
    AnimationChannel ch;
    ch.path = path;
    const int output_type = path_output_type(path);
    if (sampler.interpolation == "LINEAR")
      ch.interpolation = Interpolation::linear;
    else if (sampler.interpolation == "STEP")
      ch.interpolation = Interpolation::step;
    else if (sampler.interpolation == "CUBICSPLINE")
      ch.interpolation = Interpolation::cubic_spline;
    else
      doc_.fail(where + " has unknown interpolation '" + sampler.interpolation + "'");
    const tg::Accessor& input = expect(sampler.input, {TINYGLTF_TYPE_SCALAR}, where + " sampler input");
    if (input.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) doc_.fail(where + " sampler input must be float");
    const tg::Accessor& output = expect(sampler.output, {output_type}, where + " sampler output");
    const size_t per_key = ch.interpolation == Interpolation::cubic_spline ? 3 : 1;
    const size_t keys = input.count;
    if (path == AnimationPath::weights) {
      if (keys == 0 || output.count % (keys * per_key) != 0)
        doc_.fail(where + " has " + str(output.count) + " weight outputs for " + str(keys) + " keys");
      ch.components = uint32_t(output.count / (keys * per_key));
    } else {
      ch.components = output_type == TINYGLTF_TYPE_VEC4 ? 4 : 3;
      if (output.count != keys * per_key) doc_.fail(where + " has " + str(output.count) + " outputs for " + str(keys) + " keys");
    }
    ch.times = doc_.decode_floats<float>(sampler.input);
    ch.values = doc_.decode_animation_output(sampler.output, type_components(output_type));
    return ch;
  }

  const Document& doc_;
  const tg::Model& model_;
};

// ---- writing: geometry regeneration and buffer repacking -----------------------------------------

bool is_triangle_mode(int mode) {
  return mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP || mode == TINYGLTF_MODE_TRIANGLE_FAN;
}

// The elements of `bytes` (`element` bytes each) that `source` names, in its order: a stream
// following renumbered vertices.
std::vector<uint8_t> gather_elements(const std::vector<uint8_t>& bytes, size_t element, const std::vector<uint32_t>& source) {
  std::vector<uint8_t> out(source.size() * element);
  for (size_t i = 0; i < source.size(); ++i) std::memcpy(out.data() + i * element, bytes.data() + size_t(source[i]) * element, element);
  return out;
}

// The semantics lodkit regenerates from a Mesh; any other attribute of a regenerated primitive is
// kept only while the vertex count is unchanged.
bool is_regenerated_semantic(const std::string& semantic) {
  return semantic == "POSITION" || semantic == "NORMAL" || semantic == "TANGENT" || semantic == "TEXCOORD_0" ||
         semantic == "TEXCOORD_1" || semantic == "TEXCOORD_2" || semantic == "TEXCOORD_3" || semantic == "COLOR_0" ||
         semantic == "JOINTS_0" || semantic == "WEIGHTS_0" || semantic == "JOINTS_1" || semantic == "WEIGHTS_1";
}

// Calls f(target, semantic, accessor index) for each stream of a primitive that lodkit does not
// model: the attributes it does not regenerate (target -1), then every morph target's attributes.
template <class GltfPrimitive, class F>
void for_each_unmodelled_stream(GltfPrimitive& prim, F&& f) {
  for (auto& [semantic, index] : prim.attributes)
    if (!is_regenerated_semantic(semantic)) f(-1, semantic, index);
  for (size_t k = 0; k < prim.targets.size(); ++k)
    for (auto& [semantic, index] : prim.targets[k]) f(int(k), semantic, index);
}

struct Slot {
  int mesh = 0, primitive = 0;  // where a Scene primitive lives in the model being written
};

// ---- KHR_mesh_quantization (WriteOptions::quantize) ----------------------------------------------

// The document's position grid: p = offset + scale * q, q an integer in [0, top] per axis. One scale
// on every axis, so that normals mean the same on the grid (gltfpack's choice too); one grid for
// every mesh, so that meshes which meet (a character's parts, LOD levels) still meet exactly.
struct PositionGrid {
  double offset[3] = {0, 0, 0};
  double scale = 1;
  double top = 0;  // 2^bits - 1; 0: no grid (positions stay floats)
};

// A position component's grid coordinate: the nearest step, clamped to the grid.
auto grid_code(const PositionGrid& grid) {
  return [&grid](float x, size_t c) { return std::lround(std::clamp((x - grid.offset[c]) / grid.scale, 0.0, grid.top)); };
}

// -q's box for a UV set outside [0, 1], or for any sampled set below 16 UV bits: stored =
// (uv - offset) / scale in normalized unsigned shorts, which the KHR_texture_transform of every
// texture sampling the set maps back. With b UV bits the scale is the set's extent times
// 65535 / (2^b - 1), so the stored values run from 0 to 2^b - 1.
struct UvBox {
  float offset[2] = {0, 0}, scale[2] = {1, 1};
  bool operator==(const UvBox&) const = default;
};
using UvBoxes = std::array<std::optional<UvBox>, max_uv_sets>;

// How BinWriter stores one primitive's streams.
struct StreamCoding {
  bool quantize = false;               // normals, tangents, UVs, colours and weights in fewer bits
  const PositionGrid* grid = nullptr;  // positions and target positions on this grid
  const UvBoxes* uv_boxes = nullptr;   // quantized: UV sets outside [0, 1] stored on these boxes
  int normal_bits = 8;                 // quantized: normals and tangents in bytes (8) or shorts (9-16)
  io::DirectionFloats* directions = nullptr;  // quantized: where to keep their floats (--cc's filter codes them)
};

// Each element's float components (float2, float3, float4), stored as integers I = code(value,
// component), packed.
template <class I, class T, class Code>
std::vector<uint8_t> pack_components(const std::vector<T>& values, Code&& code) {
  constexpr size_t n = sizeof(T) / sizeof(float);
  static_assert(sizeof(T) == n * sizeof(float), "T must be tightly packed floats");
  std::vector<uint8_t> out(values.size() * n * sizeof(I));
  for (size_t i = 0; i < values.size(); ++i) {
    float f[n];
    std::memcpy(f, &values[i], sizeof f);
    for (size_t c = 0; c < n; ++c) {
      const I q = std::isnan(f[c]) ? I(0) : I(code(f[c], c));  // (a NaN has no integer)
      std::memcpy(out.data() + (i * n + c) * sizeof(I), &q, sizeof q);
    }
  }
  return out;
}

template <class T>
bool all_in_range(const std::vector<T>& values, float low, float high) {
  const auto* f = reinterpret_cast<const float*>(values.data());
  return std::all_of(f, f + values.size() * (sizeof(T) / sizeof(float)), [=](float x) { return x >= low && x <= high; });
}

// Signed normalized integers of type I (normals and tangents in bytes, rotations in shorts):
// round(x * max).
template <class I, class T>
std::vector<uint8_t> snorm(const std::vector<T>& values) {
  const float top = float(std::numeric_limits<I>::max());
  return pack_components<I>(values, [top](float x, size_t) { return std::lround(std::clamp(x, -1.0f, 1.0f) * top); });
}
// Directions (normals, tangents, their morph displacements) in `bits` per component: normalized
// bytes for 8, else normalized shorts on multiples of 2^(16 - bits), the nearest, with +-1 kept
// exact (32767, not a multiple) so unit axes stay unit. Returns the bytes and the component type.
template <class T>
std::pair<std::vector<uint8_t>, int> snorm_directions(const std::vector<T>& values, int bits) {
  if (bits <= 8) return {snorm<int8_t>(values), TINYGLTF_COMPONENT_TYPE_BYTE};
  const double step = double(1 << (16 - bits));
  return {pack_components<int16_t>(values, [step](float x, size_t) {
            return std::clamp(std::lround(std::round(std::clamp(double(x), -1.0, 1.0) * 32767.0 / step) * step), -32767L, 32767L);
          }),
          TINYGLTF_COMPONENT_TYPE_SHORT};
}
// Unsigned normalized integers of type I (UVs, colours): round(x * max).
template <class I, class T>
std::vector<uint8_t> unorm(const std::vector<T>& values) {
  const float top = float(std::numeric_limits<I>::max());
  return pack_components<I>(values, [top](float x, size_t) { return std::lround(std::clamp(x, 0.0f, 1.0f) * top); });
}

// A skinned vertex's weights (one or two sets) in normalized unsigned bytes that sum to exactly 255,
// as glTF asks of quantized weights: rounded, the largest taking the difference.
std::array<std::vector<uint8_t>, 2> unorm8_weights(const std::vector<float4>& first, const std::vector<float4>& second) {
  const size_t n = first.size(), sets = second.empty() ? 1 : 2;
  std::array<std::vector<uint8_t>, 2> out{std::vector<uint8_t>(4 * n), std::vector<uint8_t>(second.empty() ? 0 : 4 * n)};
  for (size_t v = 0; v < n; ++v) {
    float w[8] = {};
    std::memcpy(w, &first[v], sizeof(float4));
    if (sets == 2) std::memcpy(w + 4, &second[v], sizeof(float4));
    double total = 0;
    for (float& x : w) total += x = std::isfinite(x) ? std::max(x, 0.0f) : 0.0f;
    int q[8] = {}, sum = 0, largest = 0;
    for (size_t k = 0; k < 4 * sets; ++k) {
      q[k] = total > 0 ? int(std::lround(w[k] / total * 255.0)) : 0;
      sum += q[k];
      if (q[k] > q[largest]) largest = int(k);
    }
    if (total > 0) q[largest] += 255 - sum;
    for (size_t k = 0; k < 4 * sets; ++k) out[k / 4][4 * v + k % 4] = uint8_t(q[k]);
  }
  return out;
}

// A skinned vertex's float weights (one or two sets) as written: glTF asks them to sum to 1, which
// the validator checks in float, within 2e-7 per nonzero weight. A vertex that does not (Draco's
// 12-bit weights decoded: 1 +- 1.6e-4) is renormalised, summed in double with the rest left on the
// largest; the others are written as they are (byte-identical).
std::array<std::vector<float4>, 2> normalized_float_weights(const std::vector<float4>& first, const std::vector<float4>& second) {
  std::array<std::vector<float4>, 2> out{first, second};
  const size_t sets = second.empty() ? 1 : 2;
  for (size_t v = 0; v < first.size(); ++v) {
    float* w[2] = {&out[0][v].x, sets == 2 ? &out[1][v].x : nullptr};
    float sum = 0;  // in the validator's order: each component across the sets
    int nonzero = 0;
    for (size_t k = 0; k < 4; ++k)
      for (size_t set = 0; set < sets; ++set) sum += w[set][k], nonzero += w[set][k] != 0;
    if (std::fabs(sum - 1.0f) <= 2e-7f * float(nonzero)) continue;
    double total = 0;
    for (size_t set = 0; set < sets; ++set)
      for (size_t k = 0; k < 4; ++k) total += w[set][k] = std::isfinite(w[set][k]) ? std::max(w[set][k], 0.0f) : 0.0f;
    if (!(total > 0)) continue;  // no weight to scale (invalid either way)
    float* largest = w[0];
    double rest = 0;
    for (size_t set = 0; set < sets; ++set)
      for (size_t k = 0; k < 4; ++k) {
        w[set][k] = float(w[set][k] / total);
        if (w[set][k] > *largest) largest = &w[set][k];
      }
    for (size_t set = 0; set < sets; ++set)
      for (size_t k = 0; k < 4; ++k)
        if (&w[set][k] != largest) rest += w[set][k];
    *largest = float(1.0 - rest);
  }
  return out;
}

class BinWriter {
 public:
  BinWriter(tg::Model& model, std::vector<uint8_t>& bin) : model_(model), bin_(bin) {}

  // Whether a stream was written in a form only KHR_mesh_quantization allows.
  bool used_quantization() const { return used_quantization_; }

  void align() { bin_.resize((bin_.size() + 3) & ~size_t(3), 0); }

  int add_view(const void* data, size_t bytes, int target) {
    align();
    tg::BufferView view;
    view.buffer = 0;
    view.byteOffset = bin_.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* p = static_cast<const uint8_t*>(data);
    bin_.insert(bin_.end(), p, p + bytes);
    model_.bufferViews.push_back(std::move(view));
    return int(model_.bufferViews.size() - 1);
  }

  template <class T>
  int add_accessor(const std::vector<T>& values, int component_type, int type, int target, bool normalized = false) {
    tg::Accessor acc;
    acc.bufferView = add_view(values.data(), values.size() * sizeof(T), target);
    acc.componentType = component_type;
    acc.type = type;
    acc.count = values.size();
    acc.normalized = normalized;
    model_.accessors.push_back(std::move(acc));
    return int(model_.accessors.size() - 1);
  }

  // A vertex stream of `like`'s type from tightly packed elements; each element padded to 4 bytes
  // (glTF's vertex attribute alignment). With `bounds`, the accessor's min and max (a POSITION must
  // have them), in stored units.
  int add_vertex_stream(const std::vector<uint8_t>& packed, const tg::Accessor& like, bool bounds) {
    const size_t element = element_bytes(like.componentType, like.type), stride = (element + 3) & ~size_t(3);
    const size_t count = element ? packed.size() / element : 0;
    std::vector<uint8_t> bytes(count * stride, 0);
    for (size_t i = 0; i < count; ++i) std::memcpy(bytes.data() + i * stride, packed.data() + i * element, element);
    tg::Accessor acc;
    acc.bufferView = add_view(bytes.data(), bytes.size(), TINYGLTF_TARGET_ARRAY_BUFFER);
    if (stride != element) model_.bufferViews.back().byteStride = stride;
    acc.componentType = like.componentType;
    acc.type = like.type;
    acc.count = count;
    acc.normalized = like.normalized;
    acc.name = like.name;
    if (bounds && count) {
      const size_t n = type_components(like.type), size = component_bytes(like.componentType);
      acc.minValues.assign(n, INFINITY);
      acc.maxValues.assign(n, -INFINITY);
      for (size_t i = 0; i < count; ++i)
        for (size_t c = 0; c < n; ++c) {
          const double v = component_value(packed.data() + i * element + c * size, like.componentType);
          acc.minValues[c] = std::min(acc.minValues[c], v), acc.maxValues[c] = std::max(acc.maxValues[c], v);
        }
    }
    model_.accessors.push_back(std::move(acc));
    return int(model_.accessors.size() - 1);
  }

  // Packed integer elements as a vertex stream.
  int add_packed(const std::vector<uint8_t>& packed, int component_type, int type, bool normalized, bool bounds = false) {
    tg::Accessor like;
    like.componentType = component_type;
    like.type = type;
    like.normalized = normalized;
    return add_vertex_stream(packed, like, bounds);
  }

  // A float stream in fewer bits where `coding` asks for it and the values allow it.
  template <class T>
  int add_float_stream(const std::vector<T>& values, int type, const char* semantic, const StreamCoding& coding) {
    const int array = TINYGLTF_TARGET_ARRAY_BUFFER;
    if (coding.quantize) {
      const std::string_view name = semantic;
      // (Core glTF allows integer UVs and colours; integer normals and tangents need the extension.)
      if (name == "NORMAL" || name == "TANGENT") {
        const auto [packed, component] = snorm_directions(values, coding.normal_bits);
        const int accessor = add_packed(packed, component, type, true);
        if (coding.directions) {
          std::vector<float>& floats = (*coding.directions)[size_t(accessor)];
          floats.assign(4 * values.size(), 0.0f);
          for (size_t i = 0; i < values.size(); ++i) std::memcpy(&floats[4 * i], &values[i], sizeof(T));
        }
        return used_quantization_ = true, accessor;
      }
      if (name.starts_with("TEXCOORD") && all_in_range(values, 0.0f, 1.0f))
        return add_packed(unorm<uint16_t>(values), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, type, true);
      if (name == "COLOR_0" && all_in_range(values, 0.0f, 1.0f))
        return add_packed(unorm<uint8_t>(values), TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, type, true);
    }
    return add_accessor(values, TINYGLTF_COMPONENT_TYPE_FLOAT, type, array);
  }

  // UV set `set`: on its box where -q gave it one, else as add_float_stream stores it.
  int add_uv_stream(const std::vector<float2>& uvs, size_t set, const StreamCoding& coding) {
    if (coding.quantize && coding.uv_boxes && (*coding.uv_boxes)[set]) {
      const UvBox& box = *(*coding.uv_boxes)[set];
      return add_packed(pack_components<uint16_t>(uvs, [&box](float x, size_t c) {
                          return std::lround(std::clamp((double(x) - box.offset[c]) / box.scale[c], 0.0, 1.0) * 65535.0);
                        }),
                        TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC2, true);
    }
    return add_float_stream(uvs, TINYGLTF_TYPE_VEC2, "TEXCOORD", coding);
  }

  // Positions: floats with their bounds, or on the grid in unsigned shorts.
  int add_positions(const std::vector<float3>& positions, const PositionGrid* grid) {
    if (!grid) {
      const int index = add_accessor(positions, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
      set_float_bounds(index, positions);
      return index;
    }
    used_quantization_ = true;
    return add_packed(pack_components<uint16_t>(positions, grid_code(*grid)), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC3,
                      false, true);
  }

  // A morph target's position displacements: floats, or in grid steps (shorts, or floats where a
  // displacement is too long for a short).
  int add_displacements(const std::vector<float3>& d, const PositionGrid* grid) {
    if (!grid) {
      const int index = add_accessor(d, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
      set_float_bounds(index, d);
      return index;
    }
    const double step = grid->scale;
    const float* f = reinterpret_cast<const float*>(d.data());
    used_quantization_ = true;  // (a float target on a grid: its mesh's positions need the extension)
    if (std::all_of(f, f + 3 * d.size(), [step](float x) { return std::fabs(x / step) <= 32767.0; }))
      return add_packed(pack_components<int16_t>(d, [step](float x, size_t) { return std::lround(x / step); }),
                        TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_TYPE_VEC3, false, true);
    std::vector<float3> steps(d.size());
    for (size_t v = 0; v < d.size(); ++v) steps[v] = {float(d[v].x / step), float(d[v].y / step), float(d[v].z / step)};
    return add_displacements(steps, nullptr);
  }

  // A morph target's normal or tangent displacements. Quantized, in the normals' own integers, where
  // they fit the range (a flipped normal moves by up to 2).
  int add_direction_offsets(const std::vector<float3>& d, const StreamCoding& coding) {
    if (coding.quantize && all_in_range(d, -1.0f, 1.0f)) {
      const auto [packed, component] = snorm_directions(d, coding.normal_bits);
      return used_quantization_ = true, add_packed(packed, component, TINYGLTF_TYPE_VEC3, true);
    }
    return add_accessor(d, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
  }

  // Appends the Mesh's streams and indices; returns nothing, fills the primitive's references.
  void add_geometry(const Mesh& mesh, const std::vector<MorphTarget>& targets, tg::Primitive& prim, const StreamCoding& coding) {
    const int array = TINYGLTF_TARGET_ARRAY_BUFFER;
    prim.attributes["POSITION"] = add_positions(mesh.positions, coding.grid);
    if (!mesh.normals.empty()) prim.attributes["NORMAL"] = add_float_stream(mesh.normals, TINYGLTF_TYPE_VEC3, "NORMAL", coding);
    if (!mesh.tangents.empty()) prim.attributes["TANGENT"] = add_float_stream(mesh.tangents, TINYGLTF_TYPE_VEC4, "TANGENT", coding);
    for (size_t k = 0; k < max_uv_sets; ++k)
      if (!mesh.uvs[k].empty()) prim.attributes["TEXCOORD_" + str(k)] = add_uv_stream(mesh.uvs[k], k, coding);
    if (!mesh.colors.empty()) prim.attributes["COLOR_0"] = add_float_stream(mesh.colors, TINYGLTF_TYPE_VEC4, "COLOR_0", coding);
    const bool byte_joints = io::joints_fit_bytes(mesh);
    const auto add_joints = [&](const std::vector<ushort4>& joints) {
      if (!byte_joints) return add_accessor(joints, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_VEC4, array);
      std::vector<std::array<uint8_t, 4>> narrow(joints.size());
      for (size_t v = 0; v < joints.size(); ++v)
        for (int k = 0; k < 4; ++k) narrow[v][size_t(k)] = uint8_t(joints[v][size_t(k)]);
      return add_accessor(narrow, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, array);
    };
    if (coding.quantize && !mesh.weights.empty()) {
      const auto packed = unorm8_weights(mesh.weights, mesh.weights1);
      // A joint whose weight rounded to zero becomes joint 0, as glTF asks of unused joints.
      const std::vector<ushort4>* joints[2] = {&mesh.joints, &mesh.joints1};
      for (size_t set = 0; set < 2; ++set) {
        if (packed[set].empty()) continue;
        std::vector<ushort4> used = *joints[set];
        for (size_t v = 0; v < used.size(); ++v)
          for (size_t k = 0; k < 4; ++k)
            if (4 * v + k < packed[set].size() && packed[set][4 * v + k] == 0) used[v][k] = 0;
        if (!used.empty()) prim.attributes["JOINTS_" + str(set)] = add_joints(used);
        prim.attributes["WEIGHTS_" + str(set)] = add_packed(packed[set], TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, true);
      }
    } else {
      const auto weights = normalized_float_weights(mesh.weights, mesh.weights1);
      if (!mesh.joints.empty()) prim.attributes["JOINTS_0"] = add_joints(mesh.joints);
      if (!weights[0].empty())
        prim.attributes["WEIGHTS_0"] = add_accessor(weights[0], TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, array);
      if (!mesh.joints1.empty()) prim.attributes["JOINTS_1"] = add_joints(mesh.joints1);
      if (!weights[1].empty())
        prim.attributes["WEIGHTS_1"] = add_accessor(weights[1], TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, array);
    }
    if (prim.targets.empty()) add_targets(mesh, targets, prim, coding);
    add_indices(mesh, prim);
  }

  // KHR_draco_mesh_compression: the vertex streams and indices as one Draco stream
  // (io::encode_draco), its accessors without a bufferView. Streams outside it must follow the
  // decoded vertices: lodkit's morph targets are gathered here; `outside` says whether the caller
  // has more it gathers (slots of -1 on `prim`, or none yet). The decoded points' source vertices
  // are returned (empty when they are the mesh's own, in order). Under Draco the writer gathers
  // every source stream it keeps (rebuild_geometry), so none is left on `prim` as it was. On -q's
  // grid (`coding`), the positions go into the stream as their grid coordinates, exactly, and the
  // morph targets are stored as -q stores them; Draco quantizes the other streams either way.
  std::vector<uint32_t> add_draco_geometry(const Mesh& mesh, const std::vector<MorphTarget>& targets, tg::Primitive& prim,
                                           const io::DracoBits& bits, bool outside, const StreamCoding& coding) {
    for_each_unmodelled_stream(prim, [&](int, const std::string& semantic, int index) {
      if (index >= 0) throw_internal("Draco: the source's " + semantic + " stream would not follow the renumbered vertices");
    });
    const bool track_points = outside || !targets.empty() || !prim.targets.empty();
    std::vector<uint16_t> grid_positions;
    if (coding.grid) {
      const auto code = grid_code(*coding.grid);
      grid_positions.reserve(3 * mesh.vertex_count());
      for (const float3& p : mesh.positions)
        for (const auto& [x, c] : {std::pair{p.x, 0}, std::pair{p.y, 1}, std::pair{p.z, 2}}) grid_positions.push_back(uint16_t(code(x, size_t(c))));
    }
    std::optional<io::DracoPrimitive> encoded = io::encode_draco(mesh, bits, track_points, grid_positions);
    if (!encoded) {
      ++report_.draco_plain;
      add_geometry(mesh, targets, prim, coding);  // (libdraco cannot take it)
      return {};
    }
    ++(encoded->sequential ? report_.draco_sequential : report_.draco_edgebreaker);
    used_quantization_ = used_quantization_ || coding.grid;
    const io::DracoPrimitive& d = *encoded;
    const int view = add_view(d.bytes.data(), d.bytes.size(), 0);
    tg::Value::Object ids;
    for (const auto& [semantic, a] : d.attributes) {
      tg::Accessor acc;
      acc.componentType = a.component_type;
      acc.type = a.type;
      acc.count = d.points;
      if (semantic == "POSITION") {
        acc.minValues = {d.position_min.x, d.position_min.y, d.position_min.z};
        acc.maxValues = {d.position_max.x, d.position_max.y, d.position_max.z};
      }
      model_.accessors.push_back(std::move(acc));
      prim.attributes[semantic] = int(model_.accessors.size() - 1);
      ids[semantic] = tg::Value(int(a.unique_id));
    }
    tg::Accessor indices;
    // (16-bit while no index can be 65535, a primitive restart to some readers, as add_indices.)
    indices.componentType = d.points <= 65535 ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    indices.type = TINYGLTF_TYPE_SCALAR;
    indices.count = d.triangles * 3;
    model_.accessors.push_back(std::move(indices));
    prim.indices = int(model_.accessors.size() - 1);
    prim.mode = TINYGLTF_MODE_TRIANGLES;  // (a source's strip or fan is a list now)
    tg::Value::Object ext;
    ext["bufferView"] = tg::Value(view);
    ext["attributes"] = tg::Value(std::move(ids));
    prim.extensions[io::draco_extension] = tg::Value(std::move(ext));
    used_draco_ = true;
    if (!prim.targets.empty()) return std::move(encoded->point_source);  // (the caller's, as in add_geometry)
    if (d.point_source.empty()) {
      add_targets(mesh, targets, prim, coding);
      return {};
    }
    std::vector<MorphTarget> moved(targets.size());
    for (size_t k = 0; k < targets.size(); ++k)
      for (const auto stream : morph_streams)
        if (!(targets[k].*stream).empty())
          for (const uint32_t v : d.point_source) (moved[k].*stream).push_back((targets[k].*stream)[v]);
    add_targets(mesh, moved, prim, coding);
    return std::move(encoded->point_source);
  }
  bool used_draco() const { return used_draco_; }
  const WriteReport& report() const { return report_; }

  // Morph targets of `mesh`'s vertices.
  void add_targets(const Mesh& mesh, const std::vector<MorphTarget>& targets, tg::Primitive& prim, const StreamCoding& coding) {
    for (const MorphTarget& target : targets) {
      std::map<std::string, int> attributes;
      attributes["POSITION"] = add_displacements(target.positions, coding.grid);
      // A displacement of a stream the mesh does not have would be invalid: it has none to move.
      if (!target.normals.empty() && !mesh.normals.empty()) attributes["NORMAL"] = add_direction_offsets(target.normals, coding);
      if (!target.tangents.empty() && !mesh.tangents.empty()) attributes["TANGENT"] = add_direction_offsets(target.tangents, coding);
      prim.targets.push_back(std::move(attributes));
    }
  }

  // The index buffer only (a primitive reusing another's vertex accessors).
  void add_indices(const Mesh& mesh, tg::Primitive& prim) {
    const size_t n = mesh.vertex_count();
    // 16-bit indices while no index can be 65535, which readers may take for a primitive restart.
    const int elements = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
    if (n <= 65535) {
      std::vector<uint16_t> small(mesh.indices.begin(), mesh.indices.end());
      prim.indices = add_accessor(small, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, elements);
    } else {
      prim.indices = add_accessor(mesh.indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, elements);
    }
    prim.mode = TINYGLTF_MODE_TRIANGLES;
  }

  // An accessor's min and max (glTF requires them of a POSITION, a target's too).
  template <class T>
  void set_float_bounds(int index, const std::vector<T>& values) {
    constexpr size_t n = sizeof(T) / sizeof(float);
    std::vector<double> low(n, 0.0), high(n, 0.0);
    for (size_t v = 0; v < values.size(); ++v) {
      float c[n];
      std::memcpy(c, &values[v], sizeof c);
      for (size_t k = 0; k < n; ++k) low[k] = v ? std::min(low[k], double(c[k])) : c[k], high[k] = v ? std::max(high[k], double(c[k])) : c[k];
    }
    model_.accessors[size_t(index)].minValues = std::move(low);
    model_.accessors[size_t(index)].maxValues = std::move(high);
  }

 private:
  tg::Model& model_;
  std::vector<uint8_t>& bin_;
  bool used_quantization_ = false;
  bool used_draco_ = false;
  WriteReport report_;  // its Draco counts
};

// A Mesh the writer can turn into valid accessors: streams sized, indices in range, positions finite.
void check_writable(const Mesh& mesh, size_t primitive) {
  const std::string where = "cannot write glTF: scene primitive " + str(primitive) + ": ";
  const size_t n = mesh.vertex_count();
  auto sized = [&](size_t size, const char* what) {
    if (size != 0 && size != n) throw_usage(where + what + " has " + str(size) + " entries for " + str(n) + " vertices");
  };
  sized(mesh.normals.size(), "normals");
  sized(mesh.tangents.size(), "tangents");
  for (const auto& uv : mesh.uvs) sized(uv.size(), "uvs");
  sized(mesh.colors.size(), "colors");
  sized(mesh.joints.size(), "joints");
  sized(mesh.weights.size(), "weights");
  sized(mesh.joints1.size(), "second-set joints");
  sized(mesh.weights1.size(), "second-set weights");
  if (!mesh.joints1.empty() && mesh.joints.empty()) throw_usage(where + "a second set of joints needs the first");
  if (n > std::numeric_limits<uint32_t>::max()) throw_usage(where + "more than 2^32 vertices");
  if (mesh.indices.size() % 3 != 0) throw_usage(where + "index count is not a multiple of 3");
  for (uint32_t i : mesh.indices)
    if (i >= n) throw_usage(where + "index " + str(i) + " out of range for " + str(n) + " vertices");
  for (const float3& p : mesh.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) throw_usage(where + "non-finite position");
}

// Calls f(int& index) on each accessor index (below accessor_count) of a node's
// EXT_mesh_gpu_instancing and stores what f leaves.
template <class F>
void for_each_instancing_accessor(tg::Node& node, size_t accessor_count, F&& f) {
  auto found = node.extensions.find(gpu_instancing);
  if (found == node.extensions.end() || !found->second.IsObject() || !found->second.Has("attributes")) return;
  tg::Value::Object ext = found->second.Get<tg::Value::Object>();
  tg::Value::Object attributes = ext["attributes"].Get<tg::Value::Object>();
  for (auto& entry : attributes) {
    int index = entry.second.IsInt() ? entry.second.Get<int>() : -1;
    if (index < 0 || size_t(index) >= accessor_count) continue;  // the reader refuses those
    f(index);
    entry.second = tg::Value(index);
  }
  ext["attributes"] = tg::Value(std::move(attributes));
  found->second = tg::Value(std::move(ext));
}

// Which meshes of the rebuilt document take positions on the grid: meshes whose every primitive
// lodkit writes (`regenerated[m]`: a point or line primitive kept as it was stays in mesh space),
// whose GPU instances the reader decoded (Scene::nodes, to take the grid in their transforms) and
// are not skinned, and whose skins serve only such meshes (a skin takes the grid in its inverse
// bind matrices, which must be plain floats).
std::vector<bool> grid_meshes(const tg::Model& model, const Scene& scene, const std::vector<bool>& regenerated) {
  std::vector<bool> on = regenerated;
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tg::Node& node = model.nodes[n];
    if (node.mesh < 0 || !node.extensions.count(gpu_instancing)) continue;
    const bool read = n < scene.nodes.size() && !scene.nodes[n].gpu_instances.empty() && node.extensions.at(gpu_instancing).IsObject() &&
                      node.extensions.at(gpu_instancing).Has("attributes") && node.extensions.at(gpu_instancing).Get("attributes").IsObject();
    if (!read || node.skin >= 0) on[size_t(node.mesh)] = false;
  }
  std::vector<bool> skin_ok(model.skins.size(), true);
  for (size_t s = 0; s < model.skins.size(); ++s) {
    const int ibm = model.skins[s].inverseBindMatrices;
    if (ibm < 0) continue;
    const tg::Accessor& acc = model.accessors[size_t(ibm)];
    skin_ok[s] = acc.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && acc.type == TINYGLTF_TYPE_MAT4 && !acc.sparse.isSparse &&
                 acc.bufferView >= 0;
  }
  for (bool changed = true; changed;) {  // a mesh off the grid takes its skins off, and theirs the other meshes
    changed = false;
    for (const tg::Node& node : model.nodes) {
      if (node.mesh < 0 || node.skin < 0 || size_t(node.skin) >= skin_ok.size()) continue;
      const size_t m = size_t(node.mesh), s = size_t(node.skin);
      if (on[m] != skin_ok[s]) on[m] = skin_ok[s] = false, changed = true;
    }
  }
  return on;
}

PositionGrid position_grid(const std::vector<const Mesh*>& meshes, int bits) {
  PositionGrid grid;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const Mesh* mesh : meshes)
    for (const float3& p : mesh->positions) {
      const double c[3] = {p.x, p.y, p.z};
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c[k]), hi[k] = std::max(hi[k], c[k]);
    }
  if (!(lo[0] <= hi[0])) return grid;  // no positions
  grid.top = double((uint32_t(1) << bits) - 1);
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  for (int k = 0; k < 3; ++k) grid.offset[k] = lo[k];
  grid.scale = extent > 0 ? extent / grid.top : 1.0;
  return grid;
}

// Per mesh, whether every transform that would take `grid` stays well inside the float range
// (1e37), bounded without applying it: a node's (or instance's, or inverse bind matrix's)
// translation grows by at most sqrt(3) times its largest linear entry times the largest offset
// coordinate, its linear part by the grid's scale. Fuzzing found instances pushed past it.
std::vector<bool> grid_transforms_fit(const tg::Model& model, const Scene& scene, const Document& source,
                                      const std::vector<bool>& on_grid, const PositionGrid& grid) {
  constexpr double limit = 1e37;
  const double o = std::max({std::fabs(grid.offset[0]), std::fabs(grid.offset[1]), std::fabs(grid.offset[2])});
  std::vector<bool> fits(on_grid.size(), grid.scale <= limit);
  // A transform of largest translation coordinate t and largest linear entry l.
  const auto fit = [&](double t, double l) { return t + 2 * l * o <= limit && l * grid.scale <= limit; };
  const auto largest = [](auto begin, auto end) {
    double x = 0;
    for (auto it = begin; it != end; ++it) x = std::max(x, std::fabs(double(*it)));
    return x;
  };
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const tg::Node& node = model.nodes[n];
    if (node.mesh < 0 || !on_grid[size_t(node.mesh)]) continue;
    bool ok = true;
    if (node.skin >= 0 && size_t(node.skin) < model.skins.size()) {
      if (const int ibm = model.skins[size_t(node.skin)].inverseBindMatrices; ibm >= 0)
        for (const auto& m : source.decode_floats<std::array<float, 16>>(ibm))
          ok = ok && fit(largest(m.begin() + 12, m.begin() + 15), largest(m.begin(), m.begin() + 12));
    } else if (node.extensions.count(gpu_instancing) && n < scene.nodes.size()) {
      for (const Node::GpuInstance& g : scene.nodes[n].gpu_instances) {
        const float t[3] = {g.translation.x, g.translation.y, g.translation.z}, l[3] = {g.scale.x, g.scale.y, g.scale.z};
        ok = ok && fit(largest(t, t + 3), largest(l, l + 3));
      }
    } else if (node.matrix.size() == 16) {
      ok = fit(largest(node.matrix.begin() + 12, node.matrix.begin() + 15), largest(node.matrix.begin(), node.matrix.begin() + 12));
    } else {
      ok = fit(largest(node.translation.begin(), node.translation.end()),
               node.scale.empty() ? 1.0 : largest(node.scale.begin(), node.scale.end()));
    }
    if (!ok) fits[size_t(node.mesh)] = false;
  }
  return fits;
}

// The translation of T R S D, for D the grid's dequantization: T + R (S o), o the grid's offset
// (the scale becomes S s).
core::vec3d place_grid_offset(const core::vec3d& t, const double (&r)[4], const core::vec3d& scale, const PositionGrid& grid) {
  const double* o = grid.offset;
  const core::vec3d v{scale.x * o[0], scale.y * o[1], scale.z * o[2]}, q{r[0], r[1], r[2]};
  // v + 2 w (q x v) + 2 q x (q x v), q = (x, y, z) and w its real part.
  const core::vec3d c1 = core::cross(q, v), c2 = core::cross(q, c1);
  return {t.x + v.x + 2 * r[3] * c1.x + 2 * c2.x, t.y + v.y + 2 * r[3] * c1.y + 2 * c2.y, t.z + v.z + 2 * r[3] * c1.z + 2 * c2.z};
}

// Puts the grid's dequantization where each grid mesh enters its space: every node drawing one
// (in its transform; in a new child node that draws the mesh instead when the node has children, a
// camera or an extension's object such as a light, which must not take the grid, or animated
// translation, rotation or scale, which would overwrite it) and every skin of one (its inverse bind
// matrices, in `bin`).
void place_position_grid(tg::Model& model, std::vector<uint8_t>& bin, BinWriter& writer, const PositionGrid& grid,
                         const std::vector<bool>& on_grid) {
  const double s = grid.scale, *o = grid.offset;
  std::vector<bool> animated(model.nodes.size(), false), skin_on(model.skins.size(), false);
  for (const tg::Animation& anim : model.animations)
    for (const tg::AnimationChannel& ch : anim.channels)
      if (const ChannelTarget t = channel_target(ch);
          t.list == "nodes" && t.index >= 0 && size_t(t.index) < animated.size() && t.property != "weights")
        animated[size_t(t.index)] = true;
  const size_t nodes = model.nodes.size();
  for (size_t n = 0; n < nodes; ++n) {
    if (model.nodes[n].mesh < 0 || !on_grid[size_t(model.nodes[n].mesh)]) continue;
    if (model.nodes[n].skin >= 0) {  // a skinned mesh's node transform does not apply
      skin_on[size_t(model.nodes[n].skin)] = true;
      continue;
    }
    if (model.nodes[n].extensions.count(gpu_instancing)) continue;  // its instances took the grid
    // A camera, a light or another extension's object at the node must not take the grid either.
    const tg::Node& at = model.nodes[n];
    const bool holds_more = at.camera >= 0 || std::any_of(at.extensions.begin(), at.extensions.end(),
                                                          [](const auto& e) { return e.first != "MSFT_lod"; });
    if (!at.children.empty() || animated[n] || holds_more) {
      tg::Node child;
      child.mesh = std::exchange(model.nodes[n].mesh, -1);
      child.weights = std::move(model.nodes[n].weights);
      model.nodes[n].weights.clear();
      child.translation = {o[0], o[1], o[2]};
      child.scale = {s, s, s};
      const int index = int(model.nodes.size());
      model.nodes[n].children.push_back(index);
      for (tg::Animation& anim : model.animations)
        for (tg::AnimationChannel& ch : anim.channels)
          if (const ChannelTarget t = channel_target(ch); t.list == "nodes" && t.index == int(n) && t.property == "weights")
            retarget_channel(ch, "nodes", index);
      model.nodes.push_back(std::move(child));
      continue;
    }
    tg::Node& node = model.nodes[n];
    if (node.matrix.size() == 16) {  // M * D (column-major): the columns scaled, D's offset moved by M
      std::vector<double>& m = node.matrix;
      for (int r = 0; r < 4; ++r) m[12 + r] += m[r] * o[0] + m[4 + r] * o[1] + m[8 + r] * o[2];
      for (size_t c = 0; c < 12; ++c) m[c] *= s;
      continue;
    }
    // T R S D = T' R S' with S' = S s and T' = T + R (S o).
    const std::vector<double> scale = node.scale.size() == 3 ? node.scale : std::vector<double>{1, 1, 1};
    const std::vector<double> t = node.translation.size() == 3 ? node.translation : std::vector<double>{0, 0, 0};
    const double q[4] = {node.rotation.size() == 4 ? node.rotation[0] : 0, node.rotation.size() == 4 ? node.rotation[1] : 0,
                         node.rotation.size() == 4 ? node.rotation[2] : 0, node.rotation.size() == 4 ? node.rotation[3] : 1};
    const core::vec3d moved = place_grid_offset({t[0], t[1], t[2]}, q, {scale[0], scale[1], scale[2]}, grid);
    node.translation = {moved.x, moved.y, moved.z};
    node.scale = {scale[0] * s, scale[1] * s, scale[2] * s};
  }
  // Inverse bind matrices B become B D: a skinned vertex B p is B D q. In place where every skin
  // sharing the accessor takes the grid (once per accessor); else in a new accessor.
  const auto to_grid = [&](float* m) {
    for (int r = 0; r < 4; ++r) m[12 + r] = float(m[12 + r] + m[r] * o[0] + m[4 + r] * o[1] + m[8 + r] * o[2]);
    for (int c = 0; c < 12; ++c) m[c] = float(m[c] * s);
  };
  std::map<int, bool> shared_on;  // IBM accessor -> whether every skin using it takes the grid
  for (size_t k = 0; k < model.skins.size(); ++k)
    if (const int a = model.skins[k].inverseBindMatrices; a >= 0) {
      auto [it, inserted] = shared_on.try_emplace(a, true);
      it->second = it->second && skin_on[k];
    }
  std::vector<int> done;
  for (size_t k = 0; k < model.skins.size(); ++k) {
    if (!skin_on[k]) continue;
    tg::Skin& skin = model.skins[k];
    const size_t joints = skin.joints.size();
    if (const int a = skin.inverseBindMatrices; a >= 0) {
      const tg::Accessor& acc = model.accessors[size_t(a)];
      const tg::BufferView& view = model.bufferViews[size_t(acc.bufferView)];
      const size_t stride = view.byteStride ? view.byteStride : 64;
      uint8_t* first = bin.data() + view.byteOffset + acc.byteOffset;
      if (shared_on[a]) {
        if (std::find(done.begin(), done.end(), a) != done.end()) continue;
        done.push_back(a);
        for (size_t j = 0; j < acc.count; ++j) {
          float m[16];
          std::memcpy(m, first + j * stride, sizeof m);
          to_grid(m);
          std::memcpy(first + j * stride, m, sizeof m);
        }
        continue;
      }
      std::vector<float> matrices(16 * acc.count);
      for (size_t j = 0; j < acc.count; ++j) std::memcpy(&matrices[16 * j], first + j * stride, 64), to_grid(&matrices[16 * j]);
      skin.inverseBindMatrices = writer.add_accessor(matrices, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4, 0);
      model.accessors.back().count = acc.count;
      continue;
    }
    std::vector<float> matrices(16 * joints, 0.0f);  // no accessor: identities
    for (size_t j = 0; j < joints; ++j) {
      for (int d = 0; d < 4; ++d) matrices[16 * j + 5 * size_t(d)] = 1.0f;
      to_grid(&matrices[16 * j]);
    }
    skin.inverseBindMatrices = writer.add_accessor(matrices, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4, 0);
    model.accessors.back().count = joints;
  }
}

const char* interpolation_name(Interpolation i) {
  return i == Interpolation::step ? "STEP" : i == Interpolation::linear ? "LINEAR" : "CUBICSPLINE";
}

// Appends `values` to `data`, which becomes the model's buffer `buffer` (pushed by the caller once
// done), as a new float accessor of `type`; with its bounds when `bounds` (sampler inputs need them).
int append_float_accessor(tg::Model& model, tg::Buffer& data, int buffer, const std::vector<float>& values, int type, bool bounds) {
  data.data.resize((data.data.size() + 3) & ~size_t(3), 0);
  tg::BufferView view;
  view.buffer = buffer;
  view.byteOffset = data.data.size();
  view.byteLength = values.size() * sizeof(float);
  const auto* bytes = reinterpret_cast<const unsigned char*>(values.data());
  data.data.insert(data.data.end(), bytes, bytes + view.byteLength);
  tg::Accessor acc;
  acc.bufferView = int(model.bufferViews.size());
  acc.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  acc.type = type;
  const size_t components = size_t(tg::GetNumComponentsInType(uint32_t(type)));
  acc.count = values.size() / components;
  if (bounds && acc.count) {
    acc.minValues.assign(components, std::numeric_limits<double>::infinity());
    acc.maxValues.assign(components, -std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < values.size(); ++i) {
      acc.minValues[i % components] = std::min(acc.minValues[i % components], double(values[i]));
      acc.maxValues[i % components] = std::max(acc.maxValues[i % components], double(values[i]));
    }
  }
  model.bufferViews.push_back(std::move(view));
  model.accessors.push_back(std::move(acc));
  return int(model.accessors.size() - 1);
}

// Morph weights for the targets each mesh is written with (`targets[m]`, when not 0), in a node's
// weights and in a copy of each sampler that drives them: a node whose mesh has more than its
// weights and clips give (lodkit lod --morph puts a level's geomorph after the source's blend
// shapes) takes 0 for the others; one whose mesh has fewer (Primitive::source_target_count) loses
// the last ones. The copies' outputs go into a new buffer of the model, repacked with the rest.
void fit_morph_weights(tg::Model& model, const Document& source, const std::vector<size_t>& targets) {
  const auto wanted = [&](int node) -> size_t {
    if (node < 0 || size_t(node) >= model.nodes.size()) return 0;
    const int mesh = model.nodes[size_t(node)].mesh;
    return mesh >= 0 && size_t(mesh) < targets.size() ? targets[size_t(mesh)] : 0;
  };
  for (size_t n = 0; n < model.nodes.size(); ++n)
    if (std::vector<double>& w = model.nodes[n].weights; !w.empty() && wanted(int(n)) > 0) w.resize(wanted(int(n)), 0.0);
  tg::Buffer padded;
  for (tg::Animation& anim : model.animations) {
    std::map<std::pair<int, size_t>, int> copies;  // (sampler, targets) -> its padded copy
    for (tg::AnimationChannel& ch : anim.channels) {
      // A node's weights, or a mesh's (a KHR_animation_pointer "/meshes/M/weights").
      const ChannelTarget t = channel_target(ch);
      if (t.property != "weights" || t.index < 0) continue;
      const size_t want = t.list == "nodes" ? wanted(t.index) : size_t(t.index) < targets.size() ? targets[size_t(t.index)] : 0;
      if (want == 0 || ch.sampler < 0 || size_t(ch.sampler) >= anim.samplers.size()) continue;
      const tg::AnimationSampler sampler = anim.samplers[size_t(ch.sampler)];  // (a copy: samplers grow below)
      if (sampler.input < 0 || sampler.output < 0) continue;
      const tg::Accessor& out = source.accessor(sampler.output);
      const size_t keys = source.accessor(sampler.input).count * (sampler.interpolation == "CUBICSPLINE" ? 3 : 1);
      if (out.type != TINYGLTF_TYPE_SCALAR || keys == 0 || out.count % keys != 0 || out.count / keys == want) continue;
      const auto [copy, fresh] = copies.try_emplace({ch.sampler, want}, int(anim.samplers.size()));
      if (fresh) {
        // Each key's group (its values, or a cubic spline's tangents) followed by zeros, or cut.
        const std::vector<float> values = source.decode_floats<float>(sampler.output);
        const size_t given = out.count / keys;
        std::vector<float> grown(keys * want, 0.0f);
        for (size_t k = 0; k < keys; ++k)
          std::copy_n(values.begin() + ptrdiff_t(k * given), std::min(given, want), grown.begin() + ptrdiff_t(k * want));
        tg::AnimationSampler grown_sampler = sampler;
        grown_sampler.output = append_float_accessor(model, padded, int(model.buffers.size()), grown, TINYGLTF_TYPE_SCALAR, false);
        anim.samplers.push_back(std::move(grown_sampler));
      }
      ch.sampler = copy->second;
    }
  }
  if (!padded.data.empty()) model.buffers.push_back(std::move(padded));
}

// ---- -q: animation keys ---------------------------------------------------------------------------

// How far -q lets a reduced curve stray from a key it drops, per animated node: a world-space
// distance `reach`, `error` (WriteOptions::animation_error, 2^-12 by default) of the scene's extent
// at rest (the largest side of its bounding box; 0.45 mm on a 1.85 m character). Every bound below
// is given at the default and scales with `error`. A translation may stray by `reach` in world space (in its parent's
// units: divided by the parent's scale); a rotation by reach / lever radians, lever the node's
// largest distance to a descendant node plus an eighth of the extent (the geometry beyond the last
// joints), at most 2^-7 rad, so that what the node carries moves by about `reach` (as animation
// compressors judge rotations by their effect on virtual vertices): a hip takes 2^-12 rad where an
// ankle takes 4x that. Scales, and nodes lodkit did not read (or a scene without meshes):
// 2^-14 of the track's largest component, 2^-11 rad for rotations.
struct KeyTolerances {
  double rotation = 1.0 / 2048, relative = 1.0 / 16384;
  // Per node; empty: the defaults. node_weights < 0: unknown (the default).
  std::vector<double> node_translation, node_rotation, node_weights;
  double of(const std::string& path, int node, double largest) const {
    const bool known = node >= 0 && size_t(node) < node_rotation.size();
    if (path == "rotation") return known ? node_rotation[size_t(node)] : rotation;
    if (path == "translation" && known) return node_translation[size_t(node)];
    if (path == "weights" && known && node_weights[size_t(node)] >= 0) return node_weights[size_t(node)];
    return relative * largest;
  }
};

KeyTolerances key_tolerances(const Scene& scene, double error) {
  const double factor = error * 4096;  // (a power of two by default: the bounds stay exact)
  KeyTolerances t;
  t.rotation *= factor, t.relative *= factor;
  const double most = factor / 128;  // a rotation's or a weight's largest
  const size_t n = scene.nodes.size();
  const std::vector<io::Matrix> world = io::rest_world_matrices(scene);
  // The scene's box at rest: each primitive's box where a node draws it (a skinned one where its
  // first joint's bind placement puts it).
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < n; ++i) {
    const Node& node = scene.nodes[i];
    if (node.mesh < 0) continue;
    io::Matrix place = world[i];
    if (node.skin >= 0 && size_t(node.skin) < scene.skins.size()) {
      const Skin& skin = scene.skins[size_t(node.skin)];
      if (skin.joints.empty() || skin.inverse_bind_matrices.empty() || skin.joints[0] < 0 || size_t(skin.joints[0]) >= n) continue;
      io::Matrix ibm;
      std::copy(skin.inverse_bind_matrices[0].begin(), skin.inverse_bind_matrices[0].end(), ibm.begin());
      place = io::multiply(world[size_t(skin.joints[0])], ibm);
    }
    for (const Primitive& p : scene.primitives) {
      if (p.gltf_mesh != uint32_t(node.mesh) || p.mesh.positions.empty()) continue;
      float3 a, b;
      bounding_box(p.mesh, a, b);
      for (int corner = 0; corner < 8; ++corner) {
        const double v[3] = {corner & 1 ? b.x : a.x, corner & 2 ? b.y : a.y, corner & 4 ? b.z : a.z};
        for (size_t r = 0; r < 3; ++r) {
          const double x = place[r] * v[0] + place[4 + r] * v[1] + place[8 + r] * v[2] + place[12 + r];
          lo[r] = std::min(lo[r], x), hi[r] = std::max(hi[r], x);
        }
      }
    }
  }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  if (!(extent > 0) || !std::isfinite(extent)) return t;
  const double reach = extent * error;
  std::vector<double> lever(n, 0);
  for (size_t d = 0; d < n; ++d) {  // each node lengthens its ancestors' levers
    size_t steps = 0;
    for (int32_t a = scene.nodes[d].parent; a >= 0 && size_t(a) < n && steps < n; a = scene.nodes[size_t(a)].parent, ++steps)
      lever[size_t(a)] = std::max(lever[size_t(a)], std::hypot(world[d][12] - world[size_t(a)][12], world[d][13] - world[size_t(a)][13],
                                                               world[d][14] - world[size_t(a)][14]));
  }
  // Per glTF mesh: its morph targets' longest displacement (from the POSITION accessors' bounds,
  // which glTF requires, and lodkit's own targets); -1 where a bound is missing.
  std::vector<double> displacement;
  const auto grow = [&](uint32_t mesh, double length) {
    if (mesh >= displacement.size()) displacement.resize(size_t(mesh) + 1, 0);
    if (displacement[mesh] >= 0) displacement[mesh] = length < 0 ? -1 : std::max(displacement[mesh], length);
  };
  for (const Primitive& p : scene.primitives) {
    for (const MorphTarget& target : p.targets)
      for (const float3& d : target.positions) grow(p.gltf_mesh, std::hypot(d.x, d.y, d.z));
    if (!scene.source || p.gltf_mesh >= scene.source->model.meshes.size() ||
        p.gltf_primitive >= scene.source->model.meshes[p.gltf_mesh].primitives.size())
      continue;
    for (const auto& target : scene.source->model.meshes[p.gltf_mesh].primitives[p.gltf_primitive].targets) {
      const auto position = target.find("POSITION");
      if (position == target.end()) continue;
      const tg::Accessor* acc = position->second >= 0 && size_t(position->second) < scene.source->model.accessors.size()
                                    ? &scene.source->model.accessors[size_t(position->second)]
                                    : nullptr;
      if (!acc || acc->minValues.size() != 3 || acc->maxValues.size() != 3) {
        grow(p.gltf_mesh, -1);
        continue;
      }
      double sum = 0;
      for (size_t c = 0; c < 3; ++c) sum += std::pow(std::max(std::fabs(acc->minValues[c]), std::fabs(acc->maxValues[c])), 2);
      grow(p.gltf_mesh, std::sqrt(sum));
    }
  }
  // A matrix's largest scale: the longest of its linear part's columns.
  const auto scale_of = [](const io::Matrix& m) {
    return std::max({std::hypot(m[0], m[1], m[2]), std::hypot(m[4], m[5], m[6]), std::hypot(m[8], m[9], m[10])});
  };
  t.node_translation.assign(n, reach);
  t.node_rotation.assign(n, 0);
  t.node_weights.assign(n, -1);
  for (size_t i = 0; i < n; ++i) {
    t.node_rotation[i] = std::min(most, reach / (lever[i] + extent / 8));
    // Morph weights: a weight's error moves a vertex by at most that times the longest displacement
    // (in world units: times the node's scale).
    if (const int32_t mesh = scene.nodes[i].mesh; mesh >= 0 && size_t(mesh) < displacement.size() && displacement[size_t(mesh)] >= 0) {
      const double moved = displacement[size_t(mesh)] * scale_of(world[i]);
      t.node_weights[i] = moved > 0 && std::isfinite(moved) ? std::min(most, reach / moved) : most;
    }
    const int32_t parent = scene.nodes[i].parent;
    if (parent < 0 || size_t(parent) >= n) continue;
    const double scale = scale_of(world[size_t(parent)]);
    if (scale > 0 && std::isfinite(scale)) t.node_translation[i] = reach / scale;
  }
  return t;
}

// A sampler's keys: times, and values (`components` per key).
struct Keys {
  std::vector<float> times, values;
};

// A LINEAR sampler's keys, and how far a reduced curve may stray from them: the largest component
// difference, or for rotations the angle to the slerp, in radians.
struct KeyCurve {
  const std::vector<float>& times;
  const std::vector<float>& values;
  size_t components;
  bool rotation;
  double tolerance;

  const float* key(size_t k) const { return values.data() + k * components; }
  static float4 quaternion(const float* q) { return core::normalized({q[0], q[1], q[2], q[3]}); }
  // Whether the keys first..last-1 that lie strictly between t0 and t1 are within the tolerance of
  // the interpolation from (t0, va) to (t1, vb).
  bool fits(size_t first, size_t last, double t0, const float* va, double t1, const float* vb) const {
    const double span = t1 - t0;
    for (size_t k = first; k < last; ++k) {
      if (!(times[k] > t0 && times[k] < t1)) continue;
      const double s = (times[k] - t0) / span;
      if (rotation) {
        if (core::rotation_angle(core::slerp(quaternion(va), quaternion(vb), float(s)), quaternion(key(k))) > tolerance) return false;
        continue;
      }
      for (size_t c = 0; c < components; ++c)
        if (std::fabs(double(va[c]) + s * (double(vb[c]) - va[c]) - key(k)[c]) > tolerance) return false;
    }
    return true;
  }
};

// The keys -q keeps of a LINEAR or STEP sampler (the first and the last always, at their times, so
// the clip keeps its length). STEP: the keys whose value differs from the one before. LINEAR:
// greedily, each kept key as far after the previous one as every key between lies within
// `tolerance` of the two's interpolation (KeyCurve), found by doubling, then bisection (a run of r
// keys costs O(r log r) checks). A kept key between the first and the last moves to the nearest
// multiple of a power of two, 2^-8 s or less and at most a quarter of the shortest key interval,
// with the curve's value there: the reduced curve's corners stay on the curve, and the times code in
// few mantissa bits (irregular times otherwise cost most of a reduced clip). Keys whose times do not
// increase are all kept.
Keys reduce_keys(const std::vector<float>& times, const std::vector<float>& values, size_t components, bool rotation, bool step,
                 double tolerance) {
  const size_t n = times.size();
  const KeyCurve curve{times, values, components, rotation, tolerance};
  const auto key = [&](size_t k) { return curve.key(k); };
  Keys out;
  const auto take = [&](size_t k) {
    out.times.push_back(times[k]);
    out.values.insert(out.values.end(), key(k), key(k) + components);
  };
  bool increasing = true;
  for (size_t k = 1; k < n; ++k) increasing = increasing && times[k] > times[k - 1];
  if (n <= 2 || !increasing) {
    for (size_t k = 0; k < n; ++k) take(k);
    return out;
  }
  if (step) {
    for (size_t k = 0; k < n; ++k)
      if (k == 0 || k + 1 == n || !std::equal(key(k), key(k) + components, key(k - 1))) take(k);
    return out;
  }
  // The lattice, where its multiples stay exact floats.
  double gap = INFINITY, reach = 0;
  for (size_t k = 1; k < n; ++k) gap = std::min(gap, double(times[k]) - times[k - 1]);
  for (const float t : times) reach = std::max(reach, std::fabs(double(t)));
  double lattice = std::min(std::exp2(std::floor(std::log2(gap / 4))), 1.0 / 256);
  if (!(lattice >= 0x1p-20) || reach / lattice >= 0x1p23) lattice = 0;
  // Each key's corners: 0 at the key, 1 at its snapped time with the curve's value there (the first
  // and last keys, or a key whose snapped time leaves its neighbours' interval: as corner 0).
  std::vector<double> corner_time(2 * n);
  std::vector<float> corner_value(2 * n * components);
  for (size_t k = 0; k < n; ++k)
    for (size_t snap = 0; snap < 2; ++snap) {
      double t = times[k];
      size_t from = k, to = k;  // the original keys the corner lies between
      if (snap && lattice > 0 && k > 0 && k + 1 < n) {
        const double snapped = std::round(t / lattice) * lattice;
        if (snapped > times[k - 1] && snapped < times[k + 1]) t = snapped, from = snapped < times[k] ? k - 1 : k, to = from + 1;
      }
      corner_time[2 * k + snap] = t;
      float* v = corner_value.data() + (2 * k + snap) * components;
      const double s = to > from ? (t - times[from]) / (double(times[to]) - times[from]) : 0;
      if (rotation) {
        const float4 q = core::slerp(KeyCurve::quaternion(key(from)), KeyCurve::quaternion(key(to)), float(s));
        v[0] = q.x, v[1] = q.y, v[2] = q.z, v[3] = q.w;
      } else {
        for (size_t c = 0; c < components; ++c) v[c] = float(key(from)[c] + s * (double(key(to)[c]) - key(from)[c]));
      }
    }
  // Whether every key strictly between corners a and b lies on their interpolation.
  const auto fits = [&](size_t a, size_t b) {
    return curve.fits(a / 2, b / 2 + 1, corner_time[a], corner_value.data() + a * components, corner_time[b],
                      corner_value.data() + b * components);
  };
  // From corner a, the corner of key j that fits: snapped if it does, else at the key; none: npos.
  // A corner before its key leaves the key to the next segment, so it must reach key j + 1 too
  // (which makes key j + 1's own corner always reachable from any corner of key j).
  const auto reach_corner = [&](size_t a, size_t j) {
    for (const size_t b : {2 * j + 1, 2 * j})
      if (fits(a, b) && (corner_time[b] >= times[j] || fits(b, 2 * (j + 1)))) return b;
    return std::string::npos;
  };
  const auto add = [&](size_t c) {
    out.times.push_back(float(corner_time[c]));
    out.values.insert(out.values.end(), corner_value.begin() + ptrdiff_t(c * components), corner_value.begin() + ptrdiff_t((c + 1) * components));
  };
  add(0);
  for (size_t a = 0; a / 2 + 1 < n;) {
    const size_t i = a / 2;
    size_t good = i + 1, stride = 1, chosen = reach_corner(a, good);
    if (chosen == std::string::npos) chosen = 2 * good;  // (cannot happen: see reach_corner)
    for (size_t c; good + stride < n && (c = reach_corner(a, good + stride)) != std::string::npos; stride *= 2) good += stride, chosen = c;
    for (size_t bad = std::min(good + stride, n); bad - good > 1;) {  // reaches good; not bad, or past the end
      const size_t mid = good + (bad - good) / 2;
      if (const size_t c = reach_corner(a, mid); c != std::string::npos) good = mid, chosen = c;
      else bad = mid;
    }
    if (good + 1 == n) chosen = 2 * good;  // (the last key stays at its time)
    add(chosen);
    a = chosen;
  }
  return out;
}

// The strides s (powers of two, 2 or more) for which every s-th key of a LINEAR sampler, and the
// last, keep its curve within the tolerance, finest first. Such keys keep their times, which the
// samplers of one input that take the same stride share: a baked clip's smooth tracks then cost
// their values alone, where reduce_keys' fewer keys each bring a time of their own.
std::vector<size_t> thinning_strides(const KeyCurve& curve) {
  const size_t n = curve.times.size();
  std::vector<size_t> strides;
  for (size_t k = 1; k < n; ++k)
    if (!(curve.times[k] > curve.times[k - 1])) return strides;
  for (size_t s = 2; n > 2 && s / 2 < n - 1; s *= 2) {
    bool fit = true;
    for (size_t i = 0, j; fit && i + 1 < n; i = j) {
      j = std::min(i + s, n - 1);
      fit = curve.fits(i + 1, j, curve.times[i], curve.key(i), curve.times[j], curve.key(j));
    }
    if (fit) strides.push_back(s);
  }
  return strides;
}

// Every s-th key, and the last.
Keys thin_keys(const KeyCurve& curve, size_t s) {
  Keys out;
  const size_t n = curve.times.size();
  for (size_t k = 0; k < n; k = k + 1 == n ? n : std::min(k + s, n - 1)) {
    out.times.push_back(curve.times[k]);
    out.values.insert(out.values.end(), curve.key(k), curve.key(k) + curve.components);
  }
  return out;
}

// The number of keys thin_keys keeps of n at stride s.
size_t thinned_count(size_t n, size_t s) { return n < 2 ? n : (n - 2) / s + 2; }

// -q: which channels of clip `a` change nothing: every key of a LINEAR or STEP translation,
// rotation or scale holds its node's own value (within the keys' tolerance), and no other clip
// animates that property of that node (playing that clip first would leave its value there).
// None where the clip's other channels would not span its time range (it would get shorter) or
// no channel would be left.
// How many clips animate each property of each node: (node, path) -> clips.
std::map<std::pair<int, std::string>, size_t> animating_clips(const tg::Model& model) {
  std::map<std::pair<int, std::string>, size_t> clips;
  for (const tg::Animation& anim : model.animations) {
    std::set<std::pair<int, std::string>> own;
    for (const tg::AnimationChannel& ch : anim.channels) own.insert({ch.target_node, ch.target_path});
    for (const auto& key : own) ++clips[key];
  }
  return clips;
}

std::vector<bool> still_channels(const tg::Model& model, const Document& source, size_t a, const KeyTolerances& tolerances,
                                 const std::map<std::pair<int, std::string>, size_t>& clips) {
  const tg::Animation& anim = model.animations[a];
  std::vector<bool> still(anim.channels.size(), false);
  // A channel lodkit does not read (an extension's target) may have any sampler: its time range is
  // unknown, so the clip keeps all its channels.
  for (const tg::AnimationChannel& ch : anim.channels)
    if (ch.target_path != "translation" && ch.target_path != "rotation" && ch.target_path != "scale" && ch.target_path != "weights")
      return still;
  const auto span = [&](const tg::AnimationChannel& ch) -> std::pair<float, float> {
    const tg::AnimationSampler& sampler = anim.samplers[size_t(ch.sampler)];
    const std::vector<float> times = source.decode_floats<float>(sampler.input);
    if (times.empty()) return {INFINITY, -INFINITY};
    return {*std::min_element(times.begin(), times.end()), *std::max_element(times.begin(), times.end())};
  };
  for (size_t c = 0; c < anim.channels.size(); ++c) {
    const tg::AnimationChannel& ch = anim.channels[c];
    if (ch.sampler < 0 || size_t(ch.sampler) >= anim.samplers.size() || ch.target_node < 0 ||
        size_t(ch.target_node) >= model.nodes.size() || clips.at({ch.target_node, ch.target_path}) != 1)
      continue;
    const tg::AnimationSampler& sampler = anim.samplers[size_t(ch.sampler)];
    const tg::Node& node = model.nodes[size_t(ch.target_node)];
    const bool rotation = ch.target_path == "rotation";
    if ((!rotation && ch.target_path != "translation" && ch.target_path != "scale") || !node.matrix.empty() ||
        sampler.interpolation == "CUBICSPLINE" || sampler.input < 0 || sampler.output < 0 ||
        size_t(sampler.input) >= model.accessors.size() || size_t(sampler.output) >= model.accessors.size())
      continue;
    const tg::Accessor& out = model.accessors[size_t(sampler.output)];
    if (out.type != (rotation ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3)) continue;
    if (rotation) {
      const float4 rest = node.rotation.size() == 4 ? float4{float(node.rotation[0]), float(node.rotation[1]), float(node.rotation[2]),
                                                             float(node.rotation[3])}
                                                    : float4{0, 0, 0, 1};
      const std::vector<float4> keys = source.decode_floats<float4>(sampler.output, true);
      still[c] = !keys.empty() && std::all_of(keys.begin(), keys.end(), [&](const float4& q) {
        return std::isfinite(q.x + q.y + q.z + q.w) &&
               core::rotation_angle(core::normalized(q), core::normalized(rest)) <= tolerances.of("rotation", ch.target_node, 0);
      });
    } else {
      const std::vector<double>& given = ch.target_path == "scale" ? node.scale : node.translation;
      const double fallback = ch.target_path == "scale" ? 1 : 0, rest[3] = {given.size() == 3 ? given[0] : fallback,
                                                                              given.size() == 3 ? given[1] : fallback,
                                                                              given.size() == 3 ? given[2] : fallback};
      const std::vector<float3> keys = source.decode_floats<float3>(sampler.output, true);
      double largest = std::max({std::fabs(rest[0]), std::fabs(rest[1]), std::fabs(rest[2])});
      for (const float3& v : keys) largest = std::max({largest, std::fabs(double(v.x)), std::fabs(double(v.y)), std::fabs(double(v.z))});
      const double tolerance = tolerances.of(ch.target_path, ch.target_node, largest);
      still[c] = !keys.empty() && std::all_of(keys.begin(), keys.end(), [&](const float3& v) {
        return std::fabs(v.x - rest[0]) <= tolerance && std::fabs(v.y - rest[1]) <= tolerance && std::fabs(v.z - rest[2]) <= tolerance;
      });
    }
  }
  std::pair<float, float> whole{INFINITY, -INFINITY}, left{INFINITY, -INFINITY};
  for (size_t c = 0; c < anim.channels.size(); ++c) {
    if (anim.channels[c].sampler < 0 || size_t(anim.channels[c].sampler) >= anim.samplers.size()) continue;
    const auto [lo, hi] = span(anim.channels[c]);
    whole = {std::min(whole.first, lo), std::max(whole.second, hi)};
    if (!still[c]) left = {std::min(left.first, lo), std::max(left.second, hi)};
  }
  if (left != whole || std::all_of(still.begin(), still.end(), [](bool b) { return b; })) still.assign(still.size(), false);
  return still;
}

// ---- -q: UV sets outside [0, 1] (KHR_texture_transform) -------------------------------------------

constexpr const char* texture_transform = "KHR_texture_transform";

// A texture reference's KHR_texture_transform: uv' = offset + R(rotation) (scale o uv), R turning
// counter-clockwise (the extension's matrix); tex_coord overrides the reference's set when >= 0.
struct TextureTransform {
  double offset[2] = {0, 0}, rotation = 0, scale[2] = {1, 1};
  int tex_coord = -1;
};

TextureTransform read_texture_transform(const tg::ExtensionMap& extensions) {
  TextureTransform t;
  const auto found = extensions.find(texture_transform);
  if (found == extensions.end() || !found->second.IsObject()) return t;
  const tg::Value& v = found->second;
  const auto pair = [&](const char* key, double (&out)[2]) {
    if (v.Has(key) && v.Get(key).IsArray() && v.Get(key).ArrayLen() == 2 && v.Get(key).Get(0).IsNumber() && v.Get(key).Get(1).IsNumber())
      out[0] = v.Get(key).Get(0).GetNumberAsDouble(), out[1] = v.Get(key).Get(1).GetNumberAsDouble();
  };
  pair("offset", t.offset);
  pair("scale", t.scale);
  if (v.Has("rotation") && v.Get("rotation").IsNumber()) t.rotation = v.Get("rotation").GetNumberAsDouble();
  if (v.Has("texCoord") && v.Get("texCoord").IsInt()) t.tex_coord = v.Get("texCoord").GetNumberAsInt();
  return t;
}

// The transform that reads a box's stored values the way `t` read the UVs: t (offset + scale o q)
// = (t.offset + R (t.scale o offset)) + R ((t.scale o scale) o q).
TextureTransform after_box(const TextureTransform& t, const UvBox& box) {
  TextureTransform out = t;
  const double c = std::cos(t.rotation), s = std::sin(t.rotation);
  const double x = t.scale[0] * box.offset[0], y = t.scale[1] * box.offset[1];
  out.offset[0] = t.offset[0] + c * x - s * y;
  out.offset[1] = t.offset[1] + s * x + c * y;
  out.scale[0] = t.scale[0] * box.scale[0];
  out.scale[1] = t.scale[1] * box.scale[1];
  return out;
}

tg::Value texture_transform_value(const TextureTransform& t) {
  tg::Value::Object v;
  v["offset"] = tg::Value(tg::Value::Array{tg::Value(t.offset[0]), tg::Value(t.offset[1])});
  v["scale"] = tg::Value(tg::Value::Array{tg::Value(t.scale[0]), tg::Value(t.scale[1])});
  if (t.rotation != 0) v["rotation"] = tg::Value(t.rotation);
  if (t.tex_coord >= 0) v["texCoord"] = tg::Value(t.tex_coord);
  return tg::Value(std::move(v));
}

// Calls f(tex_coord, extensions) on each texture reference of a material: the core ones, and those
// its extensions hold (KHR_materials_*: members named "...Texture", objects with an "index").
template <class F>
void for_each_texture(tg::Material& material, F&& f) {
  for (auto* info : {&material.pbrMetallicRoughness.baseColorTexture, &material.pbrMetallicRoughness.metallicRoughnessTexture,
                     &material.emissiveTexture})
    if (info->index >= 0) f(info->texCoord, info->extensions);
  if (material.normalTexture.index >= 0) f(material.normalTexture.texCoord, material.normalTexture.extensions);
  if (material.occlusionTexture.index >= 0) f(material.occlusionTexture.texCoord, material.occlusionTexture.extensions);
  const auto walk = [&](auto&& self, tg::Value& value) -> void {
    if (!value.IsObject()) return;
    for (std::pair<const std::string, tg::Value>& entry : value.Get<tg::Value::Object>()) {
      const std::string& key = entry.first;
      tg::Value& member = entry.second;
      if (!member.IsObject()) continue;
      if (key.ends_with("Texture") && member.Has("index") && member.Get("index").IsInt()) {
        tg::Value::Object& info = member.Get<tg::Value::Object>();
        const int tex_coord = info.count("texCoord") && info["texCoord"].IsInt() ? info["texCoord"].GetNumberAsInt() : 0;
        tg::ExtensionMap extensions;
        if (info.count("extensions") && info["extensions"].IsObject()) extensions = info["extensions"].Get<tg::Value::Object>();
        f(tex_coord, extensions);
        if (!extensions.empty()) info["extensions"] = tg::Value(tg::Value::Object(extensions.begin(), extensions.end()));
      } else {
        self(self, member);
      }
    }
  };
  for (auto& [name, value] : material.extensions) walk(walk, value);
}

// The UV set a texture reference samples.
int texture_set(int tex_coord, const tg::ExtensionMap& extensions) {
  const int over = read_texture_transform(extensions).tex_coord;
  return over >= 0 ? over : tex_coord;
}

// -q's UV boxes, per written primitive (`where[i]`, a mesh and primitive of the rebuilt document,
// drawing meshes[i]). UV sets within [0, 1] need none. A set outside takes one box per group of
// materials (a primitive's material and its KHR_materials_variants alternatives), over every
// primitive drawn with them, and each of their textures sampling the set has its
// KHR_texture_transform composed with the box. A set stays in floats where that cannot hold: no
// texture samples it (the box would be lost), a primitive drawn with the group is not rewritten (a
// point or line primitive kept as it was) or morphs that UV set, or the box is wider than 8 (a
// step would pass 2^-13, a quarter of a 2048 texture's texel). Returns whether any box was made.
bool make_uv_boxes(tg::Model& model, const std::vector<std::pair<size_t, size_t>>& where, const std::vector<const Mesh*>& meshes,
                   int uv_bits, std::vector<UvBoxes>& boxes) {
  boxes.assign(where.size(), UvBoxes{});
  const size_t materials = model.materials.size();
  if (materials == 0) return false;
  std::vector<size_t> parent(materials);
  std::iota(parent.begin(), parent.end(), size_t(0));
  const auto find = [&](size_t m) {
    while (parent[m] != m) m = parent[m] = parent[parent[m]];
    return m;
  };
  // A primitive's materials: its own and its variants'.
  const auto materials_of = [&](const tg::Primitive& prim) {
    std::vector<size_t> out;
    if (prim.material >= 0 && size_t(prim.material) < materials) out.push_back(size_t(prim.material));
    const auto variants = prim.extensions.find("KHR_materials_variants");
    if (variants != prim.extensions.end() && variants->second.Has("mappings") && variants->second.Get("mappings").IsArray()) {
      const tg::Value& mappings = variants->second.Get("mappings");
      for (size_t k = 0; k < mappings.ArrayLen(); ++k)
        if (mappings.Get(int(k)).Has("material") && mappings.Get(int(k)).Get("material").IsInt()) {
          const int m = mappings.Get(int(k)).Get("material").GetNumberAsInt();
          if (m >= 0 && size_t(m) < materials) out.push_back(size_t(m));
        }
    }
    return out;
  };
  for (const tg::Mesh& mesh : model.meshes)
    for (const tg::Primitive& prim : mesh.primitives) {
      const std::vector<size_t> own = materials_of(prim);
      for (size_t k = 1; k < own.size(); ++k) parent[find(own[k])] = find(own[0]);
    }

  // Per group and set: whether a box can hold, and its bounds.
  struct Bounds {
    bool ok = true, sampled = false, outside = false;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  };
  std::vector<std::array<Bounds, max_uv_sets>> group(materials);
  for (size_t m = 0; m < materials; ++m)
    for_each_texture(model.materials[m], [&](int tex_coord, const tg::ExtensionMap& extensions) {
      const int set = texture_set(tex_coord, extensions);
      if (set >= 0 && size_t(set) < max_uv_sets) group[find(m)][size_t(set)].sampled = true;
    });
  std::set<std::pair<size_t, size_t>> written(where.begin(), where.end());
  for (size_t m = 0; m < model.meshes.size(); ++m)
    for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      const tg::Primitive& prim = model.meshes[m].primitives[p];
      for (const size_t material : materials_of(prim))
        for (size_t set = 0; set < max_uv_sets; ++set)
          if (!written.count({m, p}) || std::any_of(prim.targets.begin(), prim.targets.end(), [&](const auto& target) {
                return target.count("TEXCOORD_" + str(set)) > 0;
              }))
            group[find(material)][set].ok = false;
    }
  for (size_t i = 0; i < where.size(); ++i) {
    const tg::Primitive& prim = model.meshes[where[i].first].primitives[where[i].second];
    for (const size_t material : materials_of(prim))
      for (size_t set = 0; set < max_uv_sets; ++set) {
        Bounds& b = group[find(material)][set];
        for (const float2& uv : meshes[i]->uvs[set]) {
          if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) b.ok = false;
          b.outside = b.outside || uv.x < 0 || uv.x > 1 || uv.y < 0 || uv.y > 1;
          b.lo[0] = std::min(b.lo[0], double(uv.x)), b.hi[0] = std::max(b.hi[0], double(uv.x));
          b.lo[1] = std::min(b.lo[1], double(uv.y)), b.hi[1] = std::max(b.hi[1], double(uv.y));
        }
      }
  }

  // A texture transform an animation drives (KHR_animation_pointer) would overwrite the box's.
  for (const tg::Animation& anim : model.animations)
    for (const tg::AnimationChannel& ch : anim.channels) {
      const std::string pointer = channel_pointer(ch);
      const PointerTarget t = split_pointer(pointer, "materials");
      if (t.index >= 0 && size_t(t.index) < materials && t.rest.find(std::string("/") + texture_transform + "/") != std::string_view::npos)
        for (Bounds& b : group[find(size_t(t.index))]) b.ok = false;
    }
  std::vector<UvBoxes> of_group(materials);
  bool made = false;
  for (size_t g = 0; g < materials; ++g)
    for (size_t set = 0; set < max_uv_sets; ++set) {
      const Bounds& b = group[g][set];
      if (!b.ok || !b.sampled || (!b.outside && uv_bits == 16) || b.hi[0] - b.lo[0] > 8 || b.hi[1] - b.lo[1] > 8) continue;
      UvBox box;
      for (size_t c = 0; c < 2; ++c) {
        // Floats, rounded outwards: the box holds every value, and the transform written is the
        // one the values were stored with.
        box.offset[c] = float(b.lo[c]);
        if (box.offset[c] > b.lo[c]) box.offset[c] = std::nextafter(box.offset[c], -INFINITY);
        const double extent = (b.hi[c] - box.offset[c]) * 65535.0 / double((1u << uv_bits) - 1);
        box.scale[c] = float(extent);
        if (box.scale[c] < extent) box.scale[c] = std::nextafter(box.scale[c], INFINITY);
        if (box.scale[c] == 0) box.scale[c] = 1;
      }
      of_group[g][set] = box;
      made = true;
    }
  if (!made) return false;
  for (size_t m = 0; m < materials; ++m)
    for_each_texture(model.materials[m], [&](int tex_coord, tg::ExtensionMap& extensions) {
      const int set = texture_set(tex_coord, extensions);
      if (set < 0 || size_t(set) >= max_uv_sets || !of_group[find(m)][size_t(set)]) return;
      extensions[texture_transform] = texture_transform_value(after_box(read_texture_transform(extensions), *of_group[find(m)][size_t(set)]));
    });
  for (size_t i = 0; i < where.size(); ++i) {
    const tg::Primitive& prim = model.meshes[where[i].first].primitives[where[i].second];
    if (prim.material >= 0 && size_t(prim.material) < materials) boxes[i] = of_group[find(size_t(prim.material))];
  }
  return true;
}

// Replaces the geometry of the triangle primitives listed in `slots` by scene.primitives[i].mesh,
// drops what nothing references any more, and packs the surviving bufferViews and the new geometry
// into one buffer (returned; buffer 0 of the model, whose `buffers` list is left empty), quantized as
// `options` asks. `report` gets the Draco counts; `directions`, under compress_more, the float values
// of the quantized normals and tangents (compress_meshopt's octahedral filter codes those).
std::vector<uint8_t> rebuild_geometry(tg::Model& model, const Scene& scene, const std::vector<Slot>& slots,
                                      const WriteOptions& options, WriteReport& report, io::DirectionFloats& directions) {
  const size_t mesh_count = model.meshes.size();
  // Which scene primitive replaces each glTF primitive (-1: none).
  std::vector<std::vector<int>> replaced_by(mesh_count);
  for (size_t m = 0; m < mesh_count; ++m) replaced_by[m].assign(model.meshes[m].primitives.size(), -1);
  for (size_t i = 0; i < slots.size(); ++i) {
    const Slot& slot = slots[i];
    const std::string where = "cannot write glTF: scene primitive " + str(i);
    if (slot.mesh < 0 || size_t(slot.mesh) >= mesh_count || slot.primitive < 0 ||
        size_t(slot.primitive) >= replaced_by[size_t(slot.mesh)].size())
      throw_usage(where + " refers to a glTF primitive that its source does not have");
    const tg::Primitive& prim = model.meshes[size_t(slot.mesh)].primitives[size_t(slot.primitive)];
    if (!is_triangle_mode(prim.mode)) throw_usage(where + " refers to a points or lines primitive");
    int& owner = replaced_by[size_t(slot.mesh)][size_t(slot.primitive)];
    if (owner != -1) throw_usage(where + " refers to the same glTF primitive as scene primitive " + str(size_t(owner)));
    owner = int(i);
    const int material = scene.primitives[i].material;
    if (material < -1 || (material >= 0 && size_t(material) >= model.materials.size()))
      throw_usage(where + " uses material " + std::to_string(material) + ", which the document does not have");
    check_writable(scene.primitives[i].mesh, i);
    if (const int32_t shared = scene.primitives[i].shares_vertices_with; shared >= 0) {
      const Mesh& a = scene.primitives[i].mesh;
      if (size_t(shared) >= i) throw_usage(where + " shares the vertices of a primitive that does not come before it");
      const Mesh& b = scene.primitives[size_t(shared)].mesh;
      if (a.positions != b.positions || a.normals != b.normals || a.tangents != b.tangents || a.uvs != b.uvs ||
          a.colors != b.colors || a.joints != b.joints || a.weights != b.weights || a.joints1 != b.joints1 ||
          a.weights1 != b.weights1)
        throw_usage(where + " shares the vertices of primitive " + std::to_string(shared) + " but its streams differ");
    }
    for (const MorphTarget& target : scene.primitives[i].targets)
      if (target.positions.size() != scene.primitives[i].mesh.vertex_count() ||
          (!target.normals.empty() && target.normals.size() != target.positions.size()) ||
          (!target.tangents.empty() && target.tangents.size() != target.positions.size()))
        throw_usage(where + ": a morph target does not have one entry per vertex");
  }

  // Rebuild each mesh's primitive list. A triangle primitive that no scene primitive replaces, or
  // whose new mesh has no triangle, is removed. The streams lodkit does not model (morph targets,
  // other attributes) survive where the scene primitive maps its vertices to the source's (gathered
  // now, from the source's accessors, and written with the geometry) or their count is unchanged;
  // otherwise they are dropped, the morph targets for every primitive of the mesh (glTF requires
  // equal target counts).
  struct Pending {
    size_t mesh, primitive, scene_primitive;
  };
  struct Gathered {
    int target;  // -1: a vertex attribute; else the morph target
    std::string semantic;
    tg::Accessor like;  // a copy of the source accessor (its type; the source's are pruned below)
    std::vector<uint8_t> bytes;
  };
  std::vector<std::vector<Gathered>> gathered(scene.primitives.size());
  const Document source(model, "cannot write glTF: the source document");
  std::vector<Pending> pending;
  std::vector<bool> mesh_lost_morphs(mesh_count, false), mesh_removed(mesh_count, false);
  for (size_t m = 0; m < mesh_count; ++m) {
    tg::Mesh& mesh = model.meshes[m];
    bool drop_morphs = false;
    std::vector<tg::Primitive> kept;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      tg::Primitive prim = mesh.primitives[p];
      const int owner = replaced_by[m][p];
      if (!is_triangle_mode(prim.mode)) {
        kept.push_back(std::move(prim));
        continue;
      }
      if (owner < 0) continue;
      const Mesh& geometry = scene.primitives[size_t(owner)].mesh;
      if (geometry.indices.empty()) continue;
      // Source morph targets the scene drops (lod's stale geomorph): the first ones stay.
      if (const uint32_t keep = scene.primitives[size_t(owner)].source_target_count; keep < prim.targets.size()) {
        prim.targets.resize(keep);
        if (mesh.weights.size() > keep) mesh.weights.resize(keep);
        if (keep == 0) drop_morphs = true;
      }
      auto position = prim.attributes.find("POSITION");
      const std::vector<std::array<float, 3>>& weights = scene.primitives[size_t(owner)].source_weights;
      const size_t source_count = position != prim.attributes.end() ? model.accessors[size_t(position->second)].count : 0;
      // A source's own streams that lodkit does not model are kept as they are, unless they must
      // be rewritten: quantized, its morph targets (their positions go on the grid); under Draco,
      // all of them (they follow Edgebreaker's renumbering). Those go through the identity map.
      bool unmodelled = false;
      for_each_unmodelled_stream(prim, [&](auto&&...) { unmodelled = true; });
      std::vector<uint32_t> identity;
      if (((options.quantize && !prim.targets.empty()) || (options.draco && unmodelled)) &&
          scene.primitives[size_t(owner)].source_vertices.empty() && source_count == geometry.vertex_count()) {
        identity.resize(source_count);
        std::iota(identity.begin(), identity.end(), 0u);
      }
      const std::vector<uint32_t>& map = identity.empty() ? scene.primitives[size_t(owner)].source_vertices : identity;
      if (!map.empty()) {
        const std::string where = "cannot write glTF: scene primitive " + str(size_t(owner)) + "'s source_vertices";
        const size_t per_vertex = weights.empty() ? 1 : 3;
        if (map.size() != per_vertex * geometry.vertex_count())
          throw_usage(where + " has " + str(map.size()) + " entries for " + str(geometry.vertex_count()) + " vertices" +
                      (weights.empty() ? "" : ", 3 each (source_weights)"));
        if (!weights.empty() && weights.size() != geometry.vertex_count())
          throw_usage(where + ": source_weights has " + str(weights.size()) + " entries for " + str(geometry.vertex_count()) + " vertices");
        for (const uint32_t v : map)
          if (v >= source_count)
            throw_usage(where + " names vertex " + str(v) + " of a source primitive with " + str(source_count));
        const auto gather = [&](int target, const std::string& semantic, int& index) {
          const tg::Accessor& like = model.accessors[size_t(index)];
          const std::vector<uint8_t> all = source.packed_elements(index);
          const size_t element = element_bytes(like.componentType, like.type);
          const size_t count = geometry.vertex_count();
          std::vector<uint8_t> bytes(count * element);
          // Blends: floats and normalized integers are interpolated; other integers (ids) are not
          // quantities, so the heaviest source vertex gives its value.
          const bool interpolate = like.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT || like.normalized;
          const size_t components = type_components(like.type), size = component_bytes(like.componentType);
          for (size_t v = 0; v < count; ++v) {
            uint8_t* out = bytes.data() + v * element;
            if (weights.empty()) {
              std::memcpy(out, all.data() + size_t(map[v]) * element, element);
            } else if (!interpolate || components * size != element) {  // (matrices: padded columns)
              const std::array<float, 3>& w = weights[v];
              const size_t k = w[1] > w[0] ? (w[2] > w[1] ? 2 : 1) : (w[2] > w[0] ? 2 : 0);
              std::memcpy(out, all.data() + size_t(map[3 * v + k]) * element, element);
            } else {
              for (size_t c = 0; c < components; ++c) {
                double value = 0;
                for (size_t k = 0; k < 3; ++k)
                  value += double(weights[v][k]) * component_value(all.data() + size_t(map[3 * v + k]) * element + c * size, like.componentType);
                store_component(value, out + c * size, like.componentType);
              }
            }
          }
          gathered[size_t(owner)].push_back({target, semantic, like, std::move(bytes)});
          index = -1;  // written anew: the source accessor is not kept for it
        };
        for_each_unmodelled_stream(prim, gather);
      }
      const bool same_count = map.empty() && source_count == geometry.vertex_count();
      if (!same_count && map.empty() && !prim.targets.empty()) drop_morphs = true;
      for (auto it = prim.attributes.begin(); it != prim.attributes.end();)
        it = (is_regenerated_semantic(it->first) || !same_count) ? prim.attributes.erase(it) : std::next(it);
      prim.indices = -1;
      prim.material = scene.primitives[size_t(owner)].material;
      prim.extensions.erase("KHR_draco_mesh_compression");  // it describes the old geometry
      pending.push_back({m, kept.size(), size_t(owner)});
      kept.push_back(std::move(prim));
    }
    if (drop_morphs) {
      for (tg::Primitive& prim : kept) prim.targets.clear();
      mesh.weights.clear();
      mesh_lost_morphs[m] = true;
    }
    mesh_removed[m] = kept.empty();
    mesh.primitives = std::move(kept);
  }

  {
    std::vector<size_t> targets(mesh_count, 0);  // per glTF mesh, as written
    for (size_t m = 0; m < mesh_count; ++m)
      for (const tg::Primitive& prim : model.meshes[m].primitives) targets[m] = std::max(targets[m], prim.targets.size());
    for (const Pending& p : pending)
      if (model.meshes[p.mesh].primitives[p.primitive].targets.empty())
        targets[p.mesh] = std::max(targets[p.mesh], scene.primitives[p.scene_primitive].targets.size());
    fit_morph_weights(model, source, targets);
  }

  // Nodes instancing a removed mesh, or one that lost its morph targets, lose their weights and the
  // animation channels that drive them.
  std::vector<int> mesh_remap(mesh_count, -1);
  {
    int next = 0;
    for (size_t m = 0; m < mesh_count; ++m)
      if (!mesh_removed[m]) mesh_remap[m] = next++;
  }
  std::vector<bool> weights_gone(model.nodes.size(), false);
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    tg::Node& node = model.nodes[n];
    if (node.mesh < 0) continue;
    const size_t m = size_t(node.mesh);
    if (mesh_removed[m] || mesh_lost_morphs[m]) {
      node.weights.clear();
      weights_gone[n] = true;
    }
    if (mesh_removed[m]) {
      node.skin = -1;
      node.extensions.erase(gpu_instancing);  // instances of nothing
    }
    node.mesh = mesh_remap[m];
  }
  // -q: channels that change nothing go (still_channels), decided before any goes.
  if (options.quantize && !(options.animation_error >= 0 && options.animation_error <= 1))
    throw_usage("cannot write glTF: animation_error is " + std::to_string(options.animation_error) + ", not 0 to 1");
  const KeyTolerances tolerances = options.quantize ? key_tolerances(scene, options.animation_error) : KeyTolerances{};
  std::vector<std::vector<bool>> still(model.animations.size());
  if (options.quantize) {
    const auto clips = animating_clips(model);
    for (size_t a = 0; a < model.animations.size(); ++a) still[a] = still_channels(model, source, a, tolerances, clips);
  }
  for (size_t a = 0; a < model.animations.size(); ++a) {
    tg::Animation& anim = model.animations[a];
    for (size_t c = anim.channels.size(); c-- > 0;)
      if (!still[a].empty() && still[a][c]) anim.channels.erase(anim.channels.begin() + ptrdiff_t(c));
    // A node's weights, or a mesh's own (KHR_animation_pointer), that are gone; the meshes renumbered.
    std::erase_if(anim.channels, [&](const tg::AnimationChannel& ch) {
      const ChannelTarget t = channel_target(ch);
      const size_t i = size_t(t.index);
      const bool weights = t.property == "weights";
      if (t.list == "nodes") return weights && i < weights_gone.size() && weights_gone[i];
      return t.list == "meshes" && i < mesh_count && (mesh_removed[i] || (weights && mesh_lost_morphs[i]));
    });
    for (tg::AnimationChannel& ch : anim.channels)
      if (const ChannelTarget t = channel_target(ch); t.list == "meshes" && size_t(t.index) < mesh_count && mesh_remap[size_t(t.index)] != t.index)
        retarget_channel(ch, "meshes", mesh_remap[size_t(t.index)]);
    // The samplers no channel uses any more go too (their accessors with them, below).
    std::vector<int> sampler_remap(anim.samplers.size(), -1);
    for (const tg::AnimationChannel& ch : anim.channels)
      if (ch.sampler >= 0 && size_t(ch.sampler) < sampler_remap.size()) sampler_remap[size_t(ch.sampler)] = 0;
    std::vector<tg::AnimationSampler> samplers;
    for (size_t s = 0; s < sampler_remap.size(); ++s)
      if (sampler_remap[s] == 0) sampler_remap[s] = int(samplers.size()), samplers.push_back(std::move(anim.samplers[s]));
    anim.samplers = std::move(samplers);
    for (tg::AnimationChannel& ch : anim.channels)
      if (ch.sampler >= 0 && size_t(ch.sampler) < sampler_remap.size()) ch.sampler = sampler_remap[size_t(ch.sampler)];
  }
  // A clip left without channels goes: glTF wants at least one.
  std::erase_if(model.animations, [](const tg::Animation& anim) { return anim.channels.empty(); });
  {
    std::vector<tg::Mesh> meshes;
    for (size_t m = 0; m < mesh_count; ++m)
      if (!mesh_removed[m]) meshes.push_back(std::move(model.meshes[m]));
    model.meshes = std::move(meshes);
    for (Pending& p : pending) p.mesh = size_t(mesh_remap[p.mesh]);
  }

  // Quantized: the meshes whose positions go on the grid, and the grid.
  PositionGrid grid;
  std::vector<bool> on_grid(model.meshes.size(), false);
  if (options.quantize) {
    if (options.position_bits < 1 || options.position_bits > 16)
      throw_usage("cannot write glTF: position_bits is " + std::to_string(options.position_bits) + ", not 1 to 16");
    std::vector<size_t> regenerated(model.meshes.size(), 0);
    for (const Pending& p : pending) ++regenerated[p.mesh];
    for (size_t m = 0; m < on_grid.size(); ++m) on_grid[m] = regenerated[m] == model.meshes[m].primitives.size();
    on_grid = grid_meshes(model, scene, on_grid);
    const auto grid_of = [&] {
      std::vector<const Mesh*> meshes;
      for (const Pending& p : pending)
        if (on_grid[p.mesh]) meshes.push_back(&scene.primitives[p.scene_primitive].mesh);
      return position_grid(meshes, options.position_bits);
    };
    // The transforms that take the grid must stay within the float range: a mesh where one would
    // not keeps float positions (fewer meshes give a grid no larger, so one pass holds).
    const std::vector<bool> fits = grid_transforms_fit(model, scene, source, on_grid, grid_of());
    for (size_t m = 0; m < on_grid.size(); ++m) on_grid[m] = on_grid[m] && fits[m];
    on_grid = grid_meshes(model, scene, on_grid);
    grid = grid_of();
    if (grid.top == 0) on_grid.assign(on_grid.size(), false);
  }

  // Quantized (Draco quantizes UVs its own way): the UV boxes, per pending primitive.
  std::vector<UvBoxes> uv_boxes;
  bool used_uv_boxes = false;
  if (options.quantize && !options.draco) {
    std::vector<std::pair<size_t, size_t>> where;
    std::vector<const Mesh*> drawn;
    for (const Pending& p : pending) where.emplace_back(p.mesh, p.primitive), drawn.push_back(&scene.primitives[p.scene_primitive].mesh);
    used_uv_boxes = make_uv_boxes(model, where, drawn, options.uv_bits ? options.uv_bits : 16, uv_boxes);
  }

  // GPU instances of a grid mesh take the grid in their own transforms (below the node's, which
  // children and cameras share): instance T R S becomes T R S D, that is the translation
  // T + R (S o) and the scale S s. Computed now, so that the old accessors are pruned; written with
  // the geometry.
  struct GridInstances {
    size_t node;
    std::vector<float3> translation, scale;
  };
  std::vector<GridInstances> grid_instances;
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    tg::Node& node = model.nodes[n];
    if (node.mesh < 0 || !on_grid[size_t(node.mesh)] || !node.extensions.count(gpu_instancing)) continue;
    GridInstances& out = grid_instances.emplace_back(GridInstances{n, {}, {}});
    for (const Node::GpuInstance& g : scene.nodes[n].gpu_instances) {  // (grid_meshes checked they are there)
      const double q[4] = {g.rotation.x, g.rotation.y, g.rotation.z, g.rotation.w};
      const core::vec3d t = place_grid_offset(core::to_double(g.translation), q, core::to_double(g.scale), grid);
      out.translation.push_back({float(t.x), float(t.y), float(t.z)});
      out.scale.push_back({float(g.scale.x * grid.scale), float(g.scale.y * grid.scale), float(g.scale.z * grid.scale)});
    }
    tg::Value::Object ext = node.extensions[gpu_instancing].Get<tg::Value::Object>();
    tg::Value::Object attributes = ext["attributes"].Get<tg::Value::Object>();
    attributes.erase("TRANSLATION"), attributes.erase("SCALE");
    ext["attributes"] = tg::Value(std::move(attributes));
    node.extensions[gpu_instancing] = tg::Value(std::move(ext));
  }

  // Quantized: animation keys, read now and written with the geometry (the old accessors go where
  // nothing else uses them). A sampler that drives translations, rotations or scales (LINEAR or STEP;
  // cubic splines keep their keys) keeps, of three ways, the one of fewest bytes: all its keys (its
  // input stays); the keys its curve needs (reduce_keys), whose times cost 4 bytes a key, shared only
  // by samplers that keep the same ones; or every s-th key (thin_keys), whose times the samplers of
  // the same input and stride share. Rotation keyframes go in normalized shorts, as core glTF allows
  // (half the bytes, within 1/65534 per component), where every value, cubic tangents included, lies
  // in [-1, 1].
  struct SamplerKeys {
    size_t animation, sampler;
    std::vector<float> times;  // empty: the input accessor stays
    std::vector<float> values;
    size_t components;  // per key: 3, 4 (rotations), the morph weights', or a pointer's
    int type;           // the output accessor's (TINYGLTF_TYPE_*)
    bool rotation, shorts;
  };
  std::vector<SamplerKeys> sampler_keys;
  // A sampler's ways, with the bytes of its best so far (choices[i] is sampler_keys[i]'s).
  struct Choice {
    size_t input;  // samplers of equal key times (one accessor or several) have the same
    size_t count, value_bytes;
    double bytes;
    bool reduce;                  // reduce_keys' way is the best of the first two
    Keys reduced;                 // reduce_keys'
    std::vector<size_t> strides;  // thinning_strides'
  };
  std::vector<Choice> choices;
  std::map<std::vector<float>, size_t> key_times;  // -> their number in Choice::input
  if (options.quantize)
    for (size_t a = 0; a < model.animations.size(); ++a) {
      tg::Animation& anim = model.animations[a];
      for (size_t k = 0; k < anim.samplers.size(); ++k) {
        tg::AnimationSampler& sampler = anim.samplers[k];
        std::string path;
        bool one_path = true;
        std::vector<int> nodes;  // (a sampler may drive several)
        for (const tg::AnimationChannel& ch : anim.channels)
          if (ch.sampler == int(k))
            one_path = one_path && (path.empty() || path == ch.target_path), path = ch.target_path, nodes.push_back(ch.target_node);
        // (A KHR_animation_pointer's float property: a material's colour, a camera's field of view.)
        const bool rotation = path == "rotation", weights = path == "weights", pointer = path == "pointer";
        if (!one_path || (!rotation && !weights && !pointer && path != "translation" && path != "scale")) continue;
        if (sampler.input < 0 || size_t(sampler.input) >= model.accessors.size() || sampler.output < 0 ||
            size_t(sampler.output) >= model.accessors.size())
          continue;
        const tg::Accessor& in = model.accessors[size_t(sampler.input)];
        const tg::Accessor& acc = model.accessors[size_t(sampler.output)];
        const bool cubic = sampler.interpolation == "CUBICSPLINE", step = sampler.interpolation == "STEP";
        const size_t per_key = (cubic ? 3 : 1) * in.count;
        // A pointer's SCALAR output may hold several values a key (a float[] such as weights).
        const int type = rotation ? TINYGLTF_TYPE_VEC4 : weights ? TINYGLTF_TYPE_SCALAR : pointer ? acc.type : TINYGLTF_TYPE_VEC3;
        if (type != TINYGLTF_TYPE_SCALAR && type != TINYGLTF_TYPE_VEC2 && type != TINYGLTF_TYPE_VEC3 && type != TINYGLTF_TYPE_VEC4) continue;
        const size_t components = type == TINYGLTF_TYPE_SCALAR ? (per_key ? acc.count / per_key : 0) : type_components(type);
        if (in.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || in.type != TINYGLTF_TYPE_SCALAR || components == 0 ||
            acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || acc.type != type)
          continue;
        SamplerKeys out{a, k, source.decode_floats<float>(sampler.input), {}, components, type, rotation, false};
        out.values = source.decode_animation_output(sampler.output, type_components(type));  // (float: as stored)
        const size_t n = out.times.size();
        if (out.values.size() != n * components * (cubic ? 3 : 1)) continue;  // (the reader refuses such files)
        // The keys: floats, or shorts (rotations in range) for the values.
        const bool shorts = rotation && all_in_range(out.values, -1.0f, 1.0f);
        const size_t value_bytes = shorts ? 8 : 4 * components;
        const bool finite = std::all_of(out.values.begin(), out.values.end(), [](float x) { return std::isfinite(x); });
        double largest = 0;
        for (const float x : out.values) largest = std::max(largest, std::fabs(double(x)));
        double tolerance = INFINITY;
        for (const int node : nodes) tolerance = std::min(tolerance, tolerances.of(path, node, largest));
        out.shorts = shorts;
        Choice choice{key_times.try_emplace(out.times, key_times.size()).first->second, n, value_bytes, double(n * value_bytes), false, {}, {}};
        if (!cubic && finite) {
          const KeyCurve curve{out.times, out.values, components, rotation, tolerance};
          choice.reduced = reduce_keys(out.times, out.values, components, rotation, step, tolerance);
          if (const size_t m = choice.reduced.times.size(); m > 0 && m < n && m * (4 + value_bytes) < n * value_bytes)
            choice.bytes = double(m * (4 + value_bytes)), choice.reduce = true;
          if (!step) choice.strides = thinning_strides(curve);
        }
        sampler_keys.push_back(std::move(out));
        choices.push_back(std::move(choice));
      }
    }
  // The strides the samplers of each input take: coarsest first, a stride's times are written when
  // the bytes its samplers save (against their best other way) exceed them.
  std::vector<size_t> stride_of(choices.size(), 0);
  {
    std::map<size_t, std::vector<size_t>> members;  // input -> its samplers (in choices); their key counts are equal
    for (size_t i = 0; i < choices.size(); ++i) members[choices[i].input].push_back(i);
    for (const auto& [input, of_input] : members) {
      std::set<size_t, std::greater<>> strides;  // some sampler of the input fits them
      for (const size_t i : of_input) strides.insert(choices[i].strides.begin(), choices[i].strides.end());
      const size_t n = choices[of_input.front()].count;
      for (const size_t s : strides) {
        const auto fits = [&](const Choice& c) { return std::find(c.strides.begin(), c.strides.end(), s) != c.strides.end(); };
        double saved = 0;
        for (const size_t i : of_input)
          if (fits(choices[i])) saved += std::max(0.0, choices[i].bytes - double(thinned_count(n, s) * choices[i].value_bytes));
        if (saved <= 4.0 * double(thinned_count(n, s))) continue;
        for (const size_t i : of_input)
          if (const double bytes = double(thinned_count(n, s) * choices[i].value_bytes); fits(choices[i]) && bytes < choices[i].bytes)
            choices[i].bytes = bytes, stride_of[i] = s;
      }
    }
  }
  for (size_t i = 0; i < choices.size(); ++i) {
    Choice& c = choices[i];
    SamplerKeys& out = sampler_keys[i];
    tg::AnimationSampler& sampler = model.animations[out.animation].samplers[out.sampler];
    if (stride_of[i]) {
      Keys thinned = thin_keys(KeyCurve{out.times, out.values, out.components, out.rotation, 0}, stride_of[i]);
      out.times = std::move(thinned.times), out.values = std::move(thinned.values);
      sampler.input = -1;
    } else if (c.reduce) {
      out.times = std::move(c.reduced.times), out.values = std::move(c.reduced.values);
      sampler.input = -1;
    } else {
      out.times.clear();
    }
    if (!out.times.empty() || out.shorts) sampler.output = -1;  // (the old accessors are pruned below)
  }
  std::erase_if(sampler_keys, [](const SamplerKeys& keys) { return keys.times.empty() && !keys.shorts; });

  // Keep the accessors something still references, then the bufferViews those and the images use.
  std::vector<int> accessor_remap(model.accessors.size(), -1);
  auto mark_accessor = [&](int index) {
    if (index >= 0) accessor_remap[size_t(index)] = 0;
  };
  for (const tg::Mesh& mesh : model.meshes)
    for (const tg::Primitive& prim : mesh.primitives) {
      for (const auto& attribute : prim.attributes) mark_accessor(attribute.second);
      mark_accessor(prim.indices);
      for (const auto& target : prim.targets)
        for (const auto& attribute : target) mark_accessor(attribute.second);
    }
  for (const tg::Skin& skin : model.skins) mark_accessor(skin.inverseBindMatrices);
  for (tg::Node& node : model.nodes) for_each_instancing_accessor(node, accessor_remap.size(), mark_accessor);
  for (const tg::Animation& anim : model.animations)
    for (const tg::AnimationSampler& sampler : anim.samplers) {
      mark_accessor(sampler.input);
      mark_accessor(sampler.output);
    }
  std::vector<tg::Accessor> accessors;
  for (size_t a = 0; a < accessor_remap.size(); ++a)
    if (accessor_remap[a] == 0) {
      accessor_remap[a] = int(accessors.size());
      accessors.push_back(std::move(model.accessors[a]));
    }

  std::vector<int> view_remap(model.bufferViews.size(), -1);
  auto mark_view = [&](int index) {
    if (index >= 0) view_remap[size_t(index)] = 0;
  };
  for (const tg::Accessor& acc : accessors) {
    mark_view(acc.bufferView);
    if (acc.sparse.isSparse) {
      mark_view(acc.sparse.indices.bufferView);
      mark_view(acc.sparse.values.bufferView);
    }
  }
  for (const tg::Image& image : model.images) mark_view(image.bufferView);

  // Surviving bufferViews are copied byte for byte (images included) into the new buffer.
  std::vector<uint8_t> bin;
  std::vector<tg::BufferView> views;
  for (size_t v = 0; v < view_remap.size(); ++v) {
    if (view_remap[v] != 0) continue;
    tg::BufferView view = std::move(model.bufferViews[v]);
    const std::vector<unsigned char>& data = model.buffers[size_t(view.buffer)].data;
    bin.resize((bin.size() + 3) & ~size_t(3), 0);
    const size_t offset = bin.size();
    bin.insert(bin.end(), data.begin() + ptrdiff_t(view.byteOffset), data.begin() + ptrdiff_t(view.byteOffset + view.byteLength));
    view.buffer = 0;
    view.byteOffset = offset;
    view_remap[v] = int(views.size());
    views.push_back(std::move(view));
  }

  auto remap = [](int& index, const std::vector<int>& table) {
    if (index >= 0) index = table[size_t(index)];
  };
  for (tg::Accessor& acc : accessors) {
    remap(acc.bufferView, view_remap);
    if (acc.sparse.isSparse) {
      remap(acc.sparse.indices.bufferView, view_remap);
      remap(acc.sparse.values.bufferView, view_remap);
    }
  }
  for (tg::Image& image : model.images) remap(image.bufferView, view_remap);
  for (tg::Mesh& mesh : model.meshes)
    for (tg::Primitive& prim : mesh.primitives) {
      for (auto& attribute : prim.attributes) remap(attribute.second, accessor_remap);
      remap(prim.indices, accessor_remap);
      for (auto& target : prim.targets)
        for (auto& attribute : target) remap(attribute.second, accessor_remap);
    }
  for (tg::Skin& skin : model.skins) remap(skin.inverseBindMatrices, accessor_remap);
  for (tg::Node& node : model.nodes)
    for_each_instancing_accessor(node, accessor_remap.size(), [&](int& index) { remap(index, accessor_remap); });
  for (tg::Animation& anim : model.animations)
    for (tg::AnimationSampler& sampler : anim.samplers) {
      remap(sampler.input, accessor_remap);
      remap(sampler.output, accessor_remap);
    }
  model.accessors = std::move(accessors);
  model.bufferViews = std::move(views);
  model.buffers.clear();

  BinWriter writer(model, bin);
  std::vector<const tg::Primitive*> written(scene.primitives.size(), nullptr);
  std::vector<size_t> written_mesh(scene.primitives.size(), 0);
  std::vector<const UvBoxes*> written_boxes(scene.primitives.size(), nullptr);
  for (size_t i = 0; i < pending.size(); ++i) {
    const Pending& p = pending[i];
    const Primitive& in = scene.primitives[p.scene_primitive];
    tg::Primitive& out = model.meshes[p.mesh].primitives[p.primitive];
    const int32_t shared = in.shares_vertices_with;
    std::vector<Gathered>& extra = gathered[p.scene_primitive];
    const UvBoxes* boxes = uv_boxes.empty() ? nullptr : &uv_boxes[i];
    const StreamCoding coding{options.quantize, on_grid[p.mesh] ? &grid : nullptr, boxes, options.normal_bits ? options.normal_bits : 8,
                              options.compress_more && options.meshopt_compression ? &directions : nullptr};
    if (options.draco) {
      // Each primitive its own stream (Draco has no shared vertex buffers); the gathered streams
      // outside it follow its vertices.
      io::DracoBits bits;  // its defaults where the options leave the bits at 0
      bits.position = options.position_bits;
      if (options.normal_bits) bits.normal = options.normal_bits;
      if (options.uv_bits) bits.uv = options.uv_bits;
      const std::vector<uint32_t> point_source = writer.add_draco_geometry(in.mesh, in.targets, out, bits, !extra.empty(), coding);
      if (!point_source.empty())
        for (Gathered& g : extra) g.bytes = gather_elements(g.bytes, element_bytes(g.like.componentType, g.like.type), point_source);
    } else if (shared >= 0 && written[size_t(shared)] && out.attributes.empty() && out.targets.empty() && extra.empty() &&
        on_grid[written_mesh[size_t(shared)]] == on_grid[p.mesh] &&
        (written_boxes[size_t(shared)] ? *written_boxes[size_t(shared)] : UvBoxes{}) == (boxes ? *boxes : UvBoxes{})) {
      // One vertex buffer, several index buffers; each morph target too where it is the same
      // (--shared-vertices' blend shapes), else the primitive's own (each level's geomorph).
      out.attributes = written[size_t(shared)]->attributes;
      const std::vector<MorphTarget>& theirs = scene.primitives[size_t(shared)].targets;
      for (size_t k = 0; k < in.targets.size(); ++k)
        if (k < theirs.size() && k < written[size_t(shared)]->targets.size() && in.targets[k] == theirs[k])
          out.targets.push_back(written[size_t(shared)]->targets[k]);
        else writer.add_targets(in.mesh, {in.targets[k]}, out, coding);
      writer.add_indices(in.mesh, out);
    } else {
      writer.add_geometry(in.mesh, in.targets, out, coding);
    }
    for (const Gathered& g : extra) {
      if (g.target >= int(out.targets.size())) continue;  // the mesh lost its morph targets (another primitive)
      int index;
      // Quantized, a source's own target displacements are stored as lodkit's own are.
      const bool position = g.semantic == "POSITION" && coding.grid, direction = g.semantic == "NORMAL" || g.semantic == "TANGENT";
      if (g.target >= 0 && g.like.type == TINYGLTF_TYPE_VEC3 && (position || (direction && coding.quantize))) {
        const size_t element = element_bytes(g.like.componentType, g.like.type), size = component_bytes(g.like.componentType);
        std::vector<float3> d(element ? g.bytes.size() / element : 0);
        for (size_t v = 0; v < d.size(); ++v) {
          const uint8_t* e = g.bytes.data() + v * element;
          d[v] = {component_float(e, g.like.componentType, g.like.normalized), component_float(e + size, g.like.componentType, g.like.normalized),
                  component_float(e + 2 * size, g.like.componentType, g.like.normalized)};
        }
        index = position ? writer.add_displacements(d, coding.grid) : writer.add_direction_offsets(d, coding);
      } else {
        index = writer.add_vertex_stream(g.bytes, g.like, !g.like.minValues.empty() && !g.like.maxValues.empty());
      }
      if (g.target < 0) out.attributes[g.semantic] = index;
      else out.targets[size_t(g.target)][g.semantic] = index;
    }
    written[p.scene_primitive] = &out;
    written_mesh[p.scene_primitive] = p.mesh;
    written_boxes[p.scene_primitive] = boxes;
  }
  for (const GridInstances& g : grid_instances) {
    tg::Value::Object ext = model.nodes[g.node].extensions[gpu_instancing].Get<tg::Value::Object>();
    tg::Value::Object attributes = ext["attributes"].Get<tg::Value::Object>();
    attributes["TRANSLATION"] = tg::Value(writer.add_accessor(g.translation, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 0));
    attributes["SCALE"] = tg::Value(writer.add_accessor(g.scale, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 0));
    ext["attributes"] = tg::Value(std::move(attributes));
    model.nodes[g.node].extensions[gpu_instancing] = tg::Value(std::move(ext));
  }
  {
    // One bufferView per kind of data (times, float3 keys, rotations in shorts or floats), each
    // accessor at its offset: a few views instead of one or two per sampler, as each view costs its
    // JSON and, under -c, a compressed stream of its own.
    std::map<size_t, std::vector<uint8_t>> pools;  // by element size
    std::vector<std::pair<int, size_t>> pooled;    // (accessor, element size)
    const auto add = [&](const void* data, size_t count, size_t element, int component_type, int type, bool normalized) {
      std::vector<uint8_t>& pool = pools[element];
      tg::Accessor acc;
      acc.byteOffset = pool.size();
      acc.componentType = component_type, acc.type = type, acc.count = count, acc.normalized = normalized;
      pool.insert(pool.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + count * element);
      model.accessors.push_back(std::move(acc));
      pooled.emplace_back(int(model.accessors.size() - 1), element);
      return int(model.accessors.size() - 1);
    };
    std::map<std::vector<float>, int> inputs;  // reduced key times -> their accessor
    for (const SamplerKeys& keys : sampler_keys) {
      tg::AnimationSampler& sampler = model.animations[keys.animation].samplers[keys.sampler];
      if (!keys.times.empty()) {
        const auto [found, fresh] = inputs.try_emplace(keys.times, -1);
        if (fresh) {
          found->second = add(keys.times.data(), keys.times.size(), 4, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, false);
          tg::Accessor& acc = model.accessors[size_t(found->second)];  // (sampler inputs need bounds)
          acc.minValues = {*std::min_element(keys.times.begin(), keys.times.end())};
          acc.maxValues = {*std::max_element(keys.times.begin(), keys.times.end())};
        }
        sampler.input = found->second;
      }
      const size_t count = keys.values.size() / keys.components;
      if (keys.shorts) {
        const std::vector<uint8_t> packed = snorm<int16_t>(keys.values);
        sampler.output = add(packed.data(), count, 8, TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_TYPE_VEC4, true);
      } else {  // (a SCALAR output holds `components` scalars a key)
        const size_t per_element = type_components(keys.type);
        sampler.output = add(keys.values.data(), keys.values.size() / per_element, 4 * per_element, TINYGLTF_COMPONENT_TYPE_FLOAT,
                             keys.type, false);
      }
    }
    std::map<size_t, int> pool_view;
    for (const auto& [element, bytes] : pools) pool_view[element] = writer.add_view(bytes.data(), bytes.size(), 0);
    for (const auto& [accessor, element] : pooled) model.accessors[size_t(accessor)].bufferView = pool_view[element];
  }
  if (std::find(on_grid.begin(), on_grid.end(), true) != on_grid.end()) place_position_grid(model, bin, writer, grid, on_grid);
  // All are required: without them the streams would be read wrong (a UV box's transform places
  // the textures).
  for (const auto& [used, ext] : {std::pair{writer.used_draco(), io::draco_extension}, std::pair{writer.used_quantization(), "KHR_mesh_quantization"},
                                  std::pair{used_uv_boxes, texture_transform}})
    if (used)
      for (std::vector<std::string>* list : {&model.extensionsUsed, &model.extensionsRequired}) declare_extension(*list, ext);
  report = writer.report();
  return bin;
}

// Strings written by tinygltf must be valid UTF-8 (nlohmann::json refuses to dump anything else);
// names from OBJ or PLY files may be Latin-1.
std::string valid_utf8(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size();) {
    const auto c = uint8_t(s[i]);
    size_t len = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    bool ok = len != 0 && i + len <= s.size();
    for (size_t k = 1; ok && k < len; ++k) ok = (uint8_t(s[i + k]) & 0xC0) == 0x80;
    if (ok) {
      out.append(s, i, len);
      i += len;
    } else {
      out += "\xEF\xBF\xBD";  // U+FFFD
      ++i;
    }
  }
  return out;
}

// nlohmann::json -> tinygltf::Value (extras written from JSON text).
tg::Value json_to_value(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::object: {
      tg::Value::Object object;
      for (const auto& [key, value] : j.items()) object[key] = json_to_value(value);
      return tg::Value(std::move(object));
    }
    case nlohmann::json::value_t::array: {
      tg::Value::Array array;
      for (const auto& value : j) array.push_back(json_to_value(value));
      return tg::Value(std::move(array));
    }
    case nlohmann::json::value_t::string: return tg::Value(j.get<std::string>());
    case nlohmann::json::value_t::boolean: return tg::Value(j.get<bool>());
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned: return tg::Value(int(j.get<int64_t>()));
    case nlohmann::json::value_t::number_float: return tg::Value(j.get<double>());
    default: return tg::Value();
  }
}

// Skins and animations of a Scene without source, as accessors over model.buffers[0] (which
// rebuild_geometry then packs with the geometry). Everything a validator would reject is refused
// with a usage error naming the skin or channel: lodkit writes only valid glTF.
class SkinAnimationWriter {
 public:
  explicit SkinAnimationWriter(tg::Model& model) : model_(model) {
    model_.buffers.resize(1);
  }

  void add_skins(const Scene& scene) {
    const size_t nodes = scene.nodes.size();
    for (size_t s = 0; s < scene.skins.size(); ++s) {
      const Skin& in = scene.skins[s];
      const std::string where = "cannot write glTF: skins[" + str(s) + "]";
      if (in.joints.empty()) throw_usage(where + " has no joints");
      tg::Skin skin;
      skin.name = valid_utf8(in.name);
      for (const int32_t joint : in.joints) {
        if (joint < 0 || size_t(joint) >= nodes) throw_usage(where + " has joint node " + std::to_string(joint) + " of " + str(nodes));
        skin.joints.push_back(joint);
      }
      if (in.skeleton >= 0) {
        if (size_t(in.skeleton) >= nodes) throw_usage(where + " has skeleton node " + std::to_string(in.skeleton) + " of " + str(nodes));
        skin.skeleton = in.skeleton;
      }
      // No matrices means identities in glTF too.
      if (!in.inverse_bind_matrices.empty()) {
        if (in.inverse_bind_matrices.size() != in.joints.size())
          throw_usage(where + " has " + str(in.inverse_bind_matrices.size()) + " inverse bind matrices for " +
                      str(in.joints.size()) + " joints");
        std::vector<float> flat;
        flat.reserve(16 * in.inverse_bind_matrices.size());
        for (const auto& m : in.inverse_bind_matrices) {
          for (const float v : m)
            if (!std::isfinite(v)) throw_usage(where + " has a non-finite inverse bind matrix");
          // glTF requires affine matrices (last row 0 0 0 1).
          if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) throw_usage(where + " has an inverse bind matrix that is not affine");
          flat.insert(flat.end(), m.begin(), m.end());
        }
        skin.inverseBindMatrices = add_accessor(flat, TINYGLTF_TYPE_MAT4);
      }
      model_.skins.push_back(std::move(skin));
    }
  }

  void add_animations(const Scene& scene) {
    for (size_t a = 0; a < scene.animations.size(); ++a) {
      const Animation& in = scene.animations[a];
      tg::Animation anim;
      anim.name = valid_utf8(in.name);
      std::vector<std::pair<const std::vector<float>*, int>> inputs;  // key times already written
      std::vector<std::pair<int32_t, AnimationPath>> targets;
      for (size_t c = 0; c < in.channels.size(); ++c) {
        const AnimationChannel& ch = in.channels[c];
        const std::string where = "cannot write glTF: animations[" + str(a) + "].channels[" + str(c) + "]";
        check_channel(ch, scene, where);
        // glTF allows one channel per node and property in an animation.
        const std::pair<int32_t, AnimationPath> target{ch.node, ch.path};
        if (std::find(targets.begin(), targets.end(), target) != targets.end())
          throw_usage(where + " animates the same node and property as an earlier channel");
        targets.push_back(target);
        // Channels with the same key times share one input accessor.
        int input = -1;
        for (const auto& [times, accessor] : inputs)
          if (*times == ch.times) input = accessor;
        if (input < 0) {
          input = add_accessor(ch.times, TINYGLTF_TYPE_SCALAR, true);  // (bounds: required for sampler inputs)
          inputs.push_back({&ch.times, input});
        }
        tg::AnimationSampler sampler;
        sampler.input = input;
        sampler.output = add_accessor(ch.values, path_output_type(ch.path));
        sampler.interpolation = interpolation_name(ch.interpolation);
        anim.samplers.push_back(std::move(sampler));
        tg::AnimationChannel channel;
        channel.sampler = int(anim.samplers.size() - 1);
        channel.target_node = ch.node;
        channel.target_path = path_name(ch.path);
        anim.channels.push_back(std::move(channel));
      }
      if (anim.channels.empty()) throw_usage("cannot write glTF: animations[" + str(a) + "] has no channels");
      model_.animations.push_back(std::move(anim));
    }
  }

 private:
  void check_channel(const AnimationChannel& ch, const Scene& scene, const std::string& where) const {
    if (ch.node < 0 || size_t(ch.node) >= scene.nodes.size())
      throw_usage(where + " targets node " + std::to_string(ch.node) + " of " + str(scene.nodes.size()));
    if (scene.nodes[size_t(ch.node)].has_matrix) throw_usage(where + " animates a node given by a matrix");
    const size_t expected = ch.path == AnimationPath::rotation ? 4 : ch.path == AnimationPath::weights ? ch.components : 3;
    if (ch.components != expected || ch.components == 0)
      throw_usage(where + " has " + str(ch.components) + " components per key");
    if (ch.times.empty()) throw_usage(where + " has no keys");
    for (size_t k = 0; k < ch.times.size(); ++k)
      if (!std::isfinite(ch.times[k]) || ch.times[k] < 0 || (k > 0 && !(ch.times[k] > ch.times[k - 1])))
        throw_usage(where + ": key times must be finite, non-negative and increasing (key " + str(k) + ")");
    const size_t per_key = (ch.interpolation == Interpolation::cubic_spline ? 3 : 1) * size_t(ch.components);
    if (ch.values.size() % per_key != 0 || ch.values.size() / per_key != ch.times.size())
      throw_usage(where + " has " + str(ch.values.size()) + " values for " + str(ch.times.size()) + " keys");
    for (const float v : ch.values)
      if (!std::isfinite(v)) throw_usage(where + " has a non-finite value");
  }

  // A float accessor in its own bufferView of buffer 0.
  int add_accessor(const std::vector<float>& values, int type, bool bounds = false) {
    return append_float_accessor(model_, model_.buffers[0], 0, values, type, bounds);
  }

  tg::Model& model_;
};

// The MSFT_lod ids and the extras of a node. Ids are written as given (the reader fills them, so a
// node read and written keeps its own): none removes a source node's MSFT_lod, whose levels may no
// longer exist; other members of its MSFT_lod object are kept. Empty extras leave the node's as
// they were.
// A node's own extensions and extras as the Scene has them: MSFT_lod ids, KHR_node_visibility (a
// hidden node says so, a node shown again says that; other keys of the extension stay), extras.
void set_node_extensions(tg::Model& model, const Node& in, tg::Node& node) {
  if (in.lod_ids.empty()) {
    node.extensions.erase("MSFT_lod");
  } else {
    tg::Value::Array ids;
    for (const int32_t id : in.lod_ids) ids.emplace_back(int(id));
    const auto old = node.extensions.find("MSFT_lod");
    tg::Value::Object lod = old != node.extensions.end() && old->second.IsObject() ? old->second.Get<tg::Value::Object>()
                                                                                     : tg::Value::Object{};
    lod["ids"] = tg::Value(std::move(ids));
    node.extensions["MSFT_lod"] = tg::Value(std::move(lod));
    declare_extension(model.extensionsUsed, "MSFT_lod");
  }
  const auto shown = node.extensions.find(node_visibility);
  const bool hidden_now = shown != node.extensions.end() && shown->second.IsObject() && shown->second.Has("visible") &&
                          shown->second.Get("visible").IsBool() && !shown->second.Get("visible").Get<bool>();
  if (!in.visible || hidden_now) {
    tg::Value::Object visibility = shown != node.extensions.end() && shown->second.IsObject()
                                       ? shown->second.Get<tg::Value::Object>()
                                       : tg::Value::Object{};
    visibility["visible"] = tg::Value(in.visible);
    node.extensions[node_visibility] = tg::Value(std::move(visibility));
    declare_extension(model.extensionsUsed, node_visibility);
  }
  if (in.extras_json.empty()) return;
  const nlohmann::json extras = nlohmann::json::parse(in.extras_json);
  // An empty object removes the source's extras rather than writing "extras": {}.
  node.extras = extras.is_object() && extras.empty() ? tg::Value() : json_to_value(extras);
}

void set_transform(const Node& in, tg::Node& node) {
  if (in.has_matrix) {
    const std::array<float, 16> identity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    if (in.matrix != identity) node.matrix.assign(in.matrix.begin(), in.matrix.end());
  } else {
    if (in.translation != float3{}) node.translation = {in.translation.x, in.translation.y, in.translation.z};
    if (in.rotation != float4{0, 0, 0, 1}) node.rotation = {in.rotation.x, in.rotation.y, in.rotation.z, in.rotation.w};
    if (in.scale != float3{1, 1, 1}) node.scale = {in.scale.x, in.scale.y, in.scale.z};
  }
}

// A new node drawn once per instance (lodkit lod's levels of an instanced mesh, or a scene built in
// memory): EXT_mesh_gpu_instancing with its own TRANSLATION, ROTATION and SCALE accessors, whose
// data goes into `data`, the model's next buffer.
void add_gpu_instances(tg::Model& model, tg::Buffer& data, const Node& in, tg::Node& node) {
  if (in.gpu_instances.empty() || node.mesh < 0) return;
  std::vector<float> translation, rotation, scale;
  for (const Node::GpuInstance& g : in.gpu_instances) {
    translation.insert(translation.end(), {g.translation.x, g.translation.y, g.translation.z});
    rotation.insert(rotation.end(), {g.rotation.x, g.rotation.y, g.rotation.z, g.rotation.w});
    scale.insert(scale.end(), {g.scale.x, g.scale.y, g.scale.z});
  }
  const int buffer = int(model.buffers.size());
  tg::Value::Object attributes;
  attributes["TRANSLATION"] = tg::Value(append_float_accessor(model, data, buffer, translation, TINYGLTF_TYPE_VEC3, false));
  attributes["ROTATION"] = tg::Value(append_float_accessor(model, data, buffer, rotation, TINYGLTF_TYPE_VEC4, false));
  attributes["SCALE"] = tg::Value(append_float_accessor(model, data, buffer, scale, TINYGLTF_TYPE_VEC3, false));
  tg::Value::Object ext;
  ext["attributes"] = tg::Value(std::move(attributes));
  node.extensions[gpu_instancing] = tg::Value(std::move(ext));
  declare_extension(model.extensionsUsed, gpu_instancing);
}

// New node `i`'s morph weights, from the source nodes whose targets its mesh has in turn
// (Node::morph_weights_of). One node's weights and weight channels are copied (the same samplers).
// Several nodes' are concatenated: their rest weights (a node's own, else its mesh's, else 0), and
// per clip one channel (lod::concatenate_weights over the decoded clips of `scene`, which lists the
// source's animations in order) whose keys go into `data`, the model's next buffer. New nodes
// taking the same nodes' weights (a chain's levels) share that channel's sampler: `merged_samplers`
// holds it per (clip, source nodes), or -1 where the nodes have none.
using MergedSamplers = std::map<std::pair<size_t, std::vector<int32_t>>, int>;
void take_morph_weights(tg::Model& model, const Scene& scene, const std::vector<int32_t>& of, size_t i, size_t source_nodes,
                        tg::Node& node, tg::Buffer& data, MergedSamplers& merged_samplers) {
  if (of.empty() || (of.size() == 1 && of[0] < 0)) return;
  for (const int32_t s : of)
    if (s < 0 || size_t(s) >= source_nodes)
      throw_usage("cannot write glTF: nodes[" + str(i) + "] takes the morph weights of a node the source does not have");
  if (of.size() == 1) {
    const tg::Node& other = model.nodes[size_t(of[0])];
    node.weights = !other.weights.empty() || other.mesh < 0 ? other.weights : model.meshes[size_t(other.mesh)].weights;
    // The clips that drive the other node's weights drive this one's too (the same samplers): its
    // own channels, and its mesh's (a KHR_animation_pointer "/meshes/M/weights", float keys) where
    // it has no weights of its own, as core channels.
    for (tg::Animation& anim : model.animations) {
      const size_t channels = anim.channels.size();
      for (size_t c = 0; c < channels; ++c) {
        const tg::AnimationChannel& ch = anim.channels[c];
        const ChannelTarget t = channel_target(ch);
        const bool own = ch.target_node == of[0] && ch.target_path == "weights";
        const bool mesh = t.list == "meshes" && t.property == "weights" && t.index == other.mesh && other.weights.empty();
        if (!own && !mesh) continue;
        tg::AnimationChannel copy = ch;  // (its extras too)
        copy.target_node = int(i);
        copy.target_path = "weights";
        copy.target_extensions.erase(animation_pointer);
        anim.channels.push_back(std::move(copy));
      }
    }
    return;
  }
  std::vector<WeightsSource> sources(of.size());
  bool weighted = false;  // a source node or mesh has weights: the new node lists them all
  for (size_t k = 0; k < of.size(); ++k) {
    const tg::Node& other = model.nodes[size_t(of[k])];
    size_t count = 0;
    std::vector<double> rest = other.weights;
    if (other.mesh >= 0 && size_t(other.mesh) < model.meshes.size()) {
      const tg::Mesh& mesh = model.meshes[size_t(other.mesh)];
      for (const tg::Primitive& prim : mesh.primitives) count = std::max(count, prim.targets.size());
      if (rest.empty()) rest = mesh.weights;
    }
    weighted = weighted || !rest.empty();
    rest.resize(count, 0.0);
    sources[k].rest.assign(rest.begin(), rest.end());
  }
  if (weighted)
    for (const WeightsSource& s : sources) node.weights.insert(node.weights.end(), s.rest.begin(), s.rest.end());
  for (size_t a = 0; a < model.animations.size() && a < scene.animations.size(); ++a) {
    tg::Animation& anim = model.animations[a];
    const auto [known, fresh] = merged_samplers.try_emplace({a, of}, -1);
    if (fresh) {
      for (size_t k = 0; k < of.size(); ++k) sources[k].channel = weights_channel(scene.animations[a], of[k]);
      const std::optional<AnimationChannel> merged = concatenate_weights(sources);
      if (!merged) continue;  // no clip of theirs, or one the merge cannot follow exactly (lodkit lod says so)
      tg::AnimationSampler sampler;
      sampler.input = append_float_accessor(model, data, int(model.buffers.size()), merged->times, TINYGLTF_TYPE_SCALAR, true);
      sampler.output = append_float_accessor(model, data, int(model.buffers.size()), merged->values, TINYGLTF_TYPE_SCALAR, false);
      sampler.interpolation = interpolation_name(merged->interpolation);
      known->second = int(anim.samplers.size());
      anim.samplers.push_back(std::move(sampler));
    }
    if (known->second < 0) continue;
    tg::AnimationChannel channel;
    channel.sampler = known->second;
    channel.target_node = int(i);
    channel.target_path = "weights";
    anim.channels.push_back(std::move(channel));
  }
}

// A scene read from glTF may grow (lodkit lod on a skinned character adds a mesh and a node per
// level): primitives past the source's meshes become new meshes (with the source's materials),
// nodes past the source's nodes are appended (name, transform, mesh, skin, GPU instances, MSFT_lod,
// visibility and extras; a child of its parent, in the default scene if Scene::roots lists it), and
// MSFT_lod ids, visibility, extras and a new mesh set on the source's own nodes are applied.
// Everything else of the source stays as it was.
void add_to_source(tg::Model& model, const Scene& scene) {
  const size_t source_meshes = model.meshes.size();
  for (size_t i = 0; i < scene.primitives.size(); ++i) {
    const Primitive& prim = scene.primitives[i];
    if (prim.gltf_mesh < source_meshes) continue;
    const std::string where = "cannot write glTF: scene primitive " + str(i);
    // New meshes and primitives are numbered densely after the source's: a bound keeps a bad index
    // from allocating without limit.
    if (prim.gltf_mesh >= source_meshes + scene.primitives.size() || prim.gltf_primitive >= scene.primitives.size())
      throw_usage(where + " asks for a new glTF mesh or primitive beyond what the scene can fill");
    if (model.meshes.size() <= prim.gltf_mesh) model.meshes.resize(size_t(prim.gltf_mesh) + 1);
    std::vector<tg::Primitive>& prims = model.meshes[prim.gltf_mesh].primitives;
    if (prims.size() <= prim.gltf_primitive) prims.resize(size_t(prim.gltf_primitive) + 1);
    prims[prim.gltf_primitive].mode = TINYGLTF_MODE_TRIANGLES;
    prims[prim.gltf_primitive].material = prim.material;
  }
  for (size_t m = source_meshes; m < model.meshes.size(); ++m)
    if (model.meshes[m].primitives.empty()) throw_usage("cannot write glTF: new mesh " + str(m) + " has no primitive");

  const size_t source_nodes = model.nodes.size();
  if (scene.nodes.size() < source_nodes) return;  // a scene that lost nodes adds none
  tg::Buffer new_data;  // new nodes' instances and merged weight clips
  MergedSamplers merged_samplers;
  const auto known_mesh = [&](size_t i, int32_t mesh) {
    if (size_t(mesh) >= model.meshes.size()) throw_usage("cannot write glTF: nodes[" + str(i) + "] uses a mesh the document does not have");
    return int(mesh);
  };
  for (size_t i = 0; i < scene.nodes.size(); ++i) {
    const Node& in = scene.nodes[i];
    if (i < source_nodes) {
      // A source node may draw a new mesh instead of its own (lodkit lod on its own output gives an
      // earlier first level the new one; its weights and their clips stay, fitted to the new targets).
      if (in.mesh >= int32_t(source_meshes)) model.nodes[i].mesh = known_mesh(i, in.mesh);
      set_node_extensions(model, in, model.nodes[i]);
      continue;
    }
    tg::Node node;
    node.name = valid_utf8(in.name);
    if (in.mesh >= 0) {
      node.mesh = known_mesh(i, in.mesh);
      if (in.skin >= 0) {
        if (size_t(in.skin) >= model.skins.size()) throw_usage("cannot write glTF: nodes[" + str(i) + "] uses a skin the document does not have");
        node.skin = in.skin;
      }
    }
    take_morph_weights(model, scene, in.morph_weights_of, i, source_nodes, node, new_data, merged_samplers);
    add_gpu_instances(model, new_data, in, node);
    set_node_extensions(model, in, node);
    set_transform(in, node);
    model.nodes.push_back(std::move(node));
    if (in.parent >= 0 && size_t(in.parent) < i) model.nodes[size_t(in.parent)].children.push_back(int(i));
  }
  if (!new_data.data.empty()) model.buffers.push_back(std::move(new_data));
  const auto is_new_root = [&](int32_t root) {
    return root >= 0 && size_t(root) >= source_nodes && size_t(root) < model.nodes.size() && scene.nodes[size_t(root)].parent < 0;
  };
  if (model.scenes.empty()) {
    // A source without scenes: viewers would show nothing of the new nodes. One scene, with the
    // source's root nodes and the new ones.
    if (std::none_of(scene.roots.begin(), scene.roots.end(), is_new_root)) return;
    std::vector<bool> child(source_nodes, false);
    for (size_t n = 0; n < source_nodes; ++n)
      for (const int c : model.nodes[n].children)
        if (c >= 0 && size_t(c) < source_nodes) child[size_t(c)] = true;
    tg::Scene all;
    for (size_t n = 0; n < source_nodes; ++n)
      if (!child[n]) all.nodes.push_back(int(n));
    model.scenes.push_back(std::move(all));
    model.defaultScene = 0;
  }
  std::vector<int>& roots = model.scenes[size_t(std::max(0, model.defaultScene))].nodes;
  for (const int32_t root : scene.roots)
    if (is_new_root(root)) roots.push_back(root);
}

// A minimal document for a Scene without source: meshes by gltf_mesh, materials named from
// material_names, the Scene's nodes (or one node per mesh) with their skins, the animations, one scene.
tg::Model model_from_scene(const Scene& scene, std::vector<Slot>& slots) {
  tg::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "lodkit";
  std::map<uint32_t, int> dense_mesh;  // gltf_mesh -> index in model.meshes, by first appearance
  int max_material = -1;
  for (const Primitive& prim : scene.primitives) {
    auto [it, inserted] = dense_mesh.try_emplace(prim.gltf_mesh, int(model.meshes.size()));
    if (inserted) model.meshes.emplace_back();
    tg::Primitive out;
    out.mode = TINYGLTF_MODE_TRIANGLES;
    out.material = prim.material;
    tg::Mesh& mesh = model.meshes[size_t(it->second)];
    slots.push_back({it->second, int(mesh.primitives.size())});
    mesh.primitives.push_back(std::move(out));
    max_material = std::max(max_material, prim.material);
  }
  // Materials are created densely up to the largest index used; refuse an index that cannot be real.
  if (size_t(max_material + 1) > scene.primitives.size() + scene.material_names.size())
    throw_usage("cannot write glTF: material index " + std::to_string(max_material) + " is larger than the scene's " +
                str(scene.material_names.size()) + " material names");
  for (int m = 0; m <= max_material; ++m) {
    tg::Material material;
    if (size_t(m) < scene.material_names.size()) material.name = valid_utf8(scene.material_names[size_t(m)]);
    if (size_t(m) < scene.material_looks.size()) {
      const MaterialLook& look = scene.material_looks[size_t(m)];
      const float4& c = look.base_color;
      material.pbrMetallicRoughness.baseColorFactor = {c.x, c.y, c.z, c.w};
      material.pbrMetallicRoughness.metallicFactor = look.metallic;
      material.pbrMetallicRoughness.roughnessFactor = look.roughness;
      material.emissiveFactor = {look.emissive.x, look.emissive.y, look.emissive.z};
      if (c.w < 1) material.alphaMode = "BLEND";
    }
    model.materials.push_back(std::move(material));
  }
  tg::Scene out_scene;
  if (!scene.nodes.empty()) {
    for (const Node& in : scene.nodes) {
      tg::Node node;
      node.name = valid_utf8(in.name);
      if (in.mesh >= 0) {
        auto it = dense_mesh.find(uint32_t(in.mesh));
        if (it != dense_mesh.end()) node.mesh = it->second;
      }
      // glTF: a skin belongs to a node with a mesh.
      if (in.skin >= 0) {
        if (size_t(in.skin) >= scene.skins.size())
          throw_usage("cannot write glTF: nodes[" + str(model.nodes.size()) + "] uses skin " + std::to_string(in.skin) + " of " +
                      str(scene.skins.size()));
        if (node.mesh >= 0) node.skin = in.skin;
      }
      for (int32_t child : in.children)
        if (child >= 0 && size_t(child) < scene.nodes.size()) node.children.push_back(child);
      set_node_extensions(model, in, node);
      set_transform(in, node);
      model.nodes.push_back(std::move(node));
    }
    for (int32_t root : scene.roots)
      if (root >= 0 && size_t(root) < scene.nodes.size()) out_scene.nodes.push_back(root);
    if (out_scene.nodes.empty())
      for (size_t n = 0; n < scene.nodes.size(); ++n)
        if (scene.nodes[n].parent < 0) out_scene.nodes.push_back(int(n));
    if (!scene.skins.empty() || !scene.animations.empty()) {
      SkinAnimationWriter writer(model);
      writer.add_skins(scene);
      writer.add_animations(scene);
    }
    tg::Buffer instances;
    for (size_t n = 0; n < scene.nodes.size(); ++n) add_gpu_instances(model, instances, scene.nodes[n], model.nodes[n]);
    if (!instances.data.empty()) model.buffers.push_back(std::move(instances));
  } else {
    for (size_t m = 0; m < model.meshes.size(); ++m) {
      tg::Node node;
      node.mesh = int(m);
      model.nodes.push_back(std::move(node));
      out_scene.nodes.push_back(int(m));
    }
  }
  model.scenes.push_back(std::move(out_scene));
  model.defaultScene = 0;
  return model;
}

// RFC 3986 unreserved characters stay, everything else is percent-encoded.
std::string uri_escape(const std::string& s) {
  static const char hex[] = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out += char(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

// tinygltf serializes everything but the buffer (the model has none); the one buffer is added here.
Json serialize_json(const tg::Model& model, size_t bin_size, const std::string& bin_uri) {
  const bool needs_buffer = bin_size > 0 || !model.bufferViews.empty();
  tg::TinyGLTF writer;
  writer.SetImageWriter(&write_image_uri, nullptr);
  std::ostringstream stream;
  try {
    if (!writer.WriteGltfSceneToStream(&model, stream, false, false)) throw_internal("glTF: tinygltf could not serialize the scene");
    Json doc = Json::parse(stream.str());
    // tinygltf writes an object with nothing to say (a bare node, an empty scene) as null.
    for (auto& [key, value] : doc.items())
      if (value.is_array())
        for (Json& element : value)
          if (element.is_null()) element = Json::object();
    // It also writes a perspective camera's absent zfar (an infinite projection) as 0, which glTF
    // forbids.
    if (doc.contains("cameras") && doc["cameras"].is_array())
      for (Json& camera : doc["cameras"])
        if (camera.contains("perspective") && camera["perspective"].is_object()) {
          Json& perspective = camera["perspective"];
          if (perspective.contains("zfar") && perspective["zfar"].is_number() && perspective["zfar"].get<double>() == 0)
            perspective.erase("zfar");
        }
    // An animation sampler's LINEAR interpolation is glTF's default: left out, as gltfpack does
    // (26 bytes a sampler; a baked character's clip has one per joint and property).
    // A channel's node -1 stands in for none (KHR_animation_pointer's channels): left out again.
    if (doc.contains("animations") && doc["animations"].is_array())
      for (Json& animation : doc["animations"]) {
        if (animation.contains("samplers") && animation["samplers"].is_array())
          for (Json& sampler : animation["samplers"])
            if (sampler.is_object() && sampler.value("interpolation", "") == "LINEAR") sampler.erase("interpolation");
        if (animation.contains("channels") && animation["channels"].is_array())
          for (Json& channel : animation["channels"])
            if (channel.is_object() && channel.contains("target") && channel["target"].is_object()) {
              Json& target = channel["target"];
              if (target.contains("node") && target["node"].is_number_integer() && target["node"].get<int64_t>() < 0) target.erase("node");
            }
      }
    if (needs_buffer) {
      Json buffer = {{"byteLength", bin_size}};
      if (!bin_uri.empty()) buffer["uri"] = bin_uri;
      doc["buffers"] = Json::array({std::move(buffer)});
    }
    return doc;
  } catch (const Json::exception& e) {
    throw_internal(std::string("glTF: serializing the scene failed: ") + e.what());
  }
}

std::string dump_json(const Json& doc, bool pretty) { return doc.dump(pretty ? 2 : -1) + (pretty ? "\n" : ""); }

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

std::vector<uint8_t> make_glb(const std::string& json_text, const std::vector<uint8_t>& bin, const std::string& name) {
  const size_t json_padded = (json_text.size() + 3) & ~size_t(3);
  const size_t bin_padded = (bin.size() + 3) & ~size_t(3);
  const uint64_t total = 12 + 8 + uint64_t(json_padded) + (bin.empty() ? 0 : 8 + uint64_t(bin_padded));
  if (total > std::numeric_limits<uint32_t>::max()) throw_usage(name + ": scene does not fit the 4 GiB GLB limit");
  std::vector<uint8_t> out;
  out.reserve(size_t(total));
  put_u32(out, glb_magic);
  put_u32(out, 2);
  put_u32(out, uint32_t(total));
  put_u32(out, uint32_t(json_padded));
  put_u32(out, glb_chunk_json);
  out.insert(out.end(), json_text.begin(), json_text.end());
  out.resize(out.size() + json_padded - json_text.size(), ' ');  // JSON chunks pad with spaces
  if (!bin.empty()) {
    put_u32(out, uint32_t(bin_padded));
    put_u32(out, glb_chunk_bin);
    out.insert(out.end(), bin.begin(), bin.end());
    out.resize(out.size() + bin_padded - bin.size(), 0);
  }
  return out;
}

bool has_glb_extension(const std::string& name) {
  if (name.size() < 4) return false;
  std::string ext = name.substr(name.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".glb";
}

}  // namespace

std::string uri_decode(const std::string& s);     // (below, with the writer's URI helpers)
bool relative_file_uri(const std::string& uri);

namespace {

// The image a material's texture slot shows, when it maps as a mesh's MaterialLook can say: on UV
// set 0, untransformed (a transformed one would not map the same). -1 otherwise.
int look_image(const tg::Model& model, int texture, int tex_coord, const tg::ExtensionMap& extensions) {
  if (texture < 0 || size_t(texture) >= model.textures.size() || tex_coord != 0 || !extensions.empty()) return -1;
  const int image = model.textures[size_t(texture)].source;
  return image >= 0 && size_t(image) < model.images.size() ? image : -1;
}

// A material's three look_image slots, in MaterialLook::textures' order.
std::array<int, 3> look_images(const tg::Model& model, const tg::Material& m) {
  const tg::TextureInfo& base = m.pbrMetallicRoughness.baseColorTexture;
  return {look_image(model, base.index, base.texCoord, base.extensions),
          look_image(model, m.normalTexture.index, m.normalTexture.texCoord, m.normalTexture.extensions),
          look_image(model, m.emissiveTexture.index, m.emissiveTexture.texCoord, m.emissiveTexture.extensions)};
}

// What a document's materials look like, for a mesh flattened from it and written as an OBJ (its
// MTL) or a PLY: the factors, and the textures that are files beside it (source_material_looks adds
// the embedded ones, which only a flattened mesh needs).
std::vector<MaterialLook> material_looks(const tg::Model& model, const std::filesystem::path& base_dir) {
  const auto factor = [](const std::vector<double>& v, size_t k, double fallback) { return float(k < v.size() ? v[k] : fallback); };
  std::vector<MaterialLook> looks;
  for (const tg::Material& m : model.materials) {
    const tg::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    MaterialLook look;
    look.base_color = {factor(pbr.baseColorFactor, 0, 1), factor(pbr.baseColorFactor, 1, 1), factor(pbr.baseColorFactor, 2, 1),
                       m.alphaMode == "BLEND" ? factor(pbr.baseColorFactor, 3, 1) : 1.0f};
    look.emissive = {factor(m.emissiveFactor, 0, 0), factor(m.emissiveFactor, 1, 0), factor(m.emissiveFactor, 2, 0)};
    look.metallic = float(std::clamp(pbr.metallicFactor, 0.0, 1.0));
    look.roughness = float(std::clamp(pbr.roughnessFactor, 0.0, 1.0));
    const std::array<int, 3> images = look_images(model, m);
    for (size_t slot = 0; slot < images.size(); ++slot)
      if (images[slot] >= 0)
        if (const std::string& uri = model.images[size_t(images[slot])].uri; relative_file_uri(uri))
          *look.textures()[slot] = (base_dir / uri_decode(uri)).lexically_normal().string();
    looks.push_back(std::move(look));
  }
  return looks;
}

}  // namespace

Scene read_gltf(std::span<const uint8_t> bytes, const std::string& name, const std::filesystem::path& base_dir,
                const ReadOptions& options) {
  // tinygltf takes 32-bit lengths.
  if (bytes.size() > std::numeric_limits<uint32_t>::max()) throw_bad_input(name, "glTF files of 4 GiB or more are not supported");
  const bool glb = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  if (!glb && has_glb_extension(name)) {
    if (bytes.size() < 4) throw_bad_input_at_byte(name, 0, "truncated GLB header (" + str(bytes.size()) + " bytes, need 12)");
    throw_bad_input_at_byte(name, 0, "wrong GLB magic (expected 'glTF')");
  }
  std::span<const uint8_t> json_text = bytes;
  size_t json_offset = 0, glb_length = 0;
  GlbParts parts;
  if (glb) {
    parts = check_glb(bytes, name);
    json_offset = parts.json_offset;
    json_text = bytes.subspan(parts.json_offset, parts.json_size);
    glb_length = parts.length;
  }

  check_json_depth(json_text, name, json_offset);
  Json doc;
  try {
    doc = Json::parse(json_text.begin(), json_text.end());
  } catch (const Json::parse_error& e) {
    const size_t at = e.byte > 0 ? e.byte - 1 : 0;
    std::string what = e.what();
    if (auto colon = what.find("parse error"); colon != std::string::npos) what = what.substr(colon);
    throw_bad_input_at_byte(name, json_offset + at, "invalid JSON: " + what);
  } catch (const Json::exception& e) {
    // e.g. a number too large for a double ("1e1068"): nlohmann reports it without a position.
    throw_bad_input(name, std::string("invalid JSON: ") + e.what());
  }
  JsonChecker(doc, name).run();
  // Compressed geometry needs a few stand-ins (see gltf_compression.h); tinygltf then reads the
  // rewritten document (a GLB rebuilt around the same BIN chunk).
  const io::CompressedJson compressed = io::prepare_compressed_json(doc, glb);
  const bool targets_changed = prepare_animation_targets(doc);
  std::vector<uint8_t> rewritten;
  if (compressed.changed || targets_changed) {
    const std::string text = doc.dump();
    if (glb) {
      const std::vector<uint8_t> bin(bytes.begin() + ptrdiff_t(parts.bin_offset),
                                     bytes.begin() + ptrdiff_t(parts.bin_offset + parts.bin_size));
      rewritten = make_glb(text, bin, name);
      glb_length = rewritten.size();
    } else {
      rewritten.assign(text.begin(), text.end());
    }
    bytes = rewritten;
  }
  doc = Json();  // tinygltf parses the text again; keep peak memory down
  if (options.progress) options.progress(0.25);

  FileAccess access;
  if (!base_dir.empty()) {
    access.prefix = base_dir.string();
    if (access.prefix.back() != '/') access.prefix += '/';
  }
  tg::TinyGLTF loader;
  loader.SetImageLoader(&keep_encoded_image, nullptr);
  loader.SetFsCallbacks({&file_exists, &expand_path, &read_whole_file, &refuse_write, &access});
  auto source = std::make_shared<GltfSource>();
  std::string err, warn;
  bool ok = false;
  try {
    const std::string base = base_dir.string();
    if (glb)
      ok = loader.LoadBinaryFromMemory(&source->model, &err, &warn, bytes.data(), unsigned(glb_length), base);
    else
      ok = loader.LoadASCIIFromString(&source->model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                      unsigned(bytes.size()), base);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw_bad_input(name, std::string("glTF: ") + e.what());
  }
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    std::replace(err.begin(), err.end(), '\n', ';');
    throw_bad_input(name, "glTF: " + (err.empty() ? std::string("tinygltf could not load the document") : err));
  }
  if (options.progress) options.progress(0.5);
  source->base_dir = base_dir;

  std::vector<std::string> extensions_used = source->model.extensionsUsed;  // before decoding drops some
  io::decode_compressed_geometry(source->model, compressed.fallback_lengths, name);
  const Document document(source->model, name);
  document.validate();
  Scene scene = SceneBuilder(document).build();
  scene.extensions_used = std::move(extensions_used);
  scene.material_looks = material_looks(source->model, base_dir);
  if (options.warning)
    for (const std::string& ext : source->model.extensionsRequired)
      if (!known_extension(ext))
        options.warning(name + ": the file requires " + ext + ", which lodkit does not know: it is kept as it is, but "
                        "what lodkit changes may no longer agree with it");
  scene.source = std::move(source);
  scene.name = name;
  if (options.progress) options.progress(1.0);
  return scene;
}

// %XX escapes decoded (a malformed one is kept as it is).
std::string uri_decode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// The URI of `file` from a document in `output_dir`: its relative path, %-escaped; empty when it
// has none.
std::string relative_uri(const std::filesystem::path& file, const std::filesystem::path& output_dir) {
  const std::filesystem::path relative = io::relative_path(file, output_dir);
  if (relative.empty()) return {};
  std::string escaped;
  for (const auto& part : relative) escaped += (escaped.empty() ? "" : "/") + uri_escape(part.string());
  return escaped;
}

// Whether a URI names a file beside the document: relative, without a scheme (data:, http:).
bool relative_file_uri(const std::string& uri) {
  const size_t colon = uri.find(':'), slash = uri.find('/');
  return !uri.empty() && uri[0] != '/' && (colon == std::string::npos || colon > slash);
}

// The source's images outside its buffers (external files, data: URIs): a .glb (`bin` given) embeds
// the ones it can type in its BIN chunk, one file as GLB intends; an external one it does not is
// referred to by its path from the output's folder, so that a file written elsewhere still finds it.
void relocate_images(tg::Model& model, std::vector<uint8_t>* bin, const std::filesystem::path& source_dir,
                     const std::filesystem::path& output_dir) {
  for (tg::Image& image : model.images) {
    if (image.bufferView >= 0) continue;
    if (bin && !image.image.empty()) {
      if (const std::string mime = image_mime_type(image.image); !mime.empty()) {
        image.bufferView = BinWriter(model, *bin).add_view(image.image.data(), image.image.size(), 0);
        image.mimeType = mime;
        image.uri.clear();
        image.image.clear();
        continue;
      }
    }
    const std::string& uri = image.uri;  // empty for a data: URI (its bytes are in image.image)
    if (!relative_file_uri(uri) || source_dir.empty()) continue;
    if (std::string relative = relative_uri(source_dir / uri_decode(uri), output_dir); !relative.empty()) image.uri = relative;
  }
}

// The textures of a scene's material looks (one image and texture per file; PNG and JPEG, the
// types glTF's core knows), on the materials model_from_scene made. A .glb gets the images' bytes
// (relocate_images embeds them); a .gltf refers to the files from `output_dir`. A texture is left
// out where its file cannot be read or typed, and where a primitive with its material has no UVs
// (glTF's validator refuses a texture without them).
void add_look_textures(tg::Model& model, const Scene& scene, bool glb, const std::filesystem::path& output_dir) {
  std::vector<bool> has_uvs(scene.material_looks.size(), true);
  for (const Primitive& prim : scene.primitives)
    if (prim.material >= 0 && size_t(prim.material) < has_uvs.size() && prim.mesh.uvs[0].empty()) has_uvs[size_t(prim.material)] = false;
  std::map<std::string, int> texture_of;  // file -> texture index, or -1
  const auto texture = [&](const std::string& file) {
    const auto [it, inserted] = texture_of.try_emplace(file, -1);
    if (!inserted) return it->second;
    std::vector<unsigned char> bytes;
    try {
      const FileBytes read = read_file_bytes(std::filesystem::path(file));
      bytes.assign(read.data(), read.data() + read.size());
    } catch (const Error&) {
      return -1;
    }
    tg::Image image;
    image.mimeType = image_mime_type(bytes);
    if (image.mimeType != "image/png" && image.mimeType != "image/jpeg") return -1;
    if (glb) {
      image.image = std::move(bytes);
    } else {
      image.uri = relative_uri(std::filesystem::path(file), output_dir);
      if (image.uri.empty()) return -1;
      image.mimeType.clear();  // (the URI's extension says it)
    }
    tg::Texture t;
    t.source = int(model.images.size());
    model.images.push_back(std::move(image));
    it->second = int(model.textures.size());
    model.textures.push_back(t);
    return it->second;
  };
  // An image a glTF embedded (MaterialLook::images) goes in as its bytes: into the BIN chunk or a
  // data: URI (relocate_images, write_image_uri).
  std::map<const std::vector<uint8_t>*, int> texture_of_image;
  const auto embedded = [&](const std::vector<uint8_t>& bytes) {
    const auto [it, inserted] = texture_of_image.try_emplace(&bytes, int(model.textures.size()));
    if (!inserted) return it->second;
    tg::Image image;
    image.mimeType = image_mime_type(bytes);
    image.image = bytes;
    tg::Texture t;
    t.source = int(model.images.size());
    model.images.push_back(std::move(image));
    model.textures.push_back(t);
    return it->second;
  };
  const auto slot_texture = [&](const MaterialLook& look, size_t slot) {
    if (look.images[slot]) return embedded(*look.images[slot]);
    return look.textures()[slot]->empty() ? -1 : texture(*look.textures()[slot]);
  };
  for (size_t m = 0; m < scene.material_looks.size() && m < model.materials.size(); ++m) {
    if (!has_uvs[m]) continue;
    const MaterialLook& look = scene.material_looks[m];
    tg::Material& material = model.materials[m];
    material.pbrMetallicRoughness.baseColorTexture.index = slot_texture(look, 0);
    material.normalTexture.index = slot_texture(look, 1);
    if (const int emissive = slot_texture(look, 2); emissive >= 0) {
      material.emissiveTexture.index = emissive;
      // An emissive texture is multiplied by the factor: black (MTL without Ke) would hide it.
      if (look.emissive == float3{}) material.emissiveFactor = {1, 1, 1};
    }
  }
}

std::vector<MaterialLook> source_material_looks(const Scene& scene) {
  std::vector<MaterialLook> looks = scene.material_looks;
  if (!scene.source) return looks;
  const tg::Model& model = scene.source->model;
  std::map<size_t, std::shared_ptr<const std::vector<uint8_t>>> embedded;  // by image; null: none to take
  const auto image_bytes = [&](size_t i) {
    const auto [it, inserted] = embedded.try_emplace(i);
    if (!inserted) return it->second;
    const tg::Image& image = model.images[i];
    std::vector<uint8_t> bytes = image.image;  // a data: URI's (keep_encoded_image)
    if (bytes.empty() && image.bufferView >= 0 && size_t(image.bufferView) < model.bufferViews.size()) {
      const tg::BufferView& view = model.bufferViews[size_t(image.bufferView)];
      if (view.buffer >= 0 && size_t(view.buffer) < model.buffers.size() && view.byteOffset <= model.buffers[size_t(view.buffer)].data.size() &&
          view.byteLength <= model.buffers[size_t(view.buffer)].data.size() - view.byteOffset) {
        const auto data = model.buffers[size_t(view.buffer)].data.begin() + std::ptrdiff_t(view.byteOffset);
        bytes.assign(data, data + std::ptrdiff_t(view.byteLength));
      }
    }
    const std::string mime = image_mime_type(bytes);
    if (mime == "image/png" || mime == "image/jpeg") it->second = std::make_shared<const std::vector<uint8_t>>(std::move(bytes));
    return it->second;
  };
  for (size_t m = 0; m < looks.size() && m < model.materials.size(); ++m) {
    const std::array<int, 3> images = look_images(model, model.materials[m]);
    for (size_t slot = 0; slot < images.size(); ++slot)
      if (images[slot] >= 0 && looks[m].textures()[slot]->empty() && !relative_file_uri(model.images[size_t(images[slot])].uri))
        looks[m].images[slot] = image_bytes(size_t(images[slot]));
  }
  return looks;
}

std::vector<std::filesystem::path> source_files(const Scene& scene) {
  std::vector<std::filesystem::path> files;
  if (!scene.source || scene.source->base_dir.empty()) return files;
  for (const tg::Buffer& buffer : scene.source->model.buffers)
    if (relative_file_uri(buffer.uri)) files.push_back(scene.source->base_dir / uri_decode(buffer.uri));
  for (const tg::Image& image : scene.source->model.images)
    if (relative_file_uri(image.uri)) files.push_back(scene.source->base_dir / uri_decode(image.uri));
  return files;
}

namespace {

// A scene primitive's source glTF primitive and each of its vertices' source vertex (checked). No
// primitive when it has no source, or its vertices are not the source's (then the writer drops the
// streams lodkit does not model). `what` names the caller in errors.
struct SourceMap {
  const tg::Primitive* primitive = nullptr;
  std::vector<uint32_t> vertex;
};
SourceMap source_map(const Scene& scene, size_t primitive, const char* what) {
  if (!scene.source || primitive >= scene.primitives.size()) return {};
  const Primitive& prim = scene.primitives[primitive];
  const tg::Model& model = scene.source->model;
  if (prim.gltf_mesh >= model.meshes.size() || prim.gltf_primitive >= model.meshes[prim.gltf_mesh].primitives.size())
    return {};
  const tg::Primitive& source = model.meshes[prim.gltf_mesh].primitives[prim.gltf_primitive];
  const auto position = source.attributes.find("POSITION");
  if (position == source.attributes.end()) return {};
  const size_t source_count = model.accessors[size_t(position->second)].count, n = prim.mesh.vertex_count();
  const std::vector<uint32_t>& map = prim.source_vertices;
  const std::string where = std::string(what) + ": primitive " + str(primitive);
  if (!prim.source_weights.empty()) throw_usage(where + "'s vertices are blends (source_weights)");
  if (map.empty() && n != source_count) return {};
  if (!map.empty() && map.size() != n) throw_usage(where + "'s source_vertices do not match its vertices");
  SourceMap out{&source, map};
  if (map.empty()) {
    out.vertex.resize(n);
    std::iota(out.vertex.begin(), out.vertex.end(), 0u);
  }
  for (const uint32_t v : out.vertex)
    if (v >= source_count) throw_usage(where + " names source vertex " + str(v));
  return out;
}

}  // namespace

std::vector<uint32_t> source_vertex_classes(const Scene& scene, size_t primitive) {
  const SourceMap map = source_map(scene, primitive, "source_vertex_classes");
  if (!map.primitive) return {};
  const tg::Model& model = scene.source->model;
  const Document doc(model, scene.name);
  std::vector<std::vector<uint8_t>> streams;
  std::vector<size_t> element_sizes;
  for_each_unmodelled_stream(*map.primitive, [&](int, const std::string&, int index) {
    streams.push_back(doc.packed_elements(index));
    element_sizes.push_back(element_bytes(model.accessors[size_t(index)].componentType, model.accessors[size_t(index)].type));
  });
  if (streams.empty()) return {};
  std::unordered_map<std::string, uint32_t> ids;  // the streams' bytes -> class, in order of first appearance
  std::vector<uint32_t> classes(map.vertex.size());
  std::string key;
  for (size_t v = 0; v < map.vertex.size(); ++v) {
    key.clear();
    for (size_t k = 0; k < streams.size(); ++k)
      key.append(reinterpret_cast<const char*>(streams[k].data() + map.vertex[v] * element_sizes[k]), element_sizes[k]);
    classes[v] = ids.try_emplace(key, uint32_t(ids.size())).first->second;
  }
  return classes;
}

std::vector<MorphTarget> source_morph_targets(const Scene& scene, size_t primitive) {
  const SourceMap map = source_map(scene, primitive, "source_morph_targets");
  if (!map.primitive) return {};
  const Document doc(scene.source->model, scene.name);
  std::vector<MorphTarget> targets;
  const size_t count = std::min<size_t>(map.primitive->targets.size(), scene.primitives[primitive].source_target_count);
  for (size_t k = 0; k < count; ++k) {
    const auto& attributes = map.primitive->targets[k];
    MorphTarget& t = targets.emplace_back();
    t.positions.assign(map.vertex.size(), float3{});
    const char* semantics[] = {"POSITION", "NORMAL", "TANGENT"};  // (morph_streams' order)
    for (size_t s = 0; s < 3; ++s) {
      const auto it = attributes.find(semantics[s]);
      if (it == attributes.end()) continue;
      // (VEC3: the reader refuses other types.)
      const std::vector<float3> values = doc.decode_floats<float3>(it->second);
      std::vector<float3>& out = t.*morph_streams[s];
      out.resize(map.vertex.size());
      for (size_t v = 0; v < map.vertex.size(); ++v) out[v] = values[map.vertex[v]];
    }
  }
  return targets;
}

namespace {

// A node list renumbered: erased nodes (-1 in `remap`) leave it.
template <typename Index>
void renumber(std::vector<Index>& list, const std::vector<int32_t>& remap) {
  std::erase_if(list, [&](Index n) { return n >= 0 && size_t(n) < remap.size() && remap[size_t(n)] < 0; });
  for (Index& n : list)
    if (n >= 0 && size_t(n) < remap.size()) n = Index(remap[size_t(n)]);
}

}  // namespace

std::vector<int32_t> erase_nodes(Scene& scene, const std::vector<bool>& erase) {
  const size_t count = scene.nodes.size();
  std::vector<int32_t> remap(count);
  std::iota(remap.begin(), remap.end(), 0);
  if (!scene.source || scene.source->model.nodes.size() > count || erase.size() != count) return remap;
  const tg::Model& model = scene.source->model;
  const size_t sources = model.nodes.size();  // (the nodes past them are new: renumbered, never erased)
  if (!std::all_of(model.extensionsUsed.begin(), model.extensionsUsed.end(), known_extension)) return remap;
  // What else needs a node keeps it: a camera, another extension (a light), a skin, a node taking its
  // morph weights, a child that stays (a new node below it among them).
  std::vector<bool> gone(count, false);
  for (size_t n = 0; n < sources; ++n) {
    const tg::Node& node = model.nodes[n];
    gone[n] = erase[n] && node.camera < 0 && std::all_of(node.extensions.begin(), node.extensions.end(), [](const auto& e) {
      return e.first == "MSFT_lod" || e.first == node_visibility || e.first == gpu_instancing;
    });
  }
  for (const tg::Skin& skin : model.skins) {
    for (const int j : skin.joints)
      if (j >= 0 && size_t(j) < count) gone[size_t(j)] = false;
    if (skin.skeleton >= 0 && size_t(skin.skeleton) < count) gone[size_t(skin.skeleton)] = false;
  }
  for (size_t n = 0; n < count; ++n) {
    const Node& node = scene.nodes[n];
    for (const int32_t of : node.morph_weights_of)
      if (of >= 0 && size_t(of) < count) gone[size_t(of)] = false;
    if (n >= sources && node.parent >= 0 && size_t(node.parent) < count) gone[size_t(node.parent)] = false;
  }
  for (bool changed = true; changed;) {  // (a parent stays with its child: up the tree, one level a round)
    changed = false;
    for (size_t n = 0; n < sources; ++n)
      if (gone[n] && std::any_of(model.nodes[n].children.begin(), model.nodes[n].children.end(),
                                 [&](int c) { return c >= 0 && size_t(c) < count && !gone[size_t(c)]; }))
        gone[n] = false, changed = true;
  }
  if (std::none_of(gone.begin(), gone.end(), [](bool g) { return g; })) return remap;
  int32_t next = 0;
  for (size_t n = 0; n < count; ++n) remap[n] = gone[n] ? -1 : next++;
  const auto moved = [&](int32_t n) { return n >= 0 && size_t(n) < count ? remap[size_t(n)] : n; };

  // The document: a copy (the scene's source is shared) without those nodes.
  auto source = std::make_shared<GltfSource>(*scene.source);
  tg::Model& doc = source->model;
  std::vector<tg::Node> nodes;
  for (size_t n = 0; n < sources; ++n)
    if (!gone[n]) nodes.push_back(std::move(doc.nodes[n]));
  doc.nodes = std::move(nodes);
  // (MSFT_lod ids: the writer writes every node's from the scene's Node::lod_ids, renumbered below.)
  for (tg::Node& node : doc.nodes) renumber(node.children, remap);
  for (tg::Scene& s : doc.scenes) renumber(s.nodes, remap);
  for (tg::Skin& skin : doc.skins) {
    renumber(skin.joints, remap);
    skin.skeleton = moved(skin.skeleton);
  }
  // A clip's channels that move or switch a node that went go with it (the writer prunes their samplers).
  for (tg::Animation& anim : doc.animations) {
    std::erase_if(anim.channels, [&](const tg::AnimationChannel& ch) {
      const ChannelTarget t = channel_target(ch);
      return t.list == "nodes" && moved(t.index) < 0;
    });
    for (tg::AnimationChannel& ch : anim.channels)
      if (const ChannelTarget t = channel_target(ch); t.list == "nodes" && moved(t.index) != t.index) retarget_channel(ch, "nodes", moved(t.index));
  }
  scene.source = std::move(source);

  // The scene, likewise.
  std::vector<Node> kept;
  for (size_t n = 0; n < count; ++n)
    if (!gone[n]) kept.push_back(std::move(scene.nodes[n]));
  scene.nodes = std::move(kept);
  for (Node& node : scene.nodes) {
    node.parent = moved(node.parent);
    renumber(node.children, remap);
    renumber(node.lod_ids, remap);
    renumber(node.morph_weights_of, remap);
  }
  renumber(scene.roots, remap);
  for (Skin& skin : scene.skins) {
    renumber(skin.joints, remap);
    skin.skeleton = moved(skin.skeleton);
  }
  for (Animation& clip : scene.animations) {
    std::erase_if(clip.channels, [&](const AnimationChannel& ch) { return ch.node >= 0 && moved(ch.node) < 0; });
    for (AnimationChannel& ch : clip.channels) ch.node = moved(ch.node);
  }
  return remap;
}

WriteReport write_gltf(const Scene& scene, const std::filesystem::path& path, const WriteOptions& options) {
  const bool glb = format_from_path(path) == FileFormat::glb;
  std::vector<Slot> slots;
  tg::Model model;
  if (scene.source) {
    model = scene.source->model;
    add_to_source(model, scene);
    for (const Primitive& prim : scene.primitives) slots.push_back({int(prim.gltf_mesh), int(prim.gltf_primitive)});
  } else {
    model = model_from_scene(scene, slots);
    add_look_textures(model, scene, glb, path.parent_path());
  }
  if (options.draco && (options.position_bits < 1 || options.position_bits > 30))
    throw_usage("cannot write glTF: position_bits is " + std::to_string(options.position_bits) + ", not 1 to 30 (Draco)");
  if (options.uv_bits < 0 || options.uv_bits > 16)
    throw_usage("cannot write glTF: uv_bits is " + std::to_string(options.uv_bits) + ", not 0 (the default) or 1 to 16");
  if (options.normal_bits != 0 && (options.normal_bits < 8 || options.normal_bits > 16))
    throw_usage("cannot write glTF: normal_bits is " + std::to_string(options.normal_bits) + ", not 0 (the default) or 8 to 16");
  WriteReport report;
  io::DirectionFloats directions;
  std::vector<uint8_t> bin = rebuild_geometry(model, scene, slots, options, report, directions);
  // MSFT_lod, instancing and visibility are declared only while a node still uses them (a clip
  // switching a node's visibility uses it too).
  const bool switched = std::any_of(model.animations.begin(), model.animations.end(), [](const tg::Animation& anim) {
    return std::any_of(anim.channels.begin(), anim.channels.end(), [](const tg::AnimationChannel& ch) {
      return switches_visibility(channel_target(ch));
    });
  });
  for (const std::string ext : {"MSFT_lod", gpu_instancing, node_visibility})
    if (!(ext == node_visibility && switched) &&
        std::none_of(model.nodes.begin(), model.nodes.end(), [&](const tg::Node& n) { return n.extensions.count(ext) > 0; }))
      std::erase(model.extensionsUsed, ext), std::erase(model.extensionsRequired, ext);
  // So is KHR_animation_pointer (the reader makes a node property's pointer a core channel).
  if (std::none_of(model.animations.begin(), model.animations.end(), [](const tg::Animation& anim) {
        return std::any_of(anim.channels.begin(), anim.channels.end(),
                           [](const tg::AnimationChannel& ch) { return ch.target_extensions.count(animation_pointer) > 0; });
      }))
    std::erase(model.extensionsUsed, animation_pointer), std::erase(model.extensionsRequired, animation_pointer);
  relocate_images(model, glb ? &bin : nullptr, scene.source ? scene.source->base_dir : std::filesystem::path(), path.parent_path());
  const std::filesystem::path bin_path = gltf_buffer_path(path);  // (empty for a .glb)
  const std::string bin_name = bin_path.filename().string();
  Json doc = serialize_json(model, bin.size(), glb ? "" : uri_escape(bin_name));
  if (options.meshopt_compression) io::compress_meshopt(doc, bin, options, directions);
  if (glb) {
    const std::vector<uint8_t> bytes = make_glb(dump_json(doc, false), bin, path.string());
    write_file_atomic(path, bytes);
    report.bytes = bytes.size();
    return report;
  }
  if (!bin.empty()) write_file_atomic(bin_path, bin);
  const std::string json = dump_json(doc, true);
  write_file_atomic(path, json);
  report.bytes = bin.size() + json.size();
  return report;
}

}  // namespace lod
