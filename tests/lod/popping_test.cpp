// Popping along a camera flight: geomorphs spread each switch over many small steps, hard switches
// jump; the geomorph's largest step stays under a pixel.
#include <gtest/gtest.h>

#include "core/shapes.h"
#include "lodkit/error.h"
#include "lodkit/lod.h"

namespace lod {
namespace {

TEST(Popping, GeomorphsStayUnderAPixelWhereHardSwitchesJump) {
  // A finely tessellated torus, curved everywhere: every level has an error to switch on (a midpoint-
  // subdivided coarse torus simplifies back to the coarse torus exactly, with no error at all).
  const Mesh mesh = shapes::torus(1.0f, 0.3f, 96, 48);
  const LodChain chain = build_lod_chain(mesh, {.levels = 4, .morph = true});
  const PoppingResult r = measure_popping(chain, {.flight_seconds = 8});
  ASSERT_EQ(r.geomorph.frames, 480u);
  ASSERT_EQ(r.geomorph.per_frame_px.size(), 480u);
  // The flight passes switch points both ways.
  EXPECT_GE(r.hard.level_changes, 4u);
  EXPECT_GE(r.geomorph.level_changes, 4u);
  // A hard switch shows the level's error at its switch point: about error_px (1).
  EXPECT_GT(r.hard.max_px, 0.3);
  // The geomorph moves the same distance over transition_seconds * fps frames.
  EXPECT_LT(r.geomorph.max_px, 1.0);
  EXPECT_LT(r.geomorph.max_px * 10, r.hard.max_px);
  EXPECT_GT(r.geomorph.moving_frames, 10 * r.hard.moving_frames);
}

TEST(Popping, NeedsGeomorphTables) {
  const LodChain chain = build_lod_chain(shapes::icosphere(2), {.levels = 3, .measure = false});
  EXPECT_THROW(measure_popping(chain), Error);
}

}  // namespace
}  // namespace lod
