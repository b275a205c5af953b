#pragma once
// Cosserat rod energy terms (paper §6.2; Spillmann & Teschner 2007; docs/design.md §6).
//
// Layout: positions at nodes x_i (State::points), rotations at edges R_i (State::rotations);
// edge i joins nodes i and i+1 and carries the material frame R_i (R_i e_z is the edge
// tangent at rest); every edge has rest length l. Conventions as in so3.hpp: perturbations
// are left, R⁺ = exp(θ)R, and so3::vee(M) is the vector of the ANTISYMMETRIC part of M.
//
// Each term owns its value, Lie gradient and Lie Hessian (term.hpp); all three Hessians are
// exact and may be indefinite away from rest (the Newton solver regularises).
//
// ---------------------------------------------------------------------------------------
// Stretch, blocks (x_i, x_{i+1}):
//   Ψ_s = ½ k_s l (1 − ‖e‖/l)² = ½ (k_s/l) (L − l)²,   e = x_{i+1} − x_i,  L = ‖e‖,  n = e/L.
//   The axial force is ∂Ψ_s/∂L = (k_s/l)(L − l), so a rod under force F stretches by
//   ΔL = F l / k_s: k_s [N] is the axial stiffness EA.
//   ∂Ψ/∂e = (k_s/l)(L − l) n,   ∂²Ψ/∂e² = (k_s/l) [n nᵀ + (L − l)/L (I − n nᵀ)];
//   ∂e/∂(x_i, x_{i+1}) = (−I, I).
//
// Shear / alignment, blocks (x_i, x_{i+1}, θ_i):
//   Ψ_x = ½ k_x l (1 − dᵀt) = ¼ k_x l ‖d − t‖²,   d = e/L,  t = R_i a   (c := ½ k_x l),
//   a the unit material axis the edge aligns with: e_z for the elastic term; the damping of
//   the shear rate (rod_damping.hpp) uses the same form with a lagged axis. t moves with R_i
//   whatever a is (a left perturbation turns t by θ × t), so the formulas below hold for any a.
//   (The value uses the least-squares form: no cancellation near rest.)
//   Through e (a = dᵀt, P = I − d dᵀ, ∂d/∂e = P/L):
//     ∂Ψ/∂e   = −c P t / L,
//     ∂²Ψ/∂e² =  c [d tᵀ + t dᵀ + a (I − 3 d dᵀ)] / L².
//   Through θ: t → exp(θ) t = t + θ×t + ½ θ×(θ×t) + O(θ³), and
//     dᵀ(θ×t) = θ·(t×d),   dᵀ hat(θ)² t = (θ·d)(θ·t) − (θ·θ) a,  so
//     DΨ/DR   = −c t×d,
//     D²Ψ/DR² = −c [½ (d tᵀ + t dᵀ) − a I].
//   Mixed (x is additive, so it is ∂/∂e of the Lie gradient):
//     ∂²Ψ/∂θ∂e = −c hat(t) P / L.
//   At rest (t = d) the Hessian is c (I − d dᵀ)/L² ⊕ c (I − d dᵀ) coupled, PSD (Ψ ≥ 0 = Ψ(rest)).
//
// Bend / twist at interior node i, blocks (θ_a, θ_b) = (θ_{i−1}, θ_i):
//   Ψ_b = ½ l Δωᵀ K Δω,   Δω = ω − ω̄,   ω = vee(Q)/l,   Q = R_aᵀ R_b,   K = diag(K₁, K₂, K₃)
//   (vee(Q) = vee_exact(Q − Qᵀ)/2; ω is in the material frame of edge a).
//   Let C = R_b R_aᵀ (relative rotation in the world frame), so that R_aᵀ M R_b = R_aᵀ M C R_a
//   and, conjugation commuting with vee, ω(α, β) = R_aᵀ vee(E C)/l with
//     E = exp(−α) exp(β) = I + (B − A) + ½A² + ½B² − AB + O(3),   A = hat(α), B = hat(β).
//   Identities (any M, any u, v; derived index-wise):
//     vee(hat(u) M)         = G_M u,   G_M = ½ (tr(M) I − M),
//     vee(hat(u) hat(v) M)  = ½ (Mᵀu) × v − (u·v) vee(M)     (hat(u)hat(v) = v uᵀ − (u·v) I,
//                                                              vee(a bᵀ) = ½ b × a).
//   First order, with G = G_C:  ∂ω/∂β = R_aᵀ G / l = −∂ω/∂α.  With m = R_a K Δω (world):
//     g_b = Gᵀ m,   g_a = −Gᵀ m      (g_a + g_b = 0: Ψ is invariant under exp(φ)(R_a, R_b)).
//   Second order: Ψ₂ = ½ l ω₁ᵀ K ω₁ + l (KΔω)ᵀ ω₂,  and with c = vee(C), N = −C hat(m)
//   (mᵀ((Cᵀu) × v) = uᵀ N v):
//     l (KΔω)ᵀ ω₂ = mᵀ vee((½A² + ½B² − AB) C)
//                 = ¼ αᵀNα + ¼ βᵀNβ − ½ αᵀNβ − ½ (m·c)(‖α‖² + ‖β‖²) + (m·c) α·β.
//   Hence, with S = Gᵀ (R_a K R_aᵀ) G / l,
//     H_aa = H_bb = S + ¼ (N + Nᵀ) − (m·c) I,
//     H_ab = H_baᵀ = −S − ½ N + (m·c) I.
//   Checks: H_aa + H_ab + H_ba + H_bb = 0 (common rotation); at rest m = 0 and H = l JᵀKJ
//   (PSD); for a straight untwisted rod (C = I, G = I, ω̄ = 0) H_aa = H_bb = −H_ab = R K Rᵀ/l.
//
// ---------------------------------------------------------------------------------------
// Least-squares (residual) forms, for the Ceres back-end (contract: term.hpp). Each has
// Ψ = ½‖r‖² exactly (the constant is 0) and Jᵀr = the Lie gradient above; the square roots
// need non-negative stiffnesses:
//   Stretch  r = √(k_s/l) (L − l)  (1 residual),   J = √(k_s/l) [−nᵀ, nᵀ];
//            Jᵀr = (k_s/l)(L − l) [−n; n] ✓.
//   Shear    r = √c (d − t),  c = ½ k_x l  (3 residuals),
//            J = [−√c P/L, √c P/L, √c hat(t)]   (∂d/∂e = P/L; exp(θ)t = t − hat(t)θ + …,
//            so ∂(−t)/∂θ = hat(t)); Jᵀr: e-block c P(d − t)/L = −c P t/L ✓ (P d = 0),
//            θ-block −c hat(t)(d − t) = −c t × d ✓.
//   Bend     r = √l K^½ Δω  (3 residuals, K ≥ 0 diagonal),
//            J = [−W, W],  W = √l K^½ ∂ω/∂β = K^½ R_aᵀ G/√l;
//            Jᵀr = ±Gᵀ R_a K Δω = ±Gᵀ m ✓.
// Degenerate edges (L = 0, where d and n are undefined and evaluate() returns a zero
// gradient): r keeps evaluate()'s value and J = 0 (so Jᵀr = 0 = its gradient):
//   Stretch r = −√(k_s/l) l  (Ψ = ½ k_s l);   Shear r = −√(2c) t  (Ψ = c, d := 0 as in
//   evaluate(): ½ c‖d − t‖² with d ⊥ t, the mean over directions, not ½ c‖0 − t‖²).

#include "state.hpp"
#include "term.hpp"

namespace liedyn {

// Discrete Darboux vector of two adjacent edge frames, in the material frame of edge a:
//   ω = vee(R_aᵀ R_b)/l  ( = vee_exact(Q − Qᵀ)/(2l) ).  Used for the rest curvature ω̄.
Vector3 darboux_vector(const Matrix3& Ra, const Matrix3& Rb, double rest_length);

// The derivatives of an edge's potential Ψ(e), e = x_{i+1} − x_i, on the blocks (x_i, x_{i+1})
// from f = ∂Ψ/∂e and K = ∂²Ψ/∂e²: g = (−f, f), H = [K, −K; −K, K].
inline void edge_derivatives(const Vector3& f, const Matrix3& K, LocalGradient<2>* g,
                             LocalHessian<2>* H) {
  if (g != nullptr) {
    g->segment<3>(0) = -f;
    g->segment<3>(3) = f;
  }
  if (H != nullptr) {
    H->block<3, 3>(0, 0) = K;
    H->block<3, 3>(0, 3) = -K;
    H->block<3, 3>(3, 0) = -K;
    H->block<3, 3>(3, 3) = K;
  }
}

struct RodStretch {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "rod_stretch";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1};  // x_i, x_{i+1}
  int node0 = -1;                            // i    (State::points)
  int node1 = -1;                            // i+1  (State::points)
  double rest_length = 0.0;                  // l   [m], > 0
  double stiffness = 0.0;                    // k_s [N]  (axial stiffness EA)
  int stiffness_slot = -1;                   // γ index of k_s, −1: not a parameter (Ψ ∝ k_s)

  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;
  // HasParameters (term.hpp): the value is proportional to the stiffness.
  void add_parameter_adjoint(const State& q, int, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const {
    add_stiffness_adjoint(*this, q, z, dgamma);
  }

  static constexpr int kResiduals = 1;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  // r = √(k_s/l)(‖e‖ − l); J = √(k_s/l) [−nᵀ, nᵀ] (see the top; e = 0: J = 0).
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

struct RodShear {
  static constexpr int kBlocks = 3;
  static constexpr const char* kName = "rod_shear";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1, -1};  // x_i, x_{i+1}, θ_i
  int node0 = -1;                                // i    (State::points)
  int node1 = -1;                                // i+1  (State::points)
  int edge = -1;                                 // i    (State::rotations)
  double rest_length = 0.0;                      // l   [m]
  double stiffness = 0.0;                        // k_x [N]
  int stiffness_slot = -1;                       // γ index of k_x, −1: not a parameter (Ψ ∝ k_x)
  Vector3 material_axis = Vector3::UnitZ();      // a, unit (see the top)

  double evaluate(const State& q, LocalGradient<3>* g, LocalHessian<3>* H) const;
  // HasParameters (term.hpp): the value is proportional to the stiffness.
  void add_parameter_adjoint(const State& q, int, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const {
    add_stiffness_adjoint(*this, q, z, dgamma);
  }

  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  // r = √(k_x l/2)(d − t); J = [−√c P/L, √c P/L, √c hat(t)] (see the top; e = 0: J = 0).
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;
};

struct RodBendTwist {
  static constexpr int kBlocks = 2;
  static constexpr const char* kName = "rod_bend_twist";
  static constexpr bool kEnergyOfState = true;
  std::array<int, kBlocks> offsets{-1, -1};  // θ_{i−1}, θ_i
  int edge0 = -1;                            // i−1  (State::rotations), frame of ω
  int edge1 = -1;                            // i    (State::rotations)
  double rest_length = 0.0;                  // l   [m], > 0
  Vector3 stiffness = Vector3::Zero();       // (K₁, K₂, K₃) [N m²]: bend, bend, twist
  Vector3 rest_darboux = Vector3::Zero();    // ω̄ [1/m], material frame of edge i−1
  ScheduledParameter<3> rest_control;        // per-step ω̄ and its slot in γ (term.hpp)
  int stiffness_slot = -1;                   // γ index of (K₁, K₂, K₃), −1: not a parameter
  // A splice's junction (lib/incremental_potential.cpp): edge i is b's first edge, whose own
  // frame differs from a's last frame carried across the junction by a constant twist T
  // about the edge; the term sees R_i T, the frame one rod through the junction would have.
  // A left perturbation of R_i is one of R_i T, so the Lie derivatives below are unchanged.
  bool has_frame_offset = false;
  Matrix3 frame_offset = Matrix3::Identity();  // T

  void begin_frame(int k) { rest_darboux = rest_control.at(k, rest_darboux); }
  bool scheduled() const { return !rest_control.schedule.empty(); }
  double evaluate(const State& q, LocalGradient<2>* g, LocalHessian<2>* H) const;
  // For the adjoint, with W = Gᵀ R_a and the gradient (−W K Δω, W K Δω):
  //   ∂C/∂ω̄ = (W K, −W K),   ∂C/∂(K₁, K₂, K₃) = (−W diag(Δω), W diag(Δω)).
  void parameter_jacobians(const State& q, Eigen::Matrix<double, 6, 3>* d_rest_darboux,
                           Eigen::Matrix<double, 6, 3>* d_stiffness) const;
  // HasParameters (term.hpp): adds (∂C/∂γ)ᵀ z for step `frame`.
  void add_parameter_adjoint(const State& q, int frame, const LocalGradient<kBlocks>& z,
                             Eigen::VectorXd& dgamma) const;

  static constexpr int kResiduals = 3;
  using Residual = LocalResidual<kResiduals>;
  using ResidualJacobian = LocalResidualJacobian<kResiduals, kBlocks>;
  // r = √l K^½ Δω; J = [−W, W], W = K^½ R_aᵀ G/√l (see the top). Needs K ≥ 0.
  void residual(const State& q, Residual& r, ResidualJacobian* J) const;

  // R_i, or R_i T (in `storage`) with a frame offset: the frame of edge i the term sees.
  const Matrix3& rotation1(const State& q, Matrix3& storage) const {
    if (!has_frame_offset) return q.rotations[edge1];
    storage = q.rotations[edge1] * frame_offset;
    return storage;
  }
};

}  // namespace liedyn
