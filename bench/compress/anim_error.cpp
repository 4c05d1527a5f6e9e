// lodkit_bench_anim_error REFERENCE CANDIDATE CLIP: how far a compressed file's animation strays
// from the reference's. Both files' clip named CLIP is sampled at 240 Hz over the reference's
// duration; at each time every joint of the reference's skins (matched to the candidate's node of
// the same name) is placed in world space, and the largest distance between the two placements is
// printed as JSON: {"joint_error": metres, "joint": name, "time": seconds, "joints": matched}.
// Lossy animation coding (lodkit -q's key reduction, gltfpack's 30 Hz resampling and quantization)
// is judged by the same measure.
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/skin.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: lodkit_bench_anim_error REFERENCE CANDIDATE CLIP\n");
    return 1;
  }
  try {
    const lod::Scene a = lod::read_scene(argv[1]), b = lod::read_scene(argv[2]);
    const auto clip_of = [&](const lod::Scene& s) {
      for (size_t k = 0; k < s.animations.size(); ++k)
        if (s.animations[k].name == argv[3]) return k;
      throw lod::Error(lod::ErrorCategory::usage, std::string("no clip named '") + argv[3] + "'");
    };
    const size_t ca = clip_of(a), cb = clip_of(b);
    std::map<std::string, size_t> by_name;
    for (size_t n = 0; n < b.nodes.size(); ++n) by_name[b.nodes[n].name] = n;
    std::vector<std::pair<size_t, size_t>> joints;  // (reference node, candidate node)
    for (const lod::Skin& skin : a.skins)
      for (const int32_t j : skin.joints)
        if (const auto found = by_name.find(a.nodes[size_t(j)].name); found != by_name.end()) joints.emplace_back(size_t(j), found->second);
    double worst = 0, when = 0;
    std::string where;
    const float duration = lod::animation_duration(a, ca);
    for (int k = 0; k <= int(std::ceil(duration * 240)); ++k) {
      const float t = std::min(duration, float(k) / 240);
      lod::Pose pa = lod::rest_pose(a), pb = lod::rest_pose(b);
      lod::sample_animation(a, ca, t, pa);
      lod::sample_animation(b, cb, t, pb);
      const std::vector<lod::mat4> wa = lod::world_matrices(a, pa), wb = lod::world_matrices(b, pb);
      for (const auto& [ja, jb] : joints) {
        const lod::mat4 &ma = wa[ja], &mb = wb[jb];
        const double d = std::hypot(double(ma[12]) - mb[12], double(ma[13]) - mb[13], double(ma[14]) - mb[14]);
        if (d > worst) worst = d, when = t, where = a.nodes[ja].name;
      }
    }
    std::printf("%s\n", nlohmann::json{{"joint_error", worst}, {"joint", where}, {"time", when}, {"joints", joints.size()}}.dump().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodkit_bench_anim_error: %s\n", e.what());
    return 2;
  }
  return 0;
}
