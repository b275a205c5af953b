#include "broad_phase.hpp"

#include <algorithm>

namespace liedyn {

void SweepAndPrune::overlapping(const std::vector<Aabb>& boxes, std::vector<std::pair<int, int>>& pairs) {
  pairs.clear();
  const int n = static_cast<int>(boxes.size());
  if (n < 2) return;
  // The axis of the widest spread of the centres (their variance, up to the factor 1/m) of
  // the m bounded boxes. An unbounded box (±∞) has no centre (−∞ + ∞ = NaN) and overlaps
  // every box along any axis: it does not bear on the choice.
  Vector3 sum = Vector3::Zero(), squares = Vector3::Zero();
  int bounded = 0;
  for (const Aabb& b : boxes) {
    if (!b.lo.allFinite() || !b.hi.allFinite()) continue;
    const Vector3 c = 0.5 * (b.lo + b.hi);
    sum += c;
    squares += c.cwiseProduct(c);
    ++bounded;
  }
  int axis = 0;
  if (bounded > 0) (squares - sum.cwiseProduct(sum) / bounded).maxCoeff(&axis);
  const auto starts_before = [&](int i, int j) { return boxes[i].lo[axis] < boxes[j].lo[axis]; };
  if (static_cast<int>(order_.size()) != n || axis != axis_) {
    order_.resize(n);
    for (int i = 0; i < n; ++i) order_[i] = i;
    std::sort(order_.begin(), order_.end(), starts_before);
    axis_ = axis;
  } else {
    // Insertion sort: the boxes moved a little since the last query, so the list is almost
    // sorted and this is about one pass.
    for (int k = 1; k < n; ++k) {
      const int i = order_[k];
      int m = k;
      for (; m > 0 && starts_before(i, order_[m - 1]); --m) order_[m] = order_[m - 1];
      order_[m] = i;
    }
  }
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  for (int k = 0; k < n; ++k) {
    const Aabb& first = boxes[order_[k]];
    for (int m = k + 1; m < n && boxes[order_[m]].lo[axis] <= first.hi[axis]; ++m) {
      const Aabb& other = boxes[order_[m]];
      if (other.lo[b] > first.hi[b] || first.lo[b] > other.hi[b]) continue;
      if (other.lo[c] > first.hi[c] || first.lo[c] > other.hi[c]) continue;
      pairs.emplace_back(std::min(order_[k], order_[m]), std::max(order_[k], order_[m]));
    }
  }
}

}  // namespace liedyn
