// libFuzzer harness for the MTL reader: read_mtl rejects only as bad input, and what it accepts
// keeps its promises: named materials, colours, alpha, metallic and roughness in [0, 1].
#include <cstdint>
#include <cstdlib>

#include "lodkit/error.h"
#include "lodkit/io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<lod::MtlMaterial> materials;
  try {
    materials = lod::read_mtl({data, size}, "fuzz.mtl", "/textures");
  } catch (const lod::Error& e) {
    if (e.category() != lod::ErrorCategory::bad_input) std::abort();  // only "bad input" is a clean rejection
    return 0;
  }
  const auto unit = [](float x) { return x >= 0 && x <= 1; };  // (false for NaN)
  for (const lod::MtlMaterial& m : materials) {
    const lod::MaterialLook& l = m.look;
    if (m.name.empty()) std::abort();
    for (float c : {l.base_color.x, l.base_color.y, l.base_color.z, l.base_color.w, l.emissive.x, l.emissive.y,
                    l.emissive.z, l.metallic, l.roughness})
      if (!unit(c)) std::abort();
  }
  return 0;
}
