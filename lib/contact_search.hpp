#pragma once
// Which pairs of objects are within reach of each other at the start of a step, all kinds
// together, in the layout of the contact part of a coupling key (Model::coupling_key): the
// body pairs (TouchingPairs, body_contact.hpp), then the rod edge pairs (TouchingEdges,
// edge_contact.hpp), then the (rod, body) pairs (TouchingRodsAndBodies). Each object's margin
// is how far it moved in the last step (a body: its translation plus its turn times its
// reach; a node: its translation). A kinematic body with an unbounded shape (a moving plane,
// an inside-out shape) has an infinite reach: its box is all of space, every candidate pair
// with it goes to the narrow phase, and after it turns its margin is +∞ too.
//
// Two phases. The broad phase (broad_phase.hpp) puts every object that some candidate pair
// names in an axis-aligned box — a body's bounding sphere, a rod edge's capsule — grown by
// its margin, and finds the boxes that overlap; only the candidate pairs among those go to
// the narrow phase, the Touching* classes' own test of the pair (samples against shapes,
// segment distances). A pair whose boxes do not overlap is farther apart than its margins,
// so the result is the one of testing every candidate (tests/test_broad_phase.cpp checks
// it), at a cost that grows with the objects and the pairs near each other rather than with
// all candidate pairs (a rod with self-contact has ~n²/2 of them). Allocation-free after the
// first queries.

#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "body_contact.hpp"
#include "broad_phase.hpp"
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
  // The same by testing every candidate pair, without the broad phase: the reference that
  // find is tested and measured against.
  void find_exhaustively(const State& q, const Step& last_step, std::vector<bool>& touching);
  // Marks the candidates that overlap at q but are not yet in `touching`; true if any.
  bool add_penetrating(const State& q, std::vector<bool>& touching);
  // How many candidate pairs overlap at q.
  int penetrating(const State& q);
  // The smallest distance between the surfaces of two candidate rod edges at q (< 0 where
  // they overlap), +∞ without rod–rod candidates.
  double min_rod_separation(const State& q);
  bool has_rod_pairs() const { return edges_.size() > 0; }

 private:
  enum class Kind : std::uint8_t { kBodies, kEdges, kRodOnBody };
  // A candidate pair as the broad phase sees it: its kind and index among its kind's pairs.
  struct Candidate {
    Kind kind;
    int index;
  };
  // body_margin_ from the last step (kept when it is empty: the first step's start).
  void update_body_margins(const Step& last_step);
  // The boxes of every object at q, each grown by its margin (none when `last_step` is
  // null), and the candidate pairs whose boxes overlap, in near_.
  void broad_phase(const State& q, const Step* last_step);
  // Calls visit(c, entry) once for each candidate c that the last broad phase kept, entry
  // being its index in a coupling key's contact part.
  template <class Visit>
  void for_each_near(Visit&& visit);

  TouchingPairs bodies_;
  TouchingEdges edges_;
  TouchingRodsAndBodies rods_on_bodies_;
  std::vector<double> body_margin_;

  // Broad-phase objects: bodies (State::points index) and rod edges (two State::points and
  // the contact radius), in one numbering.
  struct Object {
    int first_node = -1;   // a body's point, or an edge's first node
    int second_node = -1;  // an edge's second node; −1 for a body
    int rod = -1;          // an edge's rod
    double radius = 0.0;   // a body's reach, or an edge's contact radius
  };
  std::vector<Object> objects_;
  // The candidate behind an unordered pair of objects (smaller index in the high bits).
  std::unordered_map<std::uint64_t, Candidate> candidates_;
  SweepAndPrune sweep_;
  std::vector<Aabb> boxes_;
  std::vector<std::pair<int, int>> overlapping_;
  std::vector<char> visited_;        // per (rod, body) pair: many edge–body boxes lead to it
  std::vector<double> rod_moved_;    // per rod: the farthest a node moved in the last step
};

}  // namespace liedyn
