#include "free_directions.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

namespace liedyn {

namespace {

// Keeps the 3×3 diagonal blocks of the Hessian (rows = columns), indexed by offset / 3.
struct DiagonalBlockSink {
  std::vector<Matrix3>& blocks;
  void clear() {
    for (Matrix3& b : blocks) b.setZero();
  }
  template <class Block>
  void add(int row, int column, const Block& block) {
    if (row == column) blocks[row / 3] += block;
  }
};

// The scene's name of point `index` or rotation `index` of the state.
std::string object_name(const Model& model, int index, bool rotation) {
  const int bodies = static_cast<int>(model.bodies.size());
  if (index < bodies) return "bodies[" + std::to_string(index) + "]";
  for (int r = 0; r < static_cast<int>(model.rods.size()); ++r) {
    const int first = rotation ? model.rod_rotation(r, 0) : model.rod_point(r, 0);
    const int end = rotation ? model.rod_rotation(r + 1, 0) : model.rod_point(r + 1, 0);
    if (index >= first && index < end) {
      return "rods[" + std::to_string(r) + "]." + (rotation ? "edges[" : "nodes[") +
             std::to_string(index - first) + "]";
    }
  }
  return (rotation ? "rotation " : "point ") + std::to_string(index);
}

}  // namespace

std::string FreeDirection::describe() const {
  // Axes along a coordinate axis print as (0, 0, 1); others with 3 digits.
  const auto component = [](double v) {
    std::ostringstream os;
    os.precision(3);
    os << (std::abs(v) < 5e-4 ? 0.0 : v);
    return os.str();
  };
  return std::string("free ") + (rotation ? "rotation of " : "translation of ") + object +
         (rotation ? " about (" : " along (") + component(axis.x()) + ", " +
         component(axis.y()) + ", " + component(axis.z()) + "): no stiffness holds it";
}

std::vector<FreeDirection> free_directions(const Model& model, const Component& c,
                                           const State& q) {
  std::vector<Matrix3> blocks(c.dofs / 3, Matrix3::Zero());
  DiagonalBlockSink sink{blocks};
  Eigen::VectorXd g(c.dofs);
  c.potential.assemble_into(q, g, sink);
  double scale = 0.0;
  for (const Matrix3& b : blocks) scale = std::max(scale, b.diagonal().cwiseAbs().maxCoeff());
  std::vector<FreeDirection> out;
  if (!(scale > 0.0) || !std::isfinite(scale)) return out;  // nothing to compare with
  const auto test = [&](const DofBlock& block, bool rotation) {
    const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(blocks[block.offset / 3]);
    for (int k = 0; k < 3; ++k) {
      if (eigen.eigenvalues()(k) > kFreeCurvature * scale) break;  // ascending
      Vector3 axis = eigen.eigenvectors().col(k);
      // Sign: the largest component positive, so that the same axis always prints the same.
      Eigen::Index largest = 0;
      axis.cwiseAbs().maxCoeff(&largest);
      if (axis(largest) < 0.0) axis = -axis;
      out.push_back({object_name(model, block.index, rotation), rotation, axis});
    }
  };
  for (const DofBlock& b : c.points) test(b, false);
  for (const DofBlock& b : c.rotations) test(b, true);
  return out;
}

}  // namespace liedyn
