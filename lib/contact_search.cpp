#include "contact_search.hpp"

#include "so3.hpp"

namespace liedyn {

ContactSearch::ContactSearch(const Model& model)
    : bodies_(model), edges_(model), rods_on_bodies_(model), body_margin_(model.bodies.size(), 0.0) {}

void ContactSearch::find(const State& q, const Step& last_step, std::vector<bool>& touching) {
  if (bodies_.size() > 0 || rods_on_bodies_.size() > 0) {  // else no body can touch anything that moves
    for (std::size_t i = 0; i < body_margin_.size() && !last_step.points.empty(); ++i) {
      body_margin_[i] = last_step.points[i].norm() +
                        so3::log(last_step.rotations[i]).norm() * bodies_.reach(static_cast<int>(i));
    }
    bodies_.find(q, body_margin_, touching);
  }
  if (edges_.size() > 0) edges_.find(q, last_step, touching, bodies_.size());
  if (rods_on_bodies_.size() > 0) {
    rods_on_bodies_.find(q, last_step, body_margin_, touching, bodies_.size() + edges_.size());
  }
}

bool ContactSearch::add_penetrating(const State& q, std::vector<bool>& touching) const {
  const bool bodies = bodies_.add_penetrating(q, touching);
  const bool edges = edges_.add_penetrating(q, touching, bodies_.size());
  const bool rods_on_bodies = rods_on_bodies_.add_penetrating(q, touching, bodies_.size() + edges_.size());
  return bodies || edges || rods_on_bodies;
}

int ContactSearch::penetrating(const State& q) const {
  int count = 0;
  for (std::size_t p = 0; p < bodies_.size(); ++p) count += bodies_.penetrates(q, static_cast<int>(p));
  for (std::size_t p = 0; p < edges_.size(); ++p) count += edges_.penetrates(q, static_cast<int>(p));
  for (std::size_t p = 0; p < rods_on_bodies_.size(); ++p) count += rods_on_bodies_.penetrates(q, static_cast<int>(p));
  return count;
}

}  // namespace liedyn
