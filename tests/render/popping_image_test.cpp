// An image-based check of popping (issue 8): a LOD switch rendered as a hard swap against the same
// switch as a geomorph in steps, measured by the silhouette displacement between consecutive frames.
#include <gtest/gtest.h>

#include "core/shapes.h"
#include "lodkit/lod.h"
#include "lodkit/render.h"

namespace lod {
namespace {

TEST(RenderPopping, GeomorphStepsMoveTheSilhouetteFarLessThanAHardSwitch) {
  LodOptions o;
  o.ratios = {1.0f, 0.04f};
  o.morph = true;
  o.measure = false;
  o.simplify.threads = 1;  // no worker threads: this suite runs with LeakSanitizer's TLS scan off
  const LodChain chain = build_lod_chain(shapes::icosphere(3), o);
  ASSERT_EQ(chain.morphs.size(), 1u);
  const Mesh &fine = chain.levels[0].mesh, &coarse = chain.levels[1].mesh;
  RenderContext gl;
  const ViewDifferenceOptions views{.views = 4, .width = 400, .height = 400};
  // The hard switch: the finer level's frame, then the coarser one's.
  const double hard = compare_views(gl, fine, coarse, views).max_silhouette_displacement_px;
  EXPECT_GT(hard, 3.0);
  // The geomorph in 8 steps: each frame's outline moves about an eighth as far.
  constexpr int steps = 8;
  double worst_step = 0;
  Mesh previous = morph(fine, coarse, chain.morphs[0], 0.0f);
  for (int k = 1; k <= steps; ++k) {
    const Mesh next = morph(fine, coarse, chain.morphs[0], float(k) / steps);
    worst_step = std::max(worst_step, compare_views(gl, previous, next, views).max_silhouette_displacement_px);
    previous = next;
  }
  // Rasterisation moves an outline by up to a pixel on its own.
  EXPECT_LE(worst_step, hard / steps * 2 + 1.0);
  EXPECT_LT(worst_step, hard / 2);
  // t = 1 draws the coarser level's picture exactly.
  EXPECT_EQ(compare_views(gl, previous, coarse, views).max_silhouette_displacement_px, 0.0);
}

}  // namespace
}  // namespace lod
