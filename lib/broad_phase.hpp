#pragma once
// Broad phase of contact detection: which pairs of objects' axis-aligned boxes overlap, by
// sweep and prune along one axis.
//
// Each object (a body's bounding sphere, a rod edge's capsule, grown by how far it may move)
// is an axis-aligned box [lo, hi]. Two boxes overlap when their intervals overlap on all
// three axes. Sweep and prune sorts the boxes by lo along one axis a; then for each box i, in
// that order, the boxes j that follow it with lo_j[a] ≤ hi_i[a] are exactly those whose
// interval on a overlaps i's and that start after it, and each is tested on the other two
// axes. Every overlapping pair is found once (by the one of the two that starts first), in
// O(n + m_a) after sorting, m_a being the pairs that overlap along a.
//
// Why our own rather than a library's dynamic AABB tree (FCL's broad-phase managers, as used
// by DisMech and MoveIt): our objects are few (tens of bodies, hundreds of rod edges), all
// move every step, and their order along an axis barely changes from one step to the next.
// The order of the last query is kept, so the sort is an insertion sort over an almost sorted
// list, O(n) in practice, and the whole query allocates nothing once `pairs` has grown to its
// capacity (a tree would be refitted or rebuilt each step). Measured against the brute-force
// test of every candidate pair in docs/design.md §7.7.
//
// The axis: the one along which the boxes' centres spread the most (fewest overlaps along
// it), chosen at each query; a change of axis re-sorts from scratch (std::sort, in place).
//
// A box may be unbounded, lo = −∞ and hi = +∞ (the reach of a moving plane or inside-out
// shape, contact_search.hpp): it sorts first, overlaps every other box on every axis (no
// ∞ − ∞ arises in the tests, which only compare), and is left out of the choice of axis.

#include <utility>
#include <vector>

#include "state.hpp"

namespace liedyn {

struct Aabb {
  Vector3 lo = Vector3::Zero();
  Vector3 hi = Vector3::Zero();
};

class SweepAndPrune {
 public:
  // The pairs (i, j), i < j, of boxes that overlap (closed intervals: touching counts),
  // written into `pairs` (cleared first), in no particular order. Allocation-free while
  // `pairs` has the capacity, and after the first call with as many boxes.
  void overlapping(const std::vector<Aabb>& boxes, std::vector<std::pair<int, int>>& pairs);

 private:
  std::vector<int> order_;  // box indices sorted by lo along axis_
  int axis_ = -1;
};

}  // namespace liedyn
