#pragma once
// Which pairs of objects are within reach of each other at the start of a step, all kinds
// together, in the layout of the contact part of a coupling key (Model::coupling_key): the
// body pairs (TouchingPairs, body_contact.hpp), then the rod edge pairs (TouchingEdges,
// edge_contact.hpp), then the (rod, body) pairs (TouchingRodsAndBodies). Each object's margin
// is how far it moved in the last step (a body: its translation plus its turn times its
// reach; a node: its translation). Allocation-free after construction.

#include <vector>

#include "body_contact.hpp"
#include "edge_contact.hpp"
#include "model.hpp"
#include "state.hpp"

namespace liedyn {

class ContactSearch {
 public:
  ContactSearch() = default;
  explicit ContactSearch(const Model& model);

  std::size_t size() const { return bodies_.size() + edges_.size() + rods_on_bodies_.size(); }
  // touching[p] for every candidate pair at q (`touching` has size() entries), the margins
  // from the last step (zero motion: margins 0).
  void find(const State& q, const Step& last_step, std::vector<bool>& touching);
  // Marks the candidates that overlap at q but are not yet in `touching`; true if any.
  bool add_penetrating(const State& q, std::vector<bool>& touching) const;
  // How many candidate pairs overlap at q.
  int penetrating(const State& q) const;
  // The smallest distance between the surfaces of two candidate rod edges at q (< 0 where
  // they overlap), +∞ without rod–rod candidates.
  double min_rod_separation(const State& q) const { return edges_.min_separation(q); }
  bool has_rod_pairs() const { return edges_.size() > 0; }

 private:
  TouchingPairs bodies_;
  TouchingEdges edges_;
  TouchingRodsAndBodies rods_on_bodies_;
  std::vector<double> body_margin_;
};

}  // namespace liedyn
