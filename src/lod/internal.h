// Internal: what the LOD chain builder shares with the geomorph code.
#pragma once

#include "lodkit/lod.h"

namespace lod {

// The correspondence table of a simplification: vertices of `source` (the mesh that was simplified,
// with record on) -> vertices of result.mesh.
Geomorph geomorph_from_record(const Mesh& source, const SimplifyResult& result);

}  // namespace lod
