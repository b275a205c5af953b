#pragma once
// A signed distance field φ sampled on a regular grid from a closed triangle mesh, for penalty
// contact against arbitrary shapes (the analytic shapes are in lib/sdf.hpp, whose sign and
// SdfValue conventions this follows: φ > 0 outside the solid, < 0 inside).
//
// Grid. Nodes x_ijk = o + h (i, j, k), 0 ≤ i < n_x etc. (h = cell_size, o = origin()), over
// the bounding box of the triangles' vertices grown by `padding` on every side. Each axis gets
// m = max(1, ⌈(extent + 2 padding)/h − 1e-9⌉) cells (n = m + 1 nodes; the 1e-9 keeps
// 1.5/0.1 = 15.000000000000002 at 15 cells), and the grid is centred on the padded box, which
// it covers (to 1e-9 cells). The number of cells m_x m_y m_z is limited by `max_cells`.
//
// Node values: the exact signed distance from x_ijk to the mesh,
//   φ_ijk = s · min_t ‖x_ijk − c_t‖,   c_t = closest point of triangle t (Ericson, Real-Time
//                                       Collision Detection §5.1.5, with its Voronoi region),
//   s = sign((x_ijk − c) · n_f),       n_f = angle-weighted pseudonormal of the feature f
//                                       (face, edge or vertex) that holds the closest point c
//                                       (Bærentzen & Aanæs 2005, IEEE TVCG 11(3), Theorem 1):
//     face:   its unit normal n_t;  edge: n_t + n_t' (the two faces sharing it);
//     vertex: Σ_t α_t n_t over the incident faces, α_t = the face's angle at the vertex.
// The theorem makes the sign exact wherever the closest point is unique, including at edges
// and vertices (where the sign of a single face's normal fails); at ties (medial surfaces,
// where several closest points are equally near) every candidate gives the correct sign, and
// the lowest triangle index is kept. s = +1 when (x − c)·n_f = 0 (φ = 0 there anyway).
// The solid is the side the normals point away from; normals must be consistently oriented
// (checked on every edge). If the mesh's signed volume ⅙ Σ_t a·(b × c) is negative (normals
// pointing inward overall) all normals are flipped: the solid is always the bounded side. A
// component oriented opposite to its enclosing surface is a cavity (a hollow solid), as in the
// theorem. Not checked: self-intersections and non-manifold vertices (two fans touching at a
// vertex), where the sign may be wrong.
//
// Build cost: a recursive culling over blocks of nodes keeps the exact minimum without a BVH.
// For a block with node bounding-box centre c and half-diagonal δ, every node x of the block
// has |‖x − c_t(x)‖ − ‖c − c_t(c)‖| ≤ δ (distance to a set is 1-Lipschitz), so the nearest
// triangle of any node satisfies d_t(c) ≤ min_t' d_t'(c) + 2δ: only those triangles are
// passed to the block's 8 sub-blocks, down to blocks of ≤ 2×2×2 nodes, which take the
// minimum over what is left. Cost ~ nodes × (triangles within ~2 cells of the nearest
// distance); a sphere, where all triangles are equally far from the centre, is the worst case
// for its size. Measured (-O3, one core, 64³ nodes): a 12-triangle cube 0.01 s, a
// 5120-triangle icosphere 0.35 s, 20480 triangles 1 s. Memory: one double per node.
// Work budget. The cost is counted in point-triangle distances (11–20 ns each, measured) and
// capped by `max_build_work` as max_cells caps the memory: a 327680-triangle icosphere of
// radius 0.1 m at 0.8 mm cells (254³ cells) would take minutes (at 67³ nodes already 20 s).
// Refusing, rather than a faster build: the leaves compare every triangle within a cell's
// width of the nearest distance, a large share of all inside a finely meshed curved surface
// (≈ T h/(2ρ) at depth ρ in a sphere); a bounding-volume hierarchy would narrow that to
// within a triangle's width, no narrower for such meshes (there: triangles ~0.9 mm, cells
// 0.8 mm), and exactness rules out propagating distances from neighbours instead.
// Where 3 N T (N nodes, T triangles: the most a build can evaluate) exceeds the budget, the
// work is first estimated without bias by following the culling from the root to the leaf of
// 16–256 sample nodes (a shifted R3 sequence, fixed: the same grid always gets the same
// estimate; ~2–4 T distances each, at most about a tenth of the budget in all; measured
// within 8% of the work done on icospheres of 1280–327680 triangles, 19³–205³ nodes), and
// the grid is refused (GridSdfTooCostly) if the estimate exceeds max_build_work. A build that
// passes twice the budget anyway (an estimate that missed a few costly nodes) is stopped and
// refused then: no build evaluates more than 2 max_build_work distances. The 327680-triangle
// case above is refused in ~1.6 s (38 sample nodes).
//
// Interpolation. In the cell (i, j, k) holding p, with t = (p − x_ijk)/h ∈ [0, 1]³ and the
// corner values v_abc = φ_{i+a, j+b, k+c}, the trilinear interpolant and ITS derivatives are
//   φ(p)     = Σ_abc v_abc w_a(t_x) w_b(t_y) w_c(t_z),      w_0(s) = 1 − s, w_1(s) = s,
//   ∂φ/∂p_x  = (1/h)  Σ_bc (v_1bc − v_0bc) w_b(t_y) w_c(t_z)            (y, z alike),
//   ∂²φ/∂p_x∂p_y = (1/h²) Σ_c (v_11c − v_10c − v_01c + v_00c) w_c(t_z)    (xz, yz alike),
//   ∂²φ/∂p_x² = 0                                                        (linear per axis).
// These are derivatives of the interpolant, not of the true distance: |∇φ| ≠ 1 in general,
// and ∇²φ has a zero diagonal. The interpolant is C⁰ across cell faces, where ∇φ and ∇²φ
// jump; on a face they are those of the LOWER cell (p_x = x_i + h belongs to cell i, not
// i + 1; "on" to 8 ulps of (p_x − o_x)/h, so that node_position() is on its faces); the first
// cell also owns the grid's lower boundary.
// Accuracy against the mesh's true SDF: exact at nodes; exact where the SDF is affine over a
// cell (near a flat face, inside and outside); |error| ≤ (h²/8) Σ_i max_cell |∂²φ/∂x_i²|
// where the SDF is C¹ with bounded curvature over the cell (≤ 3h²/(8r) at distance r from a
// curvature centre, e.g. r from a convex edge or vertex); at kinks of the SDF (medial
// surfaces inside, convex edges and vertices on the surface) the Lipschitz bound
// Σ_abc w_abc ‖x_abc − p‖ ≤ √3 h (w_abc = the trilinear weights). Where the SDF is convex (a
// convex solid) the interpolant is never below it (Jensen).
//
// Outside the grid box B = [o, o + h (n − 1)] the field is continued by the distance to the
// box, with q = clamp(p, B) (the nearest point of B), w = p − q, d = ‖w‖, u = w/d, the
// clamped axes A = {i : w_i ≠ 0} and the free axes F (P_A, P_F = the diagonal projections):
//   φ(p)   = φ(q) + d,
//   ∇φ(p)  = P_F ∇φ(q) + u,
//   ∇²φ(p) = P_F ∇²φ(q) P_F + (P_A − u uᵀ)/d,
// with φ(q), ∇φ(q), ∇²φ(q) the interpolant's on the box face, edge or corner. This is
// continuous at the box (d → 0), positive and growing at unit rate far away, and an upper
// bound of the mesh's true distance where φ(q) is (triangle inequality). As for the rounded
// box of lib/sdf.hpp, (P_A − u uᵀ)/d = 0 beside a box face and grows as 1/d near an edge or
// corner of B. d ≤ kCoreDistance (1e-150) counts as inside. For finite p (‖p‖ up to ~1e300)
// everything is finite; a non-finite coordinate gives φ = NaN and ∇φ = NaN (never undefined
// behaviour).

#include <array>
#include <stdexcept>
#include <vector>

#include "sdf.hpp"
#include "state.hpp"

namespace liedyn {

// A triangle soup with shared vertices; triangles list vertex indices, counter-clockwise seen
// from outside (the normal (b − a) × (c − a) points out of the solid).
struct TriangleMesh {
  std::vector<Vector3> vertices;
  std::vector<std::array<int, 3>> triangles;
};

// The grid is too costly to build: more cells than max_cells, more than 2³¹ − 2 nodes along an
// axis, or more work than max_build_work (header, "Work budget"). The remedy is a larger
// cell_size (or a smaller mesh); what() says so, with the numbers.
class GridSdfTooCostly : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Default work budget of GridSdf, in point-triangle distances: ~7 s on one core at ~15 ns each.
inline constexpr double kDefaultMaxBuildWork = 5e8;

class GridSdf {
 public:
  // Samples the mesh's exact signed distance at the nodes of a grid of cell size `cell_size`
  // (m, finite, > 0) over the mesh's bounding box grown by `padding` (m, finite, ≥ 0) on every
  // side (header). Throws std::invalid_argument, naming the offending value, vertex, triangle
  // or edge, for: cell_size ≤ 0 or not finite; padding < 0 or not finite; max_cells < 1; no
  // vertices or no triangles; a non-finite vertex; a vertex index outside [0, vertices); a
  // degenerate triangle (a repeated index, or zero area: ‖(b − a) × (c − a)‖ ≤ 1e-12 ×
  // (longest edge)²); a mesh that is not closed (every edge must be shared by exactly two
  // triangles); inconsistent orientation (two triangles running along their shared edge in
  // the same direction); a mesh enclosing no volume (|signed volume| ≤ 1e-12 × (largest
  // extent)³); max_build_work < 1 or NaN. Throws GridSdfTooCostly (an invalid_argument) for
  // more than max_cells cells (or more than 2³¹ − 2 nodes along an axis), or an estimated or
  // counted build work beyond max_build_work (header, "Work budget"; ∞: no cap).
  GridSdf(const TriangleMesh& mesh, double cell_size, double padding, long max_cells = 20000000,
          double max_build_work = kDefaultMaxBuildWork);

  // φ(p), ∇φ(p) and, if with_hessian, ∇²φ(p) (otherwise `hessian` stays zero) of the
  // trilinear interpolant inside the grid box, or of its continuation outside (header), in
  // mesh coordinates. Allocation-free, O(1).
  SdfValue evaluate(const Vector3& p, bool with_hessian = true) const;

  // The grid node (0, 0, 0), m.
  const Vector3& origin() const { return origin_; }
  // The node with the largest indices, origin() + cell_size() (dimensions() − 1), m.
  const Vector3& max_corner() const { return max_corner_; }
  double cell_size() const { return h_; }
  // Point-triangle distances the build evaluated, and the estimate made before it (0 when
  // 3 N T was within the budget and no estimate was needed).
  double build_work() const { return build_work_; }
  double estimated_build_work() const { return estimated_work_; }
  // Number of NODES along x, y, z (each ≥ 2; cells = nodes − 1).
  const Eigen::Vector3i& dimensions() const { return dims_; }
  // Position and sampled signed distance of node (i, j, k); throws std::out_of_range for an
  // index outside [0, dimensions()).
  Vector3 node_position(int i, int j, int k) const;
  double node_value(int i, int j, int k) const;

 private:
  // Interpolant and derivatives at a point q of the grid box (header, "Interpolation").
  void interpolate(const Vector3& q, bool with_hessian, SdfValue& out) const;
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims_.x()) *
               (static_cast<std::size_t>(j) +
                static_cast<std::size_t>(dims_.y()) * static_cast<std::size_t>(k));
  }

  Vector3 origin_ = Vector3::Zero();
  Vector3 max_corner_ = Vector3::Zero();
  double h_ = 1.0;
  Eigen::Vector3i dims_ = Eigen::Vector3i::Constant(2);
  std::vector<double> values_;  // φ_ijk at index(i, j, k), x fastest
  double build_work_ = 0.0;
  double estimated_work_ = 0.0;
};

}  // namespace liedyn
