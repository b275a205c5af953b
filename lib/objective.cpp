#include "objective.hpp"

#include <stdexcept>

namespace liedyn {

namespace {

// Frame −1 is the last one.
int resolve(int frame, const Trajectory& t) { return frame < 0 ? t.frames() : frame; }

}  // namespace

PointTargets::PointTargets(std::vector<int> points, std::vector<Vector3> targets, int frame,
                           double weight)
    : points_(std::move(points)), targets_(std::move(targets)), frame_(frame), weight_(weight) {
  if (points_.size() != targets_.size()) {
    throw std::invalid_argument("PointTargets: " + std::to_string(points_.size()) +
                                " points but " + std::to_string(targets_.size()) + " targets");
  }
}

double PointTargets::value(const Trajectory& trajectory, const Eigen::VectorXd&) const {
  const State& q = trajectory.states.at(resolve(frame_, trajectory));
  double sum = 0.0;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    sum += (q.points[points_[i]] - targets_[i]).squaredNorm();
  }
  return weight_ * sum;
}

void PointTargets::add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                                      Eigen::VectorXd&) const {
  if (k != resolve(frame_, trajectory)) return;
  const State& q = trajectory.states[k];
  for (std::size_t i = 0; i < points_.size(); ++i) {
    a.segment<3>(tangent_point(points_[i])) += 2.0 * weight_ * (q.points[points_[i]] - targets_[i]);
  }
}

BodyPose::BodyPose(int body, int frame, Vector3 position, Vector3 position_weights,
                   Matrix3 orientation, double orientation_weight)
    : body_(body),
      frame_(frame),
      position_(position),
      position_weights_(position_weights),
      orientation_(orientation),
      orientation_weight_(orientation_weight) {}

double BodyPose::value(const Trajectory& trajectory, const Eigen::VectorXd&) const {
  const State& q = trajectory.states.at(resolve(frame_, trajectory));
  const Vector3 e = q.points[body_] - position_;
  const Vector3 phi = so3::log(q.rotations[body_] * orientation_.transpose());
  return position_weights_.dot(e.cwiseProduct(e)) + orientation_weight_ * phi.squaredNorm();
}

void BodyPose::add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                                  Eigen::VectorXd&) const {
  if (k != resolve(frame_, trajectory)) return;
  const State& q = trajectory.states[k];
  a.segment<3>(tangent_point(body_)) +=
      2.0 * position_weights_.cwiseProduct(q.points[body_] - position_);
  a.segment<3>(tangent_rotation(q, body_)) +=
      2.0 * orientation_weight_ * so3::log(q.rotations[body_] * orientation_.transpose());
}

ProjectedTrajectory::ProjectedTrajectory(int point, Eigen::Matrix<double, 2, 3> projection,
                                         std::vector<Eigen::Vector2d> curve, double weight)
    : point_(point), projection_(projection), curve_(std::move(curve)), weight_(weight) {}

double ProjectedTrajectory::value(const Trajectory& trajectory, const Eigen::VectorXd&) const {
  if (static_cast<int>(curve_.size()) != trajectory.frames()) {
    throw std::invalid_argument("ProjectedTrajectory: the curve has " +
                                std::to_string(curve_.size()) + " points for " +
                                std::to_string(trajectory.frames()) + " frames");
  }
  double sum = 0.0;
  for (int k = 1; k <= trajectory.frames(); ++k) {
    sum += (projection_ * trajectory.states[k].points[point_] - curve_[k - 1]).squaredNorm();
  }
  return weight_ * sum;
}

void ProjectedTrajectory::add_state_gradient(const Trajectory& trajectory, int k,
                                             Eigen::VectorXd& a, Eigen::VectorXd&) const {
  if (k < 1) return;
  const Eigen::Vector2d e = projection_ * trajectory.states[k].points[point_] - curve_[k - 1];
  a.segment<3>(tangent_point(point_)) += 2.0 * weight_ * projection_.transpose() * e;
}

Effort::Effort(int begin, int end, double weight) : begin_(begin), end_(end), weight_(weight) {}

double Effort::value(const Trajectory&, const Eigen::VectorXd& gamma) const {
  return weight_ * gamma.segment(begin_, end_ - begin_).squaredNorm();
}

void Effort::add_parameter_gradient(const Eigen::VectorXd& gamma, Eigen::VectorXd& dgamma) const {
  dgamma.segment(begin_, end_ - begin_) += 2.0 * weight_ * gamma.segment(begin_, end_ - begin_);
}

double Objective::value(const Trajectory& trajectory, const Eigen::VectorXd& gamma) const {
  double sum = 0.0;
  for (const auto& t : terms_) sum += t->value(trajectory, gamma);
  return sum;
}

void Objective::add_state_gradient(const Trajectory& trajectory, int k, Eigen::VectorXd& a,
                                   Eigen::VectorXd& da) const {
  for (const auto& t : terms_) t->add_state_gradient(trajectory, k, a, da);
}

void Objective::add_parameter_gradient(const Eigen::VectorXd& gamma, Eigen::VectorXd& dgamma) const {
  for (const auto& t : terms_) t->add_parameter_gradient(gamma, dgamma);
}

}  // namespace liedyn
