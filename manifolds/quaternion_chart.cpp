#include "quaternion_chart.hpp"

namespace liedyn {

QuaternionCoordinates::QuaternionCoordinates(const Component& component)
    : variable_(component.dofs / 3, -1),
      rotation_of_block_(component.dofs / 3, -1),
      q_(component.rotations.size(), quat::Vector4(0.0, 0.0, 0.0, 1.0)),
      E_(component.rotations.size(), Matrix34::Zero()) {
  for (const DofBlock& b : component.points) point_offsets_.push_back(b.offset);
  for (std::size_t i = 0; i < component.rotations.size(); ++i) {
    rotation_offsets_.push_back(component.rotations[i].offset);
    rotation_of_block_[component.rotations[i].offset / 3] = static_cast<int>(i);
  }
  // Coordinates in tangent order, a rotation's 4 where its 3 tangent DOFs are.
  for (std::size_t block = 0; block < variable_.size(); ++block) {
    variable_[block] = size_;
    size_ += rotation_of_block_[block] < 0 ? 3 : 4;
  }
}

void QuaternionCoordinates::get(const Component& component, const State& state, double* x) {
  Eigen::Map<Eigen::VectorXd> xv(x, size_);
  for (const DofBlock& b : component.points) xv.segment<3>(variable(b.offset)) = state.points[b.index];
  for (std::size_t i = 0; i < component.rotations.size(); ++i) {
    const DofBlock& b = component.rotations[i];
    xv.segment<4>(variable(b.offset)) = quat::from_rotation(state.rotations[b.index]);
  }
}

void QuaternionCoordinates::set(const Component& component, const double* x, State& state) {
  const Eigen::Map<const Eigen::VectorXd> xv(x, size_);
  for (const DofBlock& b : component.points) state.points[b.index] = xv.segment<3>(variable(b.offset));
  for (std::size_t i = 0; i < component.rotations.size(); ++i) {
    const DofBlock& b = component.rotations[i];
    q_[i] = xv.segment<4>(variable(b.offset));
    const double norm2 = q_[i].squaredNorm();
    state.rotations[b.index] = quat::rotation(q_[i]) / norm2;
    E_[i] = (4.0 / norm2) * quat::rate_matrix(q_[i]).transpose();
  }
}

}  // namespace liedyn
