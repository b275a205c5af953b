#pragma once
// A Cosserat rod as a user describes it, and its discretisation (paper §6.2, docs/design.md §6).
//
// Nodes carry positions x_i (i = 0…n−1), edges carry rotations R_j (edge j joins nodes j and
// j+1), with R_j e_z along the edge at rest. Masses are lumped: each edge's mass
// m_j = m l_j / Σl is split equally between its two nodes; each edge's rotation carries the
// rotational inertia of a solid cylinder of radius r and length l_j about its centre,
// I_b = diag(m_j(3r² + l_j²)/12, m_j(3r² + l_j²)/12, m_j r²/2) in the edge frame.
// Rest shape: `rest_nodes` if given, else the initial nodes. It gives the edge rest lengths
// l_j (and with them the lumped masses) and the rest Darboux vectors ω̄, from its frames.
// Frames, of the rest shape and of the initial shape alike: R_0 is the minimal rotation
// taking e_z to the first edge's direction, and R_j = rot(t_{j−1} → t_j) R_{j−1} (parallel
// transport: no twist between edges). A rest shape other than the initial one is how a
// naturally curved rod starts straightened (the helical perversion, paper Fig. 5).

#include <string>
#include <vector>

#include "contact.hpp"
#include "prescribed_motion.hpp"
#include "state.hpp"
#include "term.hpp"

namespace liedyn {

struct NodeForce {
  int node = -1;
  Vector3 force = Vector3::Zero();  // world, N
  ScheduledParameter<3> control;    // per-step forces and their slot in γ (lib/term.hpp)
};

// A pulling cable along a rod (paper §7.4, lib/cable.hpp): routed through one point per edge
// of `route`, p = x_j + R_j p̄ with x_j the edge's first node and p̄ in the edge's material
// frame (e.g. (ρ cos φ, ρ sin φ, 0): on the rod's surface at angle φ), with tension T ≥ 0.
struct CableRoutePoint {
  int edge = -1;
  Vector3 local = Vector3::Zero();
};
struct CableSpec {
  std::vector<CableRoutePoint> route;  // at least 2 points
  double tension = 0.0;                // N, ≥ 0
  ScheduledParameter<1> control;       // per-step tensions and their slot in γ (lib/term.hpp)
};

// A force on every free node that is inside a ball at the start of a step (lib/loads.hpp,
// RegionForce): how the endoscope of paper §7.2 is fed into its tube.
struct RegionPush {
  Vector3 force = Vector3::Zero();   // world, N per node
  Vector3 center = Vector3::Zero();  // world, m
  double radius = 0.0;               // m, > 0
};

struct RodSpec {
  std::string name;
  std::vector<Vector3> nodes;          // initial node positions, at least 2
  std::vector<Vector3> rest_nodes;     // rest shape, same count; empty: the initial nodes
  double mass = 0.0;                   // total, kg, > 0
  double radius = 0.0;                 // m, > 0 (edge rotational inertia)
  double stretch_stiffness = 0.0;      // k_s, N: Ψ_s = ½ k_s l (1 − ‖e‖/l)² per edge
  double shear_stiffness = 0.0;        // k_x, N: Ψ_x = ½ k_x l (1 − dᵀ R e_z) per edge
  Vector3 bending_stiffness = Vector3::Zero();  // K_b = diag(bend, bend, twist), N·m²
  // Internal damping (lib/rod_damping.hpp), dynamic mode: η_s [N·s] on the stretch rate,
  // η_x [N·s] on the shear rate, (η₁, η₂, η₃) [N·m²·s] on the bending and twist rates; 0: none.
  double stretch_damping = 0.0;
  double shear_damping = 0.0;
  Vector3 bending_damping = Vector3::Zero();
  std::vector<int> fixed_nodes;        // clamped positions
  std::vector<int> fixed_edges;        // clamped rotations
  std::vector<NodeForce> node_forces;  // constant world forces on nodes
  std::vector<RegionPush> region_pushes;  // forces on the nodes inside a region
  std::vector<CableSpec> cables;       // pulling cables
  std::vector<PrescribedMotion> prescribed_motions;  // of clamped nodes and edges
  // Initial node velocities, world, m/s, one per node; empty: at rest. A clamped node's must
  // be zero (it keeps its prescribed position). Edges start at rest.
  std::vector<Vector3> node_velocities;
  // Rest Darboux vectors ω̄ per interior node (1…n−2), material frame of the edge before it;
  // empty: from the rest shape's frames.
  std::vector<Vector3> rest_darboux;
  // Per interior node: per-step ω̄ and slots in γ (lib/term.hpp); empty: none.
  std::vector<ScheduledParameter<3>> rest_darboux_controls;
  // Contact of every free node, a sphere of contact.radius, with the model's colliders
  // (lib/contact.hpp); contact.stiffness = 0: none. With contact, its edges (capsules of
  // contact.radius) touch the edges of every other rod with contact (lib/edge_contact.hpp),
  // and with self_contact its own edges more than self_contact_skip apart along it; its edges
  // (by Gauss points) and free end nodes touch the shapes of bodies (lib/body_contact.hpp).
  ContactMaterial contact;
  bool self_contact = false;
  int self_contact_skip = 2;
  // Slots in an optimisation's parameter vector γ (−1: not a parameter); bending takes 3.
  int stretch_stiffness_slot = -1, shear_stiffness_slot = -1, bending_stiffness_slot = -1;

  const std::vector<Vector3>& rest_shape() const { return rest_nodes.empty() ? nodes : rest_nodes; }

  int node_count() const { return static_cast<int>(nodes.size()); }
  int edge_count() const { return node_count() - 1; }
};

// Everything derived from a RodSpec that the energy terms and the reports need.
struct RodDiscretization {
  std::vector<double> node_mass;           // lumped, kg
  std::vector<double> rest_length;         // per edge, m
  std::vector<Matrix3> edge_inertia;       // body-frame inertia tensor per edge
  std::vector<Matrix3> frames;             // initial edge rotations (parallel transport)
  // Per interior node i = 1…n−2, the length of rod its bend–twist hinge stands for: the
  // Voronoi length ½(l_{i−1} + l_i), and at the node next to a clamped end also the clamped
  // edge's other half (see discretize).
  std::vector<double> bending_length;
  std::vector<Vector3> rest_darboux;       // per interior node, from the rest frames
};

// Minimal rotation taking unit vector a to unit vector b (a half turn about an axis
// perpendicular to a when b = −a).
Matrix3 minimal_rotation(const Vector3& a, const Vector3& b);

// Edge frames of a polyline by parallel transport, starting from the minimal rotation of
// e_z onto the first edge.
std::vector<Matrix3> parallel_transport_frames(const std::vector<Vector3>& nodes);

// What the model's joints do at a rod's ends (Model::discretize_rod finds it): a weld to the
// world for the whole run holds the end edge's frame as a clamp does; a splice continues the
// rod into another. Welds to bodies (kinematic or not) and welds that hold for some steps only
// keep the Voronoi cell: not built yet (docs/design.md §6.5).
struct RodEnds {
  bool first_welded = false, last_welded = false;    // edge 0 / edge n − 2 welded to the world
  bool first_spliced = false, last_spliced = false;  // node 0 / node n − 1 spliced
};

// Lumped masses, rest lengths, edge inertias, parallel-transported frames and rest Darboux
// vectors of a validated rod. The bending lengths and rest Darboux vectors depend on `ends`:
// take them from Model::discretize_rod.
//
// A clamped end: the rod's end edge clamped (fixed_edges) or welded to the world, and not
// spliced. With
// hinges at the interior nodes over their Voronoi lengths, the clamped edge's outer half
// belongs to no hinge and stays straight: the rod would be held half an edge inside its end,
// where the bending moment is largest, a first-order error in l (a cantilever of 40 edges at
// F L²/EI = 2 misses the elastica's tip by 1.3 % of L). The hinge next to a clamped end takes
// that half too, over l_end + ½ l_next, which holds the rod at its end node and makes the
// error second order. The hinge's rest angle stays the rest shape's, so the rest shape is
// still unstressed; free and spliced ends and interior nodes keep their Voronoi lengths
// (docs/design.md §6.5).
RodDiscretization discretize(const RodSpec& rod, RodEnds ends = {});

}  // namespace liedyn
