// Internal: the multi-pose quadric metric for skinned meshes (lod::simplify_skinned, multipose mode).
//
// Houle simplifies in one pose; a collapse that is harmless there can tear an elbow in another. Here
// each position keeps one quadric per sampled pose k, built from its faces as they stand in that pose
// (skinned by linear blend skinning), and each collapse minimises the weighted sum over the poses.
// The unknown is the bind-space position p: in pose k a vertex with weights w lands at
// x_k = A_k(w) p + t_k(w) (the blended joint matrix), which is affine in p, so each pose's quadric
// pulls back to a quadric in p and the optimum is one 3x3 solve, "optimal over all poses, solved in
// bind space". The surviving vertex's weights are chosen among the two ends' weights and their blend
// (top four, or eight for a mesh with a second influence set, renormalised) by the same multi-pose
// error, and a bone-weight term makes collapses across very different influences cost more.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/parallel.h"
#include "simplify/metric.h"
#include "simplify/quadric_metric.h"

namespace lod::collapse {

// Influences (lod::Influences): up to eight, Mesh::joints/weights then joints1/weights1. A mesh with
// one influence set uses the first four slots only.

// The first n weights (4 or 8) renormalised to sum 1 within 1e-6: summed in double, the rounding left
// on the heaviest; a slot of weight 0 points at joint 0 (valid whatever the skin). No weight: all on
// slot 0. lod::simplify_skinned normalises its input and output this way.
inline void normalize_weights(uint16_t* joints, float* w, int n) {
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += std::max(0.0f, w[i]);
  if (!(sum > 0)) {
    std::fill(w, w + n, 0.0f);
    w[0] = 1;
    return;
  }
  int heaviest = 0;
  for (int i = 0; i < n; ++i) {
    w[i] = float(std::max(0.0f, w[i]) / sum);
    if (w[i] > w[heaviest]) heaviest = i;
  }
  double rest = 0;
  for (int i = 0; i < n; ++i)
    if (i != heaviest) rest += w[i];
  w[heaviest] = float(1.0 - rest);
  for (int i = 0; i < n; ++i)
    if (w[i] == 0) joints[i] = 0;
}

// Heaviest `slots` (4 or 8) of a sparse set of up to 2 * max_influences entries (ties: lower joint
// first), renormalised to sum 1.
inline Influences top_influences(std::span<const std::pair<uint16_t, float>> set, size_t slots = 4) {
  std::array<std::pair<uint16_t, float>, 2 * max_influences> sorted{};
  const size_t n = std::min<size_t>(set.size(), sorted.size());
  const size_t kept = std::min<size_t>({n, slots, max_influences});
  std::copy_n(set.begin(), n, sorted.begin());
  std::sort(sorted.begin(), sorted.begin() + n, [](const auto& a, const auto& b) {
    return a.second > b.second || (a.second == b.second && a.first < b.first);
  });
  Influences out;
  double sum = 0;
  for (size_t i = 0; i < kept; ++i) sum += sorted[i].second;
  if (!(sum > 0)) return out;
  for (size_t i = 0; i < kept; ++i)
    if (sorted[i].second > 0) out.joint[i] = sorted[i].first, out.weight[i] = sorted[i].second;
  // Normalised as the output will be, so that the record and the output carry the same values.
  normalize_weights(out.joint, out.weight, int(slots == 8 ? 8 : 4));
  return out;
}

// Half the L1 distance between two weight vectors: 0 for the same influences, 1 for disjoint ones.
inline double influence_distance(const Influences& a, const Influences& b) {
  double d = 0;
  for (int i = 0; i < max_influences; ++i) {
    if (a.weight[i] == 0) continue;
    float other = 0;
    for (int j = 0; j < max_influences; ++j)
      if (b.weight[j] > 0 && b.joint[j] == a.joint[i]) other = b.weight[j];
    d += std::fabs(double(a.weight[i]) - other);
  }
  for (int j = 0; j < max_influences; ++j) {
    if (b.weight[j] == 0) continue;
    bool shared = false;
    for (int i = 0; i < max_influences; ++i) shared |= a.weight[i] > 0 && a.joint[i] == b.joint[j];
    if (!shared) d += b.weight[j];
  }
  return 0.5 * d;
}

struct MultiposeInput {
  // poses[k][j]: joint j's matrix in pose k (column-major 4x4, affine), object space.
  std::span<const std::vector<std::array<float, 16>>> poses;
  std::span<const float> pose_weights;  // empty: all poses alike
  float bone_weight = 0;                // see MultiposeMetric::place
  bool constrained = true;              // border planes, as constrained_qem
};

class MultiposeMetric {
 public:
  explicit MultiposeMetric(const MultiposeInput& in) : bone_weight_(in.bone_weight), constrained_(in.constrained) {
    pose_count_ = uint32_t(in.poses.size());
    double total = 0;
    for (uint32_t k = 0; k < pose_count_; ++k) total += in.pose_weights.empty() ? 1.0 : double(in.pose_weights[k]);
    joint_count_ = pose_count_ ? uint32_t(in.poses[0].size()) : 0;
    pose_weight_.resize(pose_count_);
    joints_.resize(size_t(pose_count_) * joint_count_);
    for (uint32_t k = 0; k < pose_count_; ++k) {
      pose_weight_[k] = (in.pose_weights.empty() ? 1.0 : double(in.pose_weights[k])) / total;
      for (uint32_t j = 0; j < joint_count_; ++j) {
        const std::array<float, 16>& m = in.poses[k][j];
        Affine& a = joints_[size_t(k) * joint_count_ + j];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 4; ++c) a.m[r][c] = m[size_t(4 * c + r)];
      }
    }
  }

  void initialize(State& state) {
    const Mesh& mesh = state.mesh;
    slots_ = mesh.influence_slots();
    influences_.assign(state.position_count, {});
    chosen_.assign(state.position_count, 0);
    std::vector<uint8_t> set(state.position_count, 0);
    // A position's influences are those of its first wedge (wedges of one position normally agree).
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      const uint32_t u = state.position_of[v];
      if (set[u]) continue;
      set[u] = 1;
      std::pair<uint16_t, float> raw[max_influences];
      const float4& w = mesh.weights[v];
      const ushort4& j = mesh.joints[v];
      raw[0] = {j[0], w.x}, raw[1] = {j[1], w.y}, raw[2] = {j[2], w.z}, raw[3] = {j[3], w.w};
      if (slots_ == 8) {
        const float4& w1 = mesh.weights1[v];
        const ushort4& j1 = mesh.joints1[v];
        raw[4] = {j1[0], w1.x}, raw[5] = {j1[1], w1.y}, raw[6] = {j1[2], w1.z}, raw[7] = {j1[3], w1.w};
      }
      influences_[u] = top_influences({raw, slots_}, slots_);
    }
    // Each position in each pose, then each position's per-pose quadrics from its faces there.
    const uint32_t K = pose_count_;
    std::vector<vec3d> posed(size_t(state.position_count) * K);
    core::parallel_for(state.position_count, state.threads, [&](size_t u) {
      const vec3d p = state.normalized(uint32_t(u));
      for (uint32_t k = 0; k < K; ++k) posed[u * K + k] = pose_point(state, k, influences_[u], p);
    });
    quadric_.assign(size_t(state.position_count) * K, {});
    core::parallel_for(state.position_count, state.threads, [&](size_t u) {
      if (state.flags[u] & flag_dead) return;
      const double importance = state.importance.empty() ? 1.0 : state.importance[u];
      for (const uint32_t t : state.triangles_of(uint32_t(u)))
        for (uint32_t k = 0; k < K; ++k) {
          vec3d p[3];
          for (uint32_t c = 0; c < 3; ++c) p[c] = posed[size_t(state.corner_position(t, c)) * K + k];
          add_face_quadric(state, uint32_t(u), t, p, importance, constrained_, quadric_[u * K + k]);
        }
      // Each pose's share, applied once per sum (with one pose it is 1: the sums are bind-pose QEM's).
      for (uint32_t k = 0; k < K; ++k)
        if (pose_weight_[k] != 1.0) {
          const QuadricD q = quadric_[u * K + k];
          quadric_[u * K + k] = {};
          quadric_[u * K + k].add_scaled(q, pose_weight_[k]);
        }
    });
  }
  void begin_pass(State&) {}

  Placement place(const State& state, const EdgeQuery& edge) const {
    const Choice c = choose(state, edge);
    return {c.cost, c.position};
  }

  void collapsed(State& state, const EdgeQuery& edge, const vec3d& position) {
    // The engine passes the placement but not every flag place() saw (on_edge): choose the
    // influences again at that position.
    const Choice c = choose(state, edge, &position);
    influences_[edge.kept] = c.influences;
    chosen_[edge.kept] = 1;
    const size_t K = pose_count_;
    for (size_t k = 0; k < K; ++k) quadric_[edge.kept * K + k] += quadric_[edge.removed * K + k];
  }

  void attributes_at(const State&, uint32_t, const vec3d&, float*) const {}
  bool reads_neighbourhood() const { return false; }

  // The influences of a position (internal id), and whether a collapse chose them: the wedges of a
  // position no collapse kept keep their own, the input's.
  const Influences& influences(uint32_t position) const { return influences_[position]; }
  // (None before initialize(), which the engine calls only if there is something to collapse.)
  bool chose(uint32_t position) const { return position < chosen_.size() && chosen_[position] != 0; }

 private:
  struct Affine {
    double m[3][4];  // rows of the top 3x4 of a joint matrix
  };
  struct Choice {
    double cost = 0;
    vec3d position;
    Influences influences;
  };

  // The blended joint matrix of `w` in pose k.
  Affine blend(uint32_t k, const Influences& w) const {
    Affine out{};
    for (int i = 0; i < max_influences; ++i) {
      if (w.weight[i] == 0 || w.joint[i] >= joint_count_) continue;
      const Affine& a = joints_[size_t(k) * joint_count_ + w.joint[i]];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) out.m[r][c] += w.weight[i] * a.m[r][c];
    }
    return out;
  }

  // In the normalised frame q = (x - center) * scale: q_k = A q + t' with t' = scale (A c + t - c).
  Affine normalised(const State& state, const Affine& b) const {
    Affine out = b;
    const double c[3] = {state.center.x, state.center.y, state.center.z};
    for (int r = 0; r < 3; ++r)
      out.m[r][3] = state.scale * (b.m[r][0] * c[0] + b.m[r][1] * c[1] + b.m[r][2] * c[2] + b.m[r][3] - c[r]);
    return out;
  }

  vec3d pose_point(const State& state, uint32_t k, const Influences& w, const vec3d& p) const {
    const Affine a = normalised(state, blend(k, w));
    return {a.m[0][0] * p.x + a.m[0][1] * p.y + a.m[0][2] * p.z + a.m[0][3],
            a.m[1][0] * p.x + a.m[1][1] * p.y + a.m[1][2] * p.z + a.m[1][3],
            a.m[2][0] * p.x + a.m[2][1] * p.y + a.m[2][2] * p.z + a.m[2][3]};
  }

  // Q(A p + t) as a quadric in p: A^T Qa A, A^T (Qa t + b), t^T Qa t + 2 b.t + c.
  static void add_pulled_back(const QuadricD& q, const Affine& x, QuadricD& out) {
    const double Q[3][3] = {{q.a00, q.a01, q.a02}, {q.a01, q.a11, q.a12}, {q.a02, q.a12, q.a22}};
    const double b[3] = {q.b0, q.b1, q.b2};
    double QA[3][3];  // Qa * A
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) QA[r][c] = Q[r][0] * x.m[0][c] + Q[r][1] * x.m[1][c] + Q[r][2] * x.m[2][c];
    auto ata = [&](int i, int j) { return x.m[0][i] * QA[0][j] + x.m[1][i] * QA[1][j] + x.m[2][i] * QA[2][j]; };
    const double t[3] = {x.m[0][3], x.m[1][3], x.m[2][3]};
    double g[3];  // Qa t + b
    for (int r = 0; r < 3; ++r) g[r] = Q[r][0] * t[0] + Q[r][1] * t[1] + Q[r][2] * t[2] + b[r];
    out.a00 += ata(0, 0), out.a01 += ata(0, 1), out.a02 += ata(0, 2);
    out.a11 += ata(1, 1), out.a12 += ata(1, 2), out.a22 += ata(2, 2);
    out.b0 += x.m[0][0] * g[0] + x.m[1][0] * g[1] + x.m[2][0] * g[2];
    out.b1 += x.m[0][1] * g[0] + x.m[1][1] * g[1] + x.m[2][1] * g[2];
    out.b2 += x.m[0][2] * g[0] + x.m[1][2] * g[1] + x.m[2][2] * g[2];
    out.c += q.c + t[0] * (g[0] + b[0]) + t[1] * (g[1] + b[1]) + t[2] * (g[2] + b[2]);
    out.w += q.w;
  }

  // The best candidate influences and position; with `at`, the best influences at that position.
  Choice choose(const State& state, const EdgeQuery& edge, const vec3d* at = nullptr) const {
    const Influences& wk = influences_[edge.kept];
    const Influences& wr = influences_[edge.removed];
    Influences candidates[3] = {wk, wr, {}};
    int count = 1;
    if (!edge.fixed) {
      if (!(wr == wk)) candidates[count++] = wr;
      std::pair<uint16_t, float> both[2 * max_influences];
      int n = 0;
      for (int i = 0; i < max_influences; ++i)
        if (wk.weight[i] > 0) both[n++] = {wk.joint[i], 0.5f * wk.weight[i]};
      for (int i = 0; i < max_influences; ++i) {
        if (wr.weight[i] == 0) continue;
        bool found = false;
        for (int j = 0; j < n; ++j)
          if (both[j].first == wr.joint[i]) both[j].second += 0.5f * wr.weight[i], found = true;
        if (!found) both[n++] = {wr.joint[i], 0.5f * wr.weight[i]};
      }
      const Influences blended = top_influences({both, size_t(n)}, slots_);
      if (!(blended == wk) && !(blended == wr)) candidates[count++] = blended;
    }
    const vec3d a = state.normalized(edge.kept), b = state.normalized(edge.removed);
    // Collapsing across very different influences is what tears joints in poses never sampled.
    const double bone = bone_weight_ * influence_distance(wk, wr);
    const double bone_cost = bone * bone * length_squared(b - a);
    const size_t K = pose_count_;
    Choice best;
    best.cost = -1;
    for (int i = 0; i < count; ++i) {
      QuadricD q;
      for (size_t k = 0; k < K; ++k) {
        QuadricD sum = quadric_[edge.kept * K + k];
        sum += quadric_[edge.removed * K + k];
        add_pulled_back(sum, normalised(state, blend(uint32_t(k), candidates[i])), q);
      }
      vec3d p = at ? *at : a;
      if (!at && edge.on_edge) {
        p = core::segment_optimum(q, a, b);
      } else if (!at && !edge.fixed) {
        const bool near = core::optimum(q, p) && length_squared(p - (a + b) * 0.5) <= 4 * length_squared(b - a);
        if (!near) p = core::segment_optimum(q, a, b);
      }
      const double value = core::evaluate(q, p);
      const double cost = (q.w > 0 ? value / q.w : value) + bone_cost;
      if (best.cost < 0 || cost < best.cost) best = {cost, p, candidates[i]};
    }
    return best;
  }

  uint32_t pose_count_ = 0, joint_count_ = 0;
  size_t slots_ = 4;                    // influence slots per vertex: 4, or 8 with a second set
  std::vector<double> pose_weight_;
  std::vector<Affine> joints_;          // pose-major
  std::vector<uint8_t> chosen_;         // per position: influences chosen by a collapse
  std::vector<Influences> influences_;  // per position
  std::vector<QuadricD> quadric_;       // position-major, one per pose (weighted by the pose's share)
  float bone_weight_ = 0;
  bool constrained_ = true;
};

// lod::simplify with the multi-pose metric (constrained, no attribute channels). The output's joints
// and weights are the influences each position ended with. Throws lod::Error (usage) for bad input.
SimplifyResult simplify_multipose(const Mesh& mesh, const SimplifyOptions& options, const MultiposeInput& input);

}  // namespace lod::collapse
