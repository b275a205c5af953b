#pragma once
// Objectives g({q_k}, γ) of trajectory optimisation (paper §5, §7.3–7.4): a weighted sum of
// terms, each owning its value and its derivatives with respect to the states q_k, the steps
// Δq_k (Lie derivatives for rotations, whole-state tangent layout: lib/trajectory.hpp) and
// the parameters γ, which the adjoint pass (solvers/adjoint.hpp) needs.
// A frame index −1 means the last frame n.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "trajectory.hpp"

namespace liedyn {

class ObjectiveTerm {
 public:
  virtual ~ObjectiveTerm() = default;
  virtual std::string name() const = 0;
  virtual double value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const = 0;
  // Adds ∂g/∂q_k to a and ∂g/∂Δq_k to da (whole-state tangent layout) for frame k.
  virtual void add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                                  Eigen::VectorXd& da) const = 0;
  // Adds ∂g/∂γ (explicit dependence only).
  virtual void add_parameter_gradient(const Eigen::VectorXd& gamma, Eigen::VectorXd& dgamma) const {
    (void)gamma;
    (void)dgamma;
  }
};

// w Σ_i ‖x_{p_i} − t_i‖² at one frame: rod nodes (or bodies) against a target shape, e.g. a
// letter polyline resampled to the rod's node count (paper Fig. 1, 9).
class PointTargets final : public ObjectiveTerm {
 public:
  PointTargets(std::vector<int> points, std::vector<Vector3> targets, int frame, double weight);
  std::string name() const override { return "point_targets"; }
  double value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const override;
  void add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                          Eigen::VectorXd& da) const override;

 private:
  std::vector<int> points_;
  std::vector<Vector3> targets_;
  int frame_;
  double weight_;
};

// The pose of a body at one frame (paper Fig. 8, the die):
//   Σ_a w_a (x_a − t_a)²  +  w_R ‖log(R R*ᵀ)‖²,
// per-axis position weights w (e.g. (0, 0, 1) for the height only) and the squared geodesic
// orientation error. Its Lie gradient is exactly 2 w_R log(R R*ᵀ): with φ = log(R R*ᵀ),
// log(exp(θ) R R*ᵀ) = φ + J_l⁻¹(φ) θ + O(θ²) and J_l⁻ᵀ(φ) φ = φ. (At ‖φ‖ = π the geodesic
// distance is not differentiable; the gradient returned there is one of its limits.)
class BodyPose final : public ObjectiveTerm {
 public:
  BodyPose(int body, int frame, Vector3 position, Vector3 position_weights, Matrix3 orientation,
           double orientation_weight);
  std::string name() const override { return "body_pose"; }
  double value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const override;
  void add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                          Eigen::VectorXd& da) const override;

 private:
  int body_, frame_;
  Vector3 position_, position_weights_;
  Matrix3 orientation_;
  double orientation_weight_;
};

// A point's trajectory against a curve under orthographic projection (paper Fig. 10, 11):
//   w Σ_{k=1…n} ‖P x_k − c_k‖²,   P = the 2×3 projection onto two world axes,
// c_k the curve's point at frame k (one per frame).
class ProjectedTrajectory final : public ObjectiveTerm {
 public:
  ProjectedTrajectory(int point, Eigen::Matrix<double, 2, 3> projection,
                      std::vector<Eigen::Vector2d> curve, double weight);
  std::string name() const override { return "projected_trajectory"; }
  double value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const override;
  void add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                          Eigen::VectorXd& da) const override;

 private:
  int point_;
  Eigen::Matrix<double, 2, 3> projection_;
  std::vector<Eigen::Vector2d> curve_;
  double weight_;
};

// Control-effort regularisation w Σ_{j ∈ [begin, end)} γ_j², e.g. over the per-frame cable
// tensions or forces.
class Effort final : public ObjectiveTerm {
 public:
  Effort(int begin, int end, double weight);
  std::string name() const override { return "effort"; }
  double value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const override;
  void add_state_gradient(const Trajectory&, int, Eigen::VectorXd&, Eigen::VectorXd&) const override {}
  void add_parameter_gradient(const Eigen::VectorXd& gamma, Eigen::VectorXd& dgamma) const override;

 private:
  int begin_, end_;
  double weight_;
};

// The sum of its terms.
class Objective {
 public:
  void add(std::shared_ptr<const ObjectiveTerm> term) { terms_.push_back(std::move(term)); }
  const std::vector<std::shared_ptr<const ObjectiveTerm>>& terms() const { return terms_; }
  double value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const;
  void add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                          Eigen::VectorXd& da) const;
  void add_parameter_gradient(const Eigen::VectorXd& gamma, Eigen::VectorXd& dgamma) const;

 private:
  std::vector<std::shared_ptr<const ObjectiveTerm>> terms_;
};

}  // namespace liedyn
