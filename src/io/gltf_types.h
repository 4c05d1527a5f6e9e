// Internal to the glTF reader, writer and compression codecs: glTF component and element types, their
// sizes and names.
#pragma once

#include <tiny_gltf.h>

#include <algorithm>
#include <cstddef>
#include <string_view>

#include "lodkit/mesh.h"

namespace lod::io {

// Joint indices are written in bytes when every one of both sets fits (skeletons of up to 256
// joints): the same values in half the space (plain accessors and Draco streams alike).
inline bool joints_fit_bytes(const Mesh& m) {
  const auto fits = [](const std::vector<ushort4>& joints) {
    return std::all_of(joints.begin(), joints.end(), [](const ushort4& j) { return std::max({j[0], j[1], j[2], j[3]}) < 256; });
  };
  return fits(m.joints) && fits(m.joints1);
}

inline size_t component_bytes(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;  // DOUBLE is not glTF 2.0
  }
}

inline size_t type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

inline const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "?";
  }
}

// Components of an element type given by its JSON name ("VEC3": 3); 0 for an unknown name.
inline size_t type_components(std::string_view name) {
  for (int type : {TINYGLTF_TYPE_SCALAR, TINYGLTF_TYPE_VEC2, TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4, TINYGLTF_TYPE_MAT2,
                   TINYGLTF_TYPE_MAT3, TINYGLTF_TYPE_MAT4})
    if (name == type_name(type)) return type_components(type);
  return 0;
}

}  // namespace lod::io
