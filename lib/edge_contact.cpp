#include "edge_contact.hpp"

#include "friction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace liedyn {

namespace {

// The n-point rule on [−1, 1] by Newton's method on the Legendre polynomial P_n from the
// usual cosine guesses (each converges to its own root), mapped to [0, 1]. Roots come in
// ± pairs, so each pair is computed once and the rule is exactly symmetric about ½.
QuadratureRule make_rule(int n) {
  QuadratureRule rule;
  rule.size = n;
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double derivative = 1.0;  // P_n'(z)
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p1 = 1.0, p2 = 0.0;  // P_j(z), P_{j−1}(z) by the three-term recurrence
      for (int j = 1; j <= n; ++j) {
        const double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
      }
      derivative = n * (z * p1 - p2) / (z * z - 1.0);
      const double step = p1 / derivative;
      z -= step;
      if (std::abs(step) <= 1e-16) break;
    }
    if (2 * i + 1 == n) z = 0.0;  // the middle root of an odd rule
    const double weight = 1.0 / ((1.0 - z * z) * derivative * derivative);  // ½ · 2/((1−z²)P')
    rule.nodes[i] = 0.5 * (1.0 - z);
    rule.nodes[n - 1 - i] = 0.5 * (1.0 + z);
    rule.weights[i] = weight;
    rule.weights[n - 1 - i] = weight;
  }
  return rule;
}

// A point p projected onto the segment [b0, b1] (edge_contact.hpp).
struct Projection {
  Vector3 w;        // p − (b0 + t e)
  Vector3 e;        // b1 − b0
  double distance;  // |w|
  double t;         // clamp(t̂, 0, 1); 0 when |e| = 0
  bool interior;    // 0 < t̂ < 1: t moves with the points (else it is constant)
};

Projection project(const Vector3& p, const Vector3& b0, const Vector3& b1) {
  Projection out;
  out.e = b1 - b0;
  const Vector3 u = p - b0;
  const double ee = out.e.squaredNorm();
  out.t = 0.0;
  out.interior = false;
  if (ee > 0.0) {
    const double t_hat = u.dot(out.e) / ee;
    if (t_hat >= 1.0) {
      out.t = 1.0;
    } else if (t_hat > 0.0) {
      out.t = t_hat;
      out.interior = true;
    }
  }
  out.w = out.t == 1.0 ? Vector3(p - b1) : Vector3(u - out.t * out.e);
  out.distance = out.w.norm();
  return out;
}

// Adds the derivatives of ψ(d) for d = |Σ_i α_i x_i| (at fixed t) over M blocks, given
// ψ' = d1 and ψ'' = d2 (edge_contact.hpp):
//   gradient block i:  ψ' α_i n,
//   Hessian block ij:  α_i α_j (ψ'' n nᵀ + (ψ'/d) P) − [interior] (ψ'/d) u_i u_jᵀ.
// Needs d > 0.
template <int M>
void add_distance_derivatives(const Projection& pr, const std::array<double, M>& alpha,
                              const std::array<double, M>& beta, double d1, double d2,
                              LocalGradient<M>* g, LocalHessian<M>* H) {
  const double inv_d = 1.0 / pr.distance;
  const Vector3 n = inv_d * pr.w;
  if (g != nullptr) {
    for (int i = 0; i < M; ++i) g->template segment<3>(3 * i) += (d1 * alpha[i]) * n;
  }
  if (H == nullptr) return;
  const double lateral = d1 * inv_d;  // ψ'/d
  const Matrix3 nn = n * n.transpose();
  const Matrix3 K = d2 * nn + lateral * (Matrix3::Identity() - nn);
  std::array<Vector3, M> u;
  if (pr.interior) {
    const double inv_length = 1.0 / pr.e.norm();
    for (int i = 0; i < M; ++i) u[i] = (alpha[i] * inv_length) * pr.e + (beta[i] * inv_length) * pr.w;
  }
  for (int i = 0; i < M; ++i) {
    for (int j = i; j < M; ++j) {
      Matrix3 block = (alpha[i] * alpha[j]) * K;
      if (pr.interior) block -= lateral * (u[i] * u[j].transpose());
      H->template block<3, 3>(3 * i, 3 * j) += block;
      if (j != i) H->template block<3, 3>(3 * j, 3 * i) += block.transpose();
    }
  }
}

// The chain factors of a sample s of one edge against the other's segment at t, blocks
// (a0, a1, b0, b1): side 0 samples a, side 1 samples b.
std::array<double, 4> sample_alpha(int side, double s, double t) {
  if (side == 0) return {1.0 - s, s, -(1.0 - t), -t};
  return {-(1.0 - t), -t, 1.0 - s, s};
}
std::array<double, 4> sample_beta(int side) {
  if (side == 0) return {0.0, 0.0, -1.0, 1.0};
  return {-1.0, 1.0, 0.0, 0.0};
}

// The four nodes a0, a1, b0, b1 at q.
// c_q = ½ w_q ℓ̄ of side's sample k: its share of the penalty integrated from both sides.
template <int N>
double sample_weight(const EdgeEdgeSample& term, int side, int k) {
  return 0.5 * gauss_legendre(N).weights[k] * (side == 0 ? term.rest_length_a : term.rest_length_b);
}

std::array<const Vector3*, 4> node_positions(const EdgeEdgeSample& term, const State& q) {
  return {&q.points[term.nodes[0]], &q.points[term.nodes[1]], &q.points[term.nodes[2]], &q.points[term.nodes[3]]};
}

// Calls visit(side, k, s, c, projection) for every sample: side 0 the N samples of a against
// [b0, b1], side 1 those of b against [a0, a1]; c = ½ w_k ℓ̄ its weight.
template <int N, class Visit>
void for_each_sample(const EdgeEdgeSample& term, const State& q, Visit&& visit) {
  const QuadratureRule& rule = gauss_legendre(N);
  const std::array<const Vector3*, 4> x = node_positions(term, q);
  for (int side = 0; side < 2; ++side) {
    const Vector3& p0 = *x[2 * side];
    const Vector3& p1 = *x[2 * side + 1];
    const Vector3& s0 = *x[2 - 2 * side];
    const Vector3& s1 = *x[3 - 2 * side];
    for (int k = 0; k < N; ++k) {
      const double s = rule.nodes[k];
      const Vector3 p = (1.0 - s) * p0 + s * p1;
      visit(side, k, s, sample_weight<N>(term, side, k), project(p, s0, s1));
    }
  }
}

}  // namespace

const QuadratureRule& gauss_legendre(int n) {
  static const std::array<QuadratureRule, kMaxEdgeQuadraturePoints + 1> rules = [] {
    std::array<QuadratureRule, kMaxEdgeQuadraturePoints + 1> out;
    for (int n = 1; n <= kMaxEdgeQuadraturePoints; ++n) out[n] = make_rule(n);
    return out;
  }();
  if (n < 1 || n > kMaxEdgeQuadraturePoints) {
    throw std::out_of_range("gauss_legendre: 1 to kMaxEdgeQuadraturePoints points");
  }
  return rules[n];
}

double point_segment_distance(const Vector3& p, const Vector3& b0, const Vector3& b1,
                              LocalGradient<3>* g, LocalHessian<3>* H) {
  const Projection pr = project(p, b0, b1);
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  if ((g != nullptr || H != nullptr) && pr.distance > 0.0) {
    add_distance_derivatives<3>(pr, {1.0, -(1.0 - pr.t), -pr.t}, {0.0, -1.0, 1.0}, 1.0, 0.0,
                                g, H);
  }
  return pr.distance;
}

double segment_distance(const Vector3& a0, const Vector3& a1, const Vector3& b0,
                        const Vector3& b1) {
  double best = std::min({point_segment_distance(a0, b0, b1), point_segment_distance(a1, b0, b1),
                          point_segment_distance(b0, a0, a1), point_segment_distance(b1, a0, a1)});
  // The lines' closest pair: minimise |r + s d1 − t d2|², r = a0 − b0.
  const Vector3 d1 = a1 - a0;
  const Vector3 d2 = b1 - b0;
  const Vector3 r = a0 - b0;
  const double A = d1.squaredNorm();
  const double E = d2.squaredNorm();
  const double B = d1.dot(d2);
  const double denominator = A * E - B * B;  // A E sin²(angle) ≥ 0 up to round-off
  if (A > 0.0 && E > 0.0 && denominator > 0.0) {
    const double C = d1.dot(r);
    const double F = d2.dot(r);
    // s from the 2 × 2 system, and t the best for that s. Where the lines are nearly
    // parallel the system is ill-conditioned and s is off by up to ~ eps/sin²(angle), but
    // with t fitted to it the pair only slides along the lines, which costs ~ sin²(angle)
    // times that squared. Where either is clamped the minimum involves an end, which the
    // candidates above cover.
    const double s = std::clamp((B * F - C * E) / denominator, 0.0, 1.0);
    const double t = std::clamp((B * s + F) / E, 0.0, 1.0);
    best = std::min(best, (r + s * d1 - t * d2).norm());
  }
  return best;
}

template <int N>
double BasicEdgeContact<N>::evaluate(const State& q, LocalGradient<kBlocks>* g,
                                     LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  const double reach = radius_a + radius_b;
  // Each edge's half apart, added last, so that swapping a and b gives the same value exactly.
  std::array<double, 2> half{0.0, 0.0};
  for_each_sample<N>(*this, q, [&](int side, int, double s, double c, const Projection& pr) {
    const double gap = reach - pr.distance;
    if (!(gap > 0.0)) return;
    const double ck = c * stiffness;
    half[side] += 0.5 * ck * gap * gap;
    if ((g != nullptr || H != nullptr) && pr.distance > 0.0) {
      add_distance_derivatives<4>(pr, sample_alpha(side, s, pr.t), sample_beta(side), -ck * gap,
                                  ck, g, H);
    }
  });
  return half[0] + half[1];
}

template <int N>
double BasicEdgeContact<N>::penetration(const State& q) const {
  double closest = std::numeric_limits<double>::infinity();
  for_each_sample<N>(*this, q, [&](int, int, double, double, const Projection& pr) {
    closest = std::min(closest, pr.distance);
  });
  return radius_a + radius_b - closest;
}

template <int N>
void BasicEdgeContact<N>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  r.setZero();
  if (J != nullptr) J->setZero();
  const double reach = radius_a + radius_b;
  for_each_sample<N>(*this, q, [&](int side, int k, double s, double c, const Projection& pr) {
    const double gap = reach - pr.distance;
    if (!(gap > 0.0)) return;
    const int row = side * N + k;
    const double root = std::sqrt(c * stiffness);
    r(row) = root * gap;
    if (J != nullptr && pr.distance > 0.0) {
      const Vector3 n = pr.w / pr.distance;
      const std::array<double, 4> alpha = sample_alpha(side, s, pr.t);
      for (int i = 0; i < 4; ++i) J->template block<1, 3>(row, 3 * i) = (-root * alpha[i]) * n.transpose();
    }
  });
}

template struct BasicEdgeContact<1>;
template struct BasicEdgeContact<2>;
template struct BasicEdgeContact<4>;
template struct BasicEdgeContact<8>;

template <int N, class Law>
void BasicEdgeDissipation<N, Law>::begin_step(const State& previous, const Step&) {
  const double reach = radius_a + radius_b;
  for_each_sample<N>(*this, previous, [&](int side, int k, double, double c, const Projection& pr) {
    LaggedEdgeSample& l = lagged[side * N + k];
    const double gap = reach - pr.distance;
    const bool touching = gap > 0.0 && pr.distance > 0.0;  // d̂ = 0: no normal (header)
    l.t = pr.t;
    l.separation = pr.w;
    l.normal_force = touching ? c * stiffness * gap : 0.0;
    l.normal = touching ? Vector3(pr.w / pr.distance) : Vector3::UnitZ();
  });
}

namespace {

// A sample's slip over the step relative to the point it touched: W = Σ_i α_i(t̄) x_i − ŵ.
Vector3 relative_slip(const std::array<double, 4>& alpha, const std::array<const Vector3*, 4>& x,
                      const LaggedEdgeSample& l) {
  Vector3 W = -l.separation;
  for (int i = 0; i < 4; ++i) W += alpha[i] * *x[i];
  return W;
}

// Calls visit(side, k, α, W, c_q k) for every sample in contact at the step's start.
template <int N, class Law, class Visit>
void for_each_lagged_sample(const BasicEdgeDissipation<N, Law>& term, const State& q, Visit&& visit) {
  const QuadratureRule& rule = gauss_legendre(N);
  const std::array<const Vector3*, 4> x = node_positions(term, q);
  for (int side = 0; side < 2; ++side) {
    for (int k = 0; k < N; ++k) {
      const LaggedEdgeSample& l = term.lagged[side * N + k];
      if (l.normal_force == 0.0) continue;
      const std::array<double, 4> alpha = sample_alpha(side, rule.nodes[k], l.t);
      visit(side, k, alpha, relative_slip(alpha, x, l), sample_weight<N>(term, side, k) * term.stiffness);
    }
  }
}

}  // namespace

template <int N, class Law>
double BasicEdgeDissipation<N, Law>::evaluate(const State& q, LocalGradient<kBlocks>* g,
                                              LocalHessian<kBlocks>* H) const {
  if (g != nullptr) g->setZero();
  if (H != nullptr) H->setZero();
  double value = 0.0;
  for_each_lagged_sample(*this, q, [&](int side, int k, const std::array<double, 4>& alpha, const Vector3& W,
                                       double stiffness_k) {
    const LaggedEdgeSample& l = lagged[side * N + k];
    Vector3 f;
    Matrix3 K;
    value += law[side].evaluate(W, l.normal_force, l.normal, stiffness_k, g != nullptr ? &f : nullptr,
                                H != nullptr ? &K : nullptr);
    if (g != nullptr) {
      for (int i = 0; i < 4; ++i) g->template segment<3>(3 * i) += alpha[i] * f;
    }
    if (H != nullptr) {  // α_i α_j K with K symmetric: each block pair once
      for (int i = 0; i < 4; ++i) {
        for (int j = i; j < 4; ++j) {
          const Matrix3 block = (alpha[i] * alpha[j]) * K;
          H->template block<3, 3>(3 * i, 3 * j) += block;
          if (j != i) H->template block<3, 3>(3 * j, 3 * i) += block;
        }
      }
    }
  });
  return value;
}

template <int N, class Law>
void BasicEdgeDissipation<N, Law>::residual(const State& q, Residual& r, ResidualJacobian* J) const {
  if constexpr (Law::kResidualPerSample) {
    r.setZero();
    if (J != nullptr) J->setZero();
    for_each_lagged_sample(*this, q, [&](int side, int k, const std::array<double, 4>& alpha, const Vector3& W,
                                         double stiffness_k) {
      Eigen::RowVector3d row;
      r(side * N + k) = law[side].residual(W, lagged[side * N + k].normal, stiffness_k, row);
      if (J != nullptr) {
        for (int i = 0; i < 4; ++i) J->template block<1, 3>(side * N + k, 3 * i) = alpha[i] * row;
      }
    });
  } else {
    friction_residual(*this, q, r, J);
  }
}

template <int N, class Law>
Eigen::Matrix<double, 12, 12> BasicEdgeDissipation<N, Law>::previous_jacobian(const State& q,
                                                                              const State& previous) const {
  Eigen::Matrix<double, 12, 12> out = Eigen::Matrix<double, 12, 12>::Zero();
  const std::array<const Vector3*, 4> x = node_positions(*this, q);
  const std::array<const Vector3*, 4> x_hat = node_positions(*this, previous);
  const Matrix3 I = Matrix3::Identity();
  // The projections at q_{k−1} again: the same t̄, ŵ and d̂ begin_step froze.
  for_each_sample<N>(*this, previous, [&](int side, int k, double s, double c, const Projection& pr) {
    const LaggedEdgeSample& l = lagged[side * N + k];
    if (l.normal_force == 0.0) return;
    const std::array<double, 4> alpha = sample_alpha(side, s, l.t);
    const std::array<double, 4> beta = sample_beta(side);
    std::array<Vector3, 4> gamma;  // ∂t̄/∂x̂_j
    for (int j = 0; j < 4; ++j) {
      gamma[j] = pr.interior ? Vector3((alpha[j] * pr.e + beta[j] * pr.w) / pr.e.squaredNorm()) : Vector3::Zero();
    }
    Vector3 moved_other = Vector3::Zero();  // Σ_i β_i (x_i − x̂_i)
    for (int i = 0; i < 4; ++i) moved_other += beta[i] * (*x[i] - *x_hat[i]);
    const Vector3& n = l.normal;
    const Matrix3 P = I - n * n.transpose();
    const Vector3 W = relative_slip(alpha, x, l);
    const double stiffness_k = c * stiffness;
    Vector3 f;
    law[side].evaluate(W, l.normal_force, n, stiffness_k, &f, nullptr);
    for (int j = 0; j < 4; ++j) {
      const Matrix3 dW = -alpha[j] * I - moved_other * gamma[j].transpose();
      const Matrix3 dn = P * (alpha[j] * I - pr.e * gamma[j].transpose()) / pr.distance;
      const Eigen::RowVector3d dlambda = -stiffness_k * alpha[j] * n.transpose();
      const Matrix3 df = law[side].force_jacobian(W, l.normal_force, n, stiffness_k, dW, dlambda, dn);
      for (int i = 0; i < 4; ++i) {
        out.template block<3, 3>(3 * i, 3 * j) += alpha[i] * df - beta[i] * f * gamma[j].transpose();
      }
    }
  });
  return out;
}

template <int N, class Law>
void BasicEdgeDissipation<N, Law>::add_step_adjoint(const State& q, const State& previous, const Step&,
                                                    const LocalGradient<kBlocks>& z, Eigen::VectorXd& a_previous,
                                                    Eigen::VectorXd&) const {
  if (std::all_of(lagged.begin(), lagged.end(), [](const LaggedEdgeSample& l) { return l.normal_force == 0.0; })) {
    return;
  }
  const LocalGradient<kBlocks> w = previous_jacobian(q, previous).transpose() * z;
  for (int b = 0; b < 4; ++b) a_previous.template segment<3>(tangent_point(nodes[b])) += w.template segment<3>(3 * b);
}

template struct BasicEdgeDissipation<1, SlipFriction>;
template struct BasicEdgeDissipation<4, SlipFriction>;
template struct BasicEdgeDissipation<4, NormalDashpot>;

TouchingEdges::TouchingEdges(const Model& model) {
  for (const EdgePair& e : model.edge_pairs()) {
    candidates_.push_back({{model.rod_point(e.rod_a, e.edge_a), model.rod_point(e.rod_a, e.edge_a + 1),
                            model.rod_point(e.rod_b, e.edge_b), model.rod_point(e.rod_b, e.edge_b + 1)},
                           model.rods[e.rod_a].contact.radius + model.rods[e.rod_b].contact.radius});
  }
}

double TouchingEdges::gap(const State& q, std::size_t p) const {
  const Candidate& c = candidates_[p];
  const auto& x = q.points;
  return segment_distance(x[c.nodes[0]], x[c.nodes[1]], x[c.nodes[2]], x[c.nodes[3]]) - c.radii;
}

bool TouchingEdges::touches(const State& q, const Step& step, std::size_t p) const {
  const auto& x = q.points;
  const auto moved = [&](int i) { return step.points.empty() ? 0.0 : step.points[i].norm(); };
  const auto& n = candidates_[p].nodes;
  const double margin = std::max(moved(n[0]), moved(n[1])) + std::max(moved(n[2]), moved(n[3]));
  const double reach = 0.5 * ((x[n[1]] - x[n[0]]).norm() + (x[n[3]] - x[n[2]]).norm()) + candidates_[p].radii + margin;
  const Vector3 between = 0.5 * (x[n[0]] + x[n[1]] - x[n[2]] - x[n[3]]);  // midpoint to midpoint
  return between.squaredNorm() <= reach * reach && gap(q, p) < margin;
}

void TouchingEdges::find(const State& q, const Step& step, std::vector<bool>& touching, std::size_t first) const {
  for (std::size_t p = 0; p < candidates_.size(); ++p) touching[first + p] = touches(q, step, p);
}

double TouchingEdges::min_separation(const State& q) const {
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < candidates_.size(); ++p) smallest = std::min(smallest, gap(q, p));
  return smallest;
}

}  // namespace liedyn
