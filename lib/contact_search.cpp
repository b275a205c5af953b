#include "contact_search.hpp"

#include <algorithm>
#include <limits>

#include "so3.hpp"

namespace liedyn {

namespace {

std::uint64_t object_pair(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
}

}  // namespace

ContactSearch::ContactSearch(const Model& model)
    : bodies_(model),
      edges_(model),
      rods_on_bodies_(model),
      body_margin_(model.bodies.size(), 0.0),
      rod_moved_(model.rods.size(), 0.0) {
  // The objects that some candidate names, and for each body and rod edge its object (−1:
  // none): a scene without contact between objects has none, and its steps pay nothing here.
  const std::vector<std::pair<int, int>> body_pairs = model.body_pairs();
  const std::vector<EdgePair> edge_pairs = model.edge_pairs();
  const std::vector<std::pair<int, int>> rod_bodies = model.rod_body_pairs();
  std::vector<int> body_object(model.bodies.size(), -1), first_edge(model.rods.size(), -1);
  const auto add_body = [&](int b) {
    if (body_object[b] >= 0) return;
    body_object[b] = static_cast<int>(objects_.size());
    objects_.push_back({b, -1, -1, bodies_.reach(b)});
  };
  const auto add_rod = [&](int r) {
    if (first_edge[r] >= 0) return;
    first_edge[r] = static_cast<int>(objects_.size());
    for (int e = 0; e < model.rods[r].edge_count(); ++e) {
      objects_.push_back({model.rod_point(r, e), model.rod_point(r, e + 1), r, model.rods[r].contact.radius});
    }
  };
  for (int p = 0; p < static_cast<int>(body_pairs.size()); ++p) {
    const auto [a, b] = body_pairs[p];
    add_body(a);
    add_body(b);
    candidates_[object_pair(body_object[a], body_object[b])] = {Kind::kBodies, p};
  }
  for (int p = 0; p < static_cast<int>(edge_pairs.size()); ++p) {
    const EdgePair& e = edge_pairs[p];
    add_rod(e.rod_a);
    add_rod(e.rod_b);
    candidates_[object_pair(first_edge[e.rod_a] + e.edge_a, first_edge[e.rod_b] + e.edge_b)] = {Kind::kEdges, p};
  }
  for (int p = 0; p < static_cast<int>(rod_bodies.size()); ++p) {
    const auto [r, b] = rod_bodies[p];
    add_rod(r);
    add_body(b);
    for (int e = 0; e < model.rods[r].edge_count(); ++e) {
      candidates_[object_pair(first_edge[r] + e, body_object[b])] = {Kind::kRodOnBody, p};
    }
  }
  visited_.assign(rod_bodies.size(), 0);
  // The broad phase never reports more pairs than there are pairs of objects near each
  // other; reserving for every candidate keeps it from allocating in a step.
  overlapping_.reserve(candidates_.size());
  boxes_.resize(objects_.size());
}

void ContactSearch::broad_phase(const State& q, const Step* last_step) {
  const bool moved = last_step != nullptr && !last_step->points.empty();
  std::fill(rod_moved_.begin(), rod_moved_.end(), 0.0);
  for (const Object& o : objects_) {
    if (moved && o.rod >= 0) {
      rod_moved_[o.rod] = std::max({rod_moved_[o.rod], last_step->points[o.first_node].norm(),
                                    last_step->points[o.second_node].norm()});
    }
  }
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const Object& o = objects_[i];
    const Vector3& a = q.points[o.first_node];
    if (o.rod < 0) {  // a body: its bounding sphere (r = +∞: a box of ±∞ that meets every box)
      const double r = o.radius + (last_step != nullptr ? body_margin_[o.first_node] : 0.0);
      boxes_[i] = {a.array() - r, a.array() + r};
    } else {  // an edge: its capsule, grown by the farthest a node of its rod moved (the
              // (rod, body) test's margin, and more than the edge pairs' own)
      const Vector3& b = q.points[o.second_node];
      const double r = o.radius + rod_moved_[o.rod];
      boxes_[i] = {a.cwiseMin(b).array() - r, a.cwiseMax(b).array() + r};
    }
  }
  sweep_.overlapping(boxes_, overlapping_);
}

template <class Visit>
void ContactSearch::for_each_near(Visit&& visit) {
  std::fill(visited_.begin(), visited_.end(), 0);
  const std::size_t first_edge = bodies_.size(), first_rod_on_body = first_edge + edges_.size();
  for (const auto& [i, j] : overlapping_) {
    const auto found = candidates_.find(object_pair(i, j));
    if (found == candidates_.end()) continue;  // not a candidate (same body, neighbouring edges, filtered)
    const Candidate c = found->second;
    switch (c.kind) {
      case Kind::kBodies: visit(c, static_cast<std::size_t>(c.index)); break;
      case Kind::kEdges: visit(c, first_edge + c.index); break;
      case Kind::kRodOnBody:
        if (visited_[c.index]) break;
        visited_[c.index] = 1;
        visit(c, first_rod_on_body + c.index);
        break;
    }
  }
}

void ContactSearch::update_body_margins(const Step& last_step) {
  if (bodies_.size() == 0 && rods_on_bodies_.size() == 0) return;  // no body touches anything that moves
  for (std::size_t i = 0; i < body_margin_.size() && !last_step.points.empty(); ++i) {
    // A turn by θ moves a point at distance r from the centre by at most θ r. A body that
    // did not turn moves by its translation alone, even an unbounded one (whose θ · ∞ would
    // be 0 · ∞ = NaN, and a NaN margin fails every test); one that turned, by +∞.
    const double turn = so3::log(last_step.rotations[i]).norm();
    body_margin_[i] = last_step.points[i].norm() + (turn > 0.0 ? turn * bodies_.reach(static_cast<int>(i)) : 0.0);
  }
}

void ContactSearch::find_exhaustively(const State& q, const Step& last_step, std::vector<bool>& touching) {
  update_body_margins(last_step);
  bodies_.find(q, body_margin_, touching);
  edges_.find(q, last_step, touching, bodies_.size());
  rods_on_bodies_.find(q, last_step, body_margin_, touching, bodies_.size() + edges_.size());
}

void ContactSearch::find(const State& q, const Step& last_step, std::vector<bool>& touching) {
  update_body_margins(last_step);
  broad_phase(q, &last_step);
  std::fill(touching.begin(), touching.end(), false);
  for_each_near([&](Candidate c, std::size_t entry) {
    switch (c.kind) {
      case Kind::kBodies: touching[entry] = bodies_.touches(q, c.index, body_margin_); break;
      case Kind::kEdges: touching[entry] = edges_.touches(q, last_step, c.index); break;
      case Kind::kRodOnBody: touching[entry] = rods_on_bodies_.touches(q, last_step, body_margin_, c.index); break;
    }
  });
}

bool ContactSearch::add_penetrating(const State& q, std::vector<bool>& touching) {
  broad_phase(q, nullptr);
  bool added = false;
  for_each_near([&](Candidate c, std::size_t entry) {
    if (touching[entry]) return;
    bool overlaps = false;
    switch (c.kind) {
      case Kind::kBodies: overlaps = bodies_.penetrates(q, c.index); break;
      case Kind::kEdges: overlaps = edges_.penetrates(q, c.index); break;
      case Kind::kRodOnBody: overlaps = rods_on_bodies_.penetrates(q, c.index); break;
    }
    if (overlaps) touching[entry] = added = true;
  });
  return added;
}

int ContactSearch::penetrating(const State& q) {
  broad_phase(q, nullptr);
  int count = 0;
  for_each_near([&](Candidate c, std::size_t) {
    switch (c.kind) {
      case Kind::kBodies: count += bodies_.penetrates(q, c.index); break;
      case Kind::kEdges: count += edges_.penetrates(q, c.index); break;
      case Kind::kRodOnBody: count += rods_on_bodies_.penetrates(q, c.index); break;
    }
  });
  return count;
}

double ContactSearch::min_rod_separation(const State& q) {
  if (edges_.size() == 0) return std::numeric_limits<double>::infinity();
  // Capsules that overlap have overlapping boxes: if any candidate overlaps, the smallest
  // gap is among the broad phase's pairs. Otherwise every gap is positive and the pairs
  // apart must be measured too.
  broad_phase(q, nullptr);
  double smallest = std::numeric_limits<double>::infinity();
  for_each_near([&](Candidate c, std::size_t) {
    if (c.kind == Kind::kEdges) smallest = std::min(smallest, edges_.gap(q, c.index));
  });
  return smallest <= 0.0 ? smallest : edges_.min_separation(q);
}

}  // namespace liedyn
