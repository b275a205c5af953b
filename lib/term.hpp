#pragma once
// What an energy term is, for the assembler (IPC-Toolkit style: each term owns its value,
// Lie gradient and Lie Hessian in one place; "Lie" as defined in so3.hpp).
//
// A term type T provides
//   static constexpr int kBlocks;             // 3-DOF blocks in its stencil (points, rotations)
//   std::array<int, kBlocks> offsets;         // tangent offset of each block, −1 if not a DOF
//   double evaluate(const State& q, LocalGradient<kBlocks>* g, LocalHessian<kBlocks>* H) const;
// evaluate returns the value and, when the pointers are non-null, writes (not adds) the
// local Lie gradient and Lie Hessian. Blocks whose offset is −1 are ignored by assembly.
// Terms are stored per type in contiguous vectors: no virtual call per element.

#include <Eigen/Core>
#include <array>

namespace liedyn {

template <int B>
using LocalGradient = Eigen::Matrix<double, 3 * B, 1>;
template <int B>
using LocalHessian = Eigen::Matrix<double, 3 * B, 3 * B>;

}  // namespace liedyn
