// scripts/bench.sh skin: skinned simplification, three modes side by side (issue 7).
//
// For each test character (tests/skin/fixtures.h: the procedural humanoid, and man.off rigged by
// hand) and each ratio (25%, 10%, 3% of the triangles), simplify with houle (in the mid-range pose),
// subset and multipose (16 poses over every clip), then play every clip at 30 fps and measure the
// skinned LOD against the skinned original with lod::compare (symmetric Hausdorff and RMS over the
// bounding-box diagonal of the rest pose): mean over frames and max over frames. Also the
// simplification time (median of RUNS), and the per-frame cost of the skeletal geomorph
// (lod::SkinnedGeomorph) against plain skinning of the finer level (lod::skin_vertices), one thread,
// medians. Prints markdown tables and the targets; exits 1 when a target fails.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "lodkit/lod.h"
#include "median.h"
#include "lodkit/measure.h"
#include "lodkit/skin.h"
#include "skin/fixtures.h"

using namespace lod;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

Mesh posed(const Mesh& m, const std::vector<mat4>& joints) {
  SkinnedVertices v;
  skin_vertices(m, joints, v);
  Mesh out = m;
  out.positions = std::move(v.positions);
  out.normals = std::move(v.normals);
  return out;
}

struct Frames {
  std::vector<std::vector<mat4>> joints;  // every frame of every clip at 30 fps
};

Frames frames_of(const Scene& scene, uint32_t skin) {
  Frames f;
  for (size_t a = 0; a < scene.animations.size(); ++a) {
    const float duration = animation_duration(scene, a);
    const int count = std::max(1, int(std::floor(duration * 30.0f)) + 1);
    for (int i = 0; i < count; ++i) {
      Pose pose = rest_pose(scene);
      sample_animation(scene, a, float(i) / 30.0f, pose);
      f.joints.push_back(joint_matrices(scene, skin, world_matrices(scene, pose)));
    }
  }
  return f;
}

struct Row {
  std::string character, mode;
  float ratio = 0;
  uint64_t triangles = 0;
  double seconds = 0, mean_h = 0, max_h = 0, mean_rms = 0, max_rms = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path man = argc > 1 ? argv[1] : "data/corpus/man.off";
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
  struct Character {
    std::string name;
    Scene scene;
  };
  std::vector<Character> characters;
  characters.push_back({"humanoid", fixtures::humanoid_scene()});
  if (std::filesystem::exists(man)) characters.push_back({"man", fixtures::rigged_man_scene(man)});

  std::vector<Row> rows;
  bool pass = true;
  std::printf("| character | ratio | mode | triangles | simplify s (median of %d) | Hausdorff mean %% | Hausdorff max %% | RMS mean %% | RMS max %% |\n", runs);
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|---:|\n");
  struct MorphRow {
    std::string character;
    double skin = 0, morph = 0;
    size_t vertices = 0;
  };
  std::vector<MorphRow> morph_rows;
  for (const Character& c : characters) {
    const std::vector<SkinnedPrimitive> skinned = skinned_primitives(c.scene);
    if (skinned.empty()) return std::fprintf(stderr, "%s has no skinned primitive\n", c.name.c_str()), 2;
    const SkinnedPrimitive sp = skinned[0];
    const Mesh& mesh = c.scene.primitives[sp.primitive].mesh;
    const Frames frames = frames_of(c.scene, sp.skin);
    const std::vector<std::vector<mat4>> poses = sample_poses(c.scene, sp.skin, 16);
    const std::vector<mat4> mid = joint_matrices(c.scene, sp.skin, world_matrices(c.scene, mid_range_pose(c.scene, sp.skin)));
    float3 lo, hi;
    bounding_box(mesh, lo, hi);
    const double diagonal = std::sqrt(double(hi.x - lo.x) * (hi.x - lo.x) + double(hi.y - lo.y) * (hi.y - lo.y) +
                                      double(hi.z - lo.z) * (hi.z - lo.z));
    std::vector<Mesh> original_frames;
    for (const auto& f : frames.joints) original_frames.push_back(posed(mesh, f));

    for (const float ratio : {0.25f, 0.10f, 0.03f}) {
      double houle_max = 0, subset_max = 0, multipose_max = 0;
      for (const SkinMode mode : {SkinMode::houle, SkinMode::subset, SkinMode::multipose}) {
        SkinSimplifyOptions o;
        o.mode = mode;
        o.simplify.target_ratio = ratio;
        o.simplify.record = false;
        o.poses = mode == SkinMode::houle ? std::vector<std::vector<mat4>>{mid} : poses;
        std::vector<double> times;
        SimplifyResult r;
        for (int k = 0; k < runs; ++k) {
          const double t0 = now();
          r = simplify_skinned(mesh, o);
          times.push_back(now() - t0);
        }
        Row row{c.name, skin_mode_name(mode), ratio, r.mesh.triangle_count(), bench::median(times)};
        for (size_t f = 0; f < frames.joints.size(); ++f) {
          const Deviation d = compare(original_frames[f], posed(r.mesh, frames.joints[f]),
                                      {.samples = 100'000, .attributes = false});
          row.mean_h += d.hausdorff, row.max_h = std::max(row.max_h, d.hausdorff);
          row.mean_rms += d.rms, row.max_rms = std::max(row.max_rms, d.rms);
        }
        const double n = double(frames.joints.size());
        row.mean_h /= n, row.mean_rms /= n;
        std::printf("| %s | %.0f%% | %s | %llu | %.3f | %.4f | %.4f | %.4f | %.4f |\n", c.name.c_str(), 100 * ratio,
                    row.mode.c_str(), (unsigned long long)row.triangles, row.seconds, 100 * row.mean_h / diagonal,
                    100 * row.max_h / diagonal, 100 * row.mean_rms / diagonal, 100 * row.max_rms / diagonal);
        std::fflush(stdout);
        if (mode == SkinMode::houle) houle_max = row.max_h;
        if (mode == SkinMode::subset) subset_max = row.max_h;
        if (mode == SkinMode::multipose) multipose_max = row.max_h;
        rows.push_back(row);
      }
      // Targets: never worse than either single-pose method; <= 0.8x the better at 10% and 3%.
      const double best_single = std::min(houle_max, subset_max);
      const bool never_worse = multipose_max <= houle_max && multipose_max <= subset_max;
      const bool factor = ratio > 0.2f || multipose_max <= 0.8 * best_single;
      std::printf("| %s | %.0f%% | **multipose / better single** | | | | %.2fx %s | | |\n", c.name.c_str(), 100 * ratio,
                  multipose_max / best_single, never_worse && factor ? "PASS" : "FAIL");
      pass = pass && never_worse && factor;
    }

    // Skeletal geomorph cost: level 0 (the input) morphing towards a multipose half-size level.
    LodOptions lo_options;
    lo_options.ratios = {1.0f, 0.5f};
    lo_options.morph = true;
    lo_options.measure = false;
    lo_options.simplifier = skinned_simplifier({.poses = poses});
    const LodChain chain = build_lod_chain(mesh, lo_options);
    const Mesh &fine = chain.levels[0].mesh, &coarse = chain.levels[1].mesh;
    SkinnedVertices out;
    SkinnedGeomorph morph(fine, coarse, chain.morphs[0]);
    std::vector<double> skin_times, morph_times;
    const int reps = 200;
    for (int k = 0; k < 15; ++k) {
      const auto& joints = frames.joints[size_t(k) % frames.joints.size()];
      double t0 = now();
      for (int i = 0; i < reps; ++i) skin_vertices(fine, joints, out);
      skin_times.push_back((now() - t0) / reps);
      t0 = now();
      for (int i = 0; i < reps; ++i) morph.evaluate(joints, 0.37f, out);
      morph_times.push_back((now() - t0) / reps);
    }
    morph_rows.push_back({c.name, bench::median(skin_times), bench::median(morph_times), fine.vertex_count()});
  }
  std::printf("\n| character | vertices | skinning µs/frame | skin + geomorph µs/frame | ratio | target <= 1.5x |\n");
  std::printf("|---|---:|---:|---:|---:|---|\n");
  for (const MorphRow& m : morph_rows) {
    const double ratio = m.morph / m.skin;
    std::printf("| %s | %zu | %.1f | %.1f | %.2fx | %s |\n", m.character.c_str(), m.vertices, 1e6 * m.skin, 1e6 * m.morph,
                ratio, ratio <= 1.5 ? "PASS" : "FAIL");
    pass = pass && ratio <= 1.5;
  }
  std::printf("\none thread for the morph timing (15 frames x 200 repetitions, medians); errors: every frame of every clip at 30 fps, "
              "lod::compare with 100k samples, over the rest pose's bounding-box diagonal\n");
  return pass ? 0 : 1;
}
