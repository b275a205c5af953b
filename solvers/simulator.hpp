#pragma once
// Forward simulation of a Model by backward Euler: each step minimises the incremental
// potential of every independent component with the chosen back-end (step_solver.hpp) (paper §4);
// in static mode each step is a load step without inertia (Model::static_equilibrium).
// Clamped rod nodes and edges with a prescribed motion, and kinematic bodies, are moved before
// each step.
//
//   q_k = argmin Ψ(q; q_{k−1}, Δq_{k−1}),  starting from the extrapolation
//   x = x_{k−1} + Δx_{k−1},  R = ΔR_{k−1} R_{k−1};  then Δx_k = x_k − x_{k−1}, ΔR_k = R_k R_{k−1}ᵀ.
//
// Reported quantities (docs/design.md §2.2): v_k = Δx_k/h, ω_k = log(ΔR_k)/h (world frame);
// kinetic energy Σ ½ m‖v‖² + ½ ωᵀ (R I_b Rᵀ) ω and angular momentum about the world origin
// Σ m x × v + R I_b Rᵀ ω, over bodies and over rods' lumped node masses and edge inertias
// (not over kinematic bodies: they are driven from outside the system).

#include <memory>
#include <vector>

#include "../lib/contact_search.hpp"
#include "free_directions.hpp"
#include "islands.hpp"
#include "step_solver.hpp"

namespace liedyn {

class Simulator {
 public:
  // Validates the model and options (throws ModelError) and builds the components.
  Simulator(Model model, const SolverOptions& options);

  // Advances one time step. When the report says the state was not updated, the simulator
  // is left exactly as before the call. Under fox_goodwin, building a set of islands checks
  // its stable step (lib/stability.hpp): the constructor throws ModelError for the first set,
  // step() for one that a joint's active frames first make within the run.
  StepReport step();

  // Restarts the run from state q with the step dq (velocities dq/h; zero in static mode) at
  // the current frame, as a control loop resets its plant: the integrators' history starts
  // again from there, as at frame 0 (their first steps from the initial step), while time,
  // the schedules and prescribed motions go on. q and dq must have the model's sizes, finite
  // entries and rotations (throws std::invalid_argument otherwise; callers check more).
  void set_state(const State& q, const Step& dq);

  const Model& model() const { return model_; }
  const State& state() const { return state_; }
  const Step& last_step() const { return step_; }
  int frame() const { return frame_; }
  double time() const { return frame_ * model_.time_step; }

  // Velocity of State::points[point] and angular velocity (world frame) of
  // State::rotations[rotation]; for body i both indices are i (see Model for rods).
  Vector3 linear_velocity(int point) const;
  Vector3 angular_velocity(int rotation) const;
  // SolverOptions::measure_condition for the next steps (sampling an expensive diagnostic).
  void set_measure_condition(bool on);

  double kinetic_energy() const;
  double potential_energy() const;  // conservative loads (IncrementalPotential::potential_energy)
  Vector3 angular_momentum() const;
  // Deepest penetration ρ − φ of a contact sample into a collider (lib/contact.hpp), m;
  // 0 when no sample touches (or the model has none).
  double max_penetration() const;
  // Largest violation ‖c‖∞ of an exact joint (m or rad; IncrementalPotential::
  // constraint_violation) at the current state, 0 without exact joints.
  double constraint_violation() const;
  // The multipliers λ of the exact joint terms at the current state, in component order
  // (IncrementalPotential::exact_forces), written into `out` (cleared first).
  void exact_forces(std::vector<Vector3>& out) const;
  // Directions that nothing holds at the current state (free_directions.hpp), over every
  // component: why a static step cannot meet the tolerance. One assembly per component.
  std::vector<FreeDirection> free_directions() const;
  // The islands of the last step (of step 1 before any; solvers/islands.hpp), and how many
  // distinct sets of them the run has built.
  int islands() const { return static_cast<int>(current_->solvers.size()); }
  int island_sets() const { return static_cast<int>(islands_.size()); }
  // Which couplings held in the last step (Model::coupling_key: the joints, then the body
  // pairs of Model::body_pairs within reach of each other).
  const std::vector<bool>& coupling_key() const { return key_; }
  // How many pairs are in contact at the current state, all kinds: a body or rod with a
  // sample (a rod: a free node) inside a collider it touches, two bodies with a sample of one
  // inside the other's shape (ρ − φ > 0).
  int contact_pairs() const;
  // The smallest distance between the surfaces of two rod edges that may touch
  // (TouchingEdges::min_separation), +∞ without rod–rod contact in the model.
  double min_rod_separation() const { return search_.min_rod_separation(state_); }
  bool has_rod_contact() const { return search_.has_rod_pairs(); }

 private:
  // Calls f(point, mass, rotation, body_inertia) for every lumped mass and rotational
  // inertia (−1 for the index a mass does not have).
  template <class Function>
  void for_each_mass(Function&& f) const;

  // Moves the clamped nodes and edges of prescribed motions, and the kinematic bodies, to
  // their place at the end of the coming step (time (frame + 1) h, or λ of the motion in
  // static mode).
  void apply_prescribed_motions(double load_scale);

  Model model_;
  std::vector<RodDiscretization> rods_;
  State initial_;  // q_0: where prescribed motions start from
  SolverOptions options_;
  State state_, previous_;
  Step step_, previous_step_;
  Step step_before_;  // Δq_{k−2} for BDF2's step k (the initial step at k = 1 and 2)
  int frame_ = 0;
  int start_frame_ = 0;  // the frame the run started, or was last restarted (set_state), from
  // The step solvers of one set of islands (one per island) and their threads.
  struct StepIslands {
    std::vector<std::unique_ptr<StepSolver>> solvers;
    std::vector<StepReport> reports;  // per island, for the islands' threads
    int threads = 1;                  // SolverOptions::island_threads resolved
  };
  StepIslands& islands_at(const std::vector<bool>& key);  // IslandCache::at, this simulator's solvers
  IslandCache<StepIslands> islands_;
  StepIslands* current_ = nullptr;  // the islands of the state (last step's, or step 1's)
  std::vector<bool> key_;           // their couplings (Model::coupling_key)
  std::vector<bool> saved_key_;     // key_ at the start of a step (restored if it fails)
  // Contact between objects: the candidate pairs and which touch. Mutable: its broad phase
  // keeps the order of its last query (a cache), also for the const reports.
  mutable ContactSearch search_;
  std::vector<bool> touching_;  // the contact part of key_
  State start_;  // the step's start, to solve it again with pairs found within it
  static constexpr int kMaxContactRounds = 3;
};

}  // namespace liedyn
