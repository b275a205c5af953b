#include "incremental_potential.hpp"

#include <numeric>

namespace liedyn {

void IncrementalPotential::begin_step(const State& previous, const Step& previous_step) {
  for (auto& t : translational_inertia) t.begin_step(previous, previous_step);
  for (auto& t : rotational_inertia) t.begin_step(previous, previous_step);
  for (auto& t : torques) t.begin_step(previous, previous_step);
}

double IncrementalPotential::value(const State& q) const {
  double value = 0.0;
  for_each_term_vector([&](const auto& terms) {
    for (const auto& term : terms) value += term.evaluate(q, nullptr, nullptr);
  });
  return value;
}

double IncrementalPotential::potential_energy(const State& q) const {
  double energy = 0.0;
  for (const auto& t : gravity) energy += t.evaluate(q, nullptr, nullptr);
  for (const auto& t : forces) energy += t.evaluate(q, nullptr, nullptr);
  for (const auto& t : springs) energy += t.evaluate(q, nullptr, nullptr);
  return energy;
}

namespace {

// Union–find over bodies, joined by springs between two bodies.
int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::vector<Component> build_components(const Model& model) {
  const int n = static_cast<int>(model.bodies.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (const SpringSpec& s : model.springs) {
    if (s.a.body >= 0 && s.b.body >= 0) {
      parent[find_root(parent, s.a.body)] = find_root(parent, s.b.body);
    }
  }

  std::vector<Component> components;
  std::vector<int> component_of(n, -1);
  std::vector<int> point_offset(n, -1), rotation_offset(n, -1);
  std::vector<int> component_of_root(n, -1);
  for (int i = 0; i < n; ++i) {
    const int root = find_root(parent, i);
    if (component_of_root[root] < 0) {
      component_of_root[root] = static_cast<int>(components.size());
      components.emplace_back();
    }
    Component& c = components[component_of_root[root]];
    component_of[i] = component_of_root[root];
    point_offset[i] = c.dofs;
    rotation_offset[i] = c.dofs + 3;
    c.points.push_back({i, point_offset[i]});
    c.rotations.push_back({i, rotation_offset[i]});
    c.dofs += 6;
  }

  const double inv_h2 = 1.0 / (model.time_step * model.time_step);
  for (int i = 0; i < n; ++i) {
    const RigidBody& body = model.bodies[i];
    IncrementalPotential& p = components[component_of[i]].potential;
    TranslationalInertia ti;
    ti.offsets = {point_offset[i]};
    ti.point = i;
    ti.mass_over_h2 = body.mass * inv_h2;
    p.translational_inertia.push_back(ti);
    RotationalInertia ri;
    ri.offsets = {rotation_offset[i]};
    ri.rotation = i;
    ri.J_over_h2 = rotational_mass(body.inertia) * inv_h2;
    p.rotational_inertia.push_back(ri);
    if (!model.gravity.isZero(0.0)) {
      Gravity g;
      g.offsets = {point_offset[i]};
      g.point = i;
      g.weight = body.mass * model.gravity;
      p.gravity.push_back(g);
    }
  }

  auto attach = [](const BodyPoint& bp) {
    AttachedPoint ap;
    ap.point = bp.body;
    ap.rotation = bp.body;
    ap.local = bp.point;
    return ap;
  };
  auto offsets_of = [&](const BodyPoint& bp) -> std::array<int, 2> {
    if (bp.body < 0) return {-1, -1};
    return {point_offset[bp.body], rotation_offset[bp.body]};
  };

  for (const ForceSpec& f : model.forces) {
    ConstantForce term;
    term.offsets = offsets_of(f.at);
    term.at = attach(f.at);
    term.force = f.force;
    components[component_of[f.at.body]].potential.forces.push_back(term);
  }
  for (const TorqueSpec& t : model.torques) {
    ConstantTorque term;
    term.offsets = {rotation_offset[t.body]};
    term.rotation = t.body;
    term.torque = t.torque;
    components[component_of[t.body]].potential.torques.push_back(term);
  }
  for (const SpringSpec& s : model.springs) {
    Spring term;
    const auto oa = offsets_of(s.a), ob = offsets_of(s.b);
    term.offsets = {oa[0], oa[1], ob[0], ob[1]};
    term.a = attach(s.a);
    term.b = attach(s.b);
    term.stiffness = s.stiffness;
    term.rest_length = s.rest_length;
    const int body = s.a.body >= 0 ? s.a.body : s.b.body;
    components[component_of[body]].potential.springs.push_back(term);
  }
  return components;
}

}  // namespace liedyn
