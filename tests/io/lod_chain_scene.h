// A LOD chain laid out as lodkit lod writes one, built by hand for the glTF and render tests: level i
// is node i drawing glTF mesh i, node 0 lists the coarser levels in MSFT_lod, and node i carries
// extras[i] (JSON text, "" for none).
#pragma once

#include <string>
#include <vector>

#include "lodkit/io.h"

namespace lod::test {

inline Scene lod_chain_scene(const std::vector<Mesh>& levels, const std::vector<std::string>& extras) {
  Scene chain;
  for (size_t i = 0; i < levels.size(); ++i) {
    Primitive prim;
    prim.mesh = levels[i];
    prim.gltf_mesh = uint32_t(i);
    chain.primitives.push_back(std::move(prim));
    Node node;
    node.mesh = int32_t(i);
    node.extras_json = extras[i];
    chain.nodes.push_back(std::move(node));
    if (i > 0) chain.nodes[0].lod_ids.push_back(int32_t(i));
  }
  chain.roots = {0};
  return chain;
}

}  // namespace lod::test
