#pragma once
// Triangle meshes that tests build in code (lib/mesh_sdf.hpp's TriangleMesh).

#include <array>

#include "lib/mesh_sdf.hpp"

namespace liedyn::test {

// The box |x_i| ≤ h_i, two triangles per face, counter-clockwise seen from outside.
inline TriangleMesh box_mesh(const Vector3& h) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1 ? 1 : -1) * h.x(), (i & 2 ? 1 : -1) * h.y(), (i & 4 ? 1 : -1) * h.z());
  }
  for (const auto& q : {std::array<int, 4>{0, 2, 3, 1},
                        {4, 5, 7, 6},
                        {0, 1, 5, 4},
                        {2, 6, 7, 3},
                        {0, 4, 6, 2},
                        {1, 3, 7, 5}}) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

}  // namespace liedyn::test
