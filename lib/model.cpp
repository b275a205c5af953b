#include "model.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <sstream>

#include "so3.hpp"

namespace liedyn {
namespace {

std::string index_field(const std::string& array, std::size_t i, const std::string& member) {
  return array + "[" + std::to_string(i) + "]" + (member.empty() ? "" : "." + member);
}

void require_finite(const Eigen::MatrixXd& m, const std::string& field) {
  if (!m.allFinite()) throw ModelError(field, "must be finite (found NaN or Inf)");
}

void require_body(int body, std::size_t count, const std::string& field, bool allow_world) {
  if (body == -1 && allow_world) return;
  if (body < 0 || static_cast<std::size_t>(body) >= count) {
    throw ModelError(field, "refers to body " + std::to_string(body) + ", but there are " +
                                std::to_string(count) + " bodies");
  }
}

void validate_inertia(const Matrix3& I, const std::string& field) {
  require_finite(I, field);
  if (!I.isApprox(I.transpose(), 1e-12)) throw ModelError(field, "must be symmetric");
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Matrix3>(I).eigenvalues();
  if (moments.minCoeff() <= 0.0) {
    std::ostringstream os;
    os << "must be positive definite (principal moments " << moments.transpose() << ")";
    throw ModelError(field, os.str());
  }
  // Triangle inequality: the largest moment may not exceed the sum of the other two,
  // otherwise J = ½ tr(I) 1 − I is not PSD and no mass distribution has this inertia.
  if (moments(2) > moments(0) + moments(1) + kInertiaTolerance * moments.sum()) {
    std::ostringstream os;
    os << "violates the triangle inequality: principal moments " << moments.transpose()
       << " have " << moments(2) << " > " << moments(0) << " + " << moments(1);
    throw ModelError(field, os.str());
  }
}

}  // namespace

ModelError::ModelError(std::string field, const std::string& reason)
    : std::invalid_argument(field + ": " + reason), field_(std::move(field)) {}

void Model::validate() const {
  if (!std::isfinite(time_step) || time_step <= 0.0) {
    throw ModelError("time_step", "must be a finite positive number of seconds");
  }
  require_finite(gravity, "gravity");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const RigidBody& b = bodies[i];
    if (!std::isfinite(b.mass) || b.mass <= 0.0) {
      throw ModelError(index_field("bodies", i, "mass"), "must be a finite positive number");
    }
    validate_inertia(b.inertia, index_field("bodies", i, "inertia"));
    require_finite(b.position, index_field("bodies", i, "position"));
    require_finite(b.orientation, index_field("bodies", i, "orientation"));
    const double drift = (b.orientation.transpose() * b.orientation - Matrix3::Identity()).norm();
    if (drift > 1e-9 || b.orientation.determinant() <= 0.0) {
      throw ModelError(index_field("bodies", i, "orientation"), "must be a rotation matrix");
    }
    require_finite(b.linear_velocity, index_field("bodies", i, "linear_velocity"));
    require_finite(b.angular_velocity, index_field("bodies", i, "angular_velocity"));
    // ΔR_0 = exp(h ω_0) and the reported ω = log(ΔR)/h only represent |ω| h < π: a faster
    // spin would silently alias to a slower one (or the opposite sense).
    if (b.angular_velocity.norm() * time_step >= std::numbers::pi) {
      std::ostringstream os;
      os << "|angular_velocity| · time_step = " << b.angular_velocity.norm() * time_step
         << " rad per step must be below π (reduce time_step)";
      throw ModelError(index_field("bodies", i, "angular_velocity"), os.str());
    }
  }
  for (std::size_t i = 0; i < springs.size(); ++i) {
    const SpringSpec& s = springs[i];
    require_body(s.a.body, bodies.size(), index_field("springs", i, "body_a"), true);
    require_body(s.b.body, bodies.size(), index_field("springs", i, "body_b"), true);
    if (s.a.body == s.b.body) {
      throw ModelError(index_field("springs", i, "body_b"),
                       s.a.body == -1 ? "connects two world anchors"
                                      : "connects a body to itself (the spring would do nothing)");
    }
    require_finite(s.a.point, index_field("springs", i, "point_a"));
    require_finite(s.b.point, index_field("springs", i, "point_b"));
    if (!std::isfinite(s.stiffness) || s.stiffness < 0.0) {
      throw ModelError(index_field("springs", i, "stiffness"), "must be finite and ≥ 0");
    }
    if (!std::isfinite(s.rest_length) || s.rest_length < 0.0) {
      throw ModelError(index_field("springs", i, "rest_length"), "must be finite and ≥ 0");
    }
  }
  for (std::size_t i = 0; i < forces.size(); ++i) {
    require_body(forces[i].at.body, bodies.size(), index_field("forces", i, "body"), false);
    require_finite(forces[i].at.point, index_field("forces", i, "point"));
    require_finite(forces[i].force, index_field("forces", i, "force"));
  }
  for (std::size_t i = 0; i < torques.size(); ++i) {
    require_body(torques[i].body, bodies.size(), index_field("torques", i, "body"), false);
    require_finite(torques[i].torque, index_field("torques", i, "torque"));
  }
}

State Model::initial_state() const {
  State q;
  for (const RigidBody& b : bodies) {
    q.points.push_back(b.position);
    q.rotations.push_back(so3::orthonormalize(b.orientation));
  }
  return q;
}

Step Model::initial_step() const {
  Step dq;
  for (const RigidBody& b : bodies) {
    dq.points.push_back(time_step * b.linear_velocity);
    dq.rotations.push_back(so3::exp(time_step * b.angular_velocity));
  }
  return dq;
}

}  // namespace liedyn
