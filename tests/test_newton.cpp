// Newton over the three linear systems (solvers/linear_system.hpp): the sparse system, with
// either of its factorisations (banded, CHOLMOD), must give the same iterates as the dense
// one, regularise the same way, and be chosen by the simulator for large coupled components.

#include <gtest/gtest.h>
#include <omp.h>

#include "lib/so3.hpp"
#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"
#include "rod_models.hpp"

namespace liedyn {
namespace {

// How the bodies of the test models are joined: each to the next (a band in body order:
// the sparse system factorises it banded), or each to the first (a star: no narrow band in
// body order, CHOLMOD's fill-reducing order wins).
enum class Topology { kChain, kStar };

// n spinning bodies joined by springs between body points, the first hung from a world
// anchor; gravity on. `rest_scale` multiplies the initial lengths: rest_scale > 1 makes the
// springs start compressed, and a compressed spring's Hessian is indefinite (forcing
// regularisation at large stiffness).
Model chain(int n, double stiffness, double rest_scale, Topology topology = Topology::kChain) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  for (int i = 0; i < n; ++i) {
    RigidBody b;
    b.name = "link" + std::to_string(i);
    b.mass = 0.5 + 0.1 * i;
    b.inertia = Vector3(0.02, 0.03, 0.04).asDiagonal();
    b.position = Vector3(0.3 * i, 0.05 * (i % 3), -0.1 * (i % 2));
    b.orientation = so3::exp(Vector3(0.1 * i, -0.2, 0.3));
    b.angular_velocity = Vector3(0.5, -1.0 + 0.2 * i, 2.0);
    b.linear_velocity = Vector3(0.0, 0.1 * i, 0.0);
    model.bodies.push_back(b);
  }
  auto world_point = [&](int body, const Vector3& local) {
    return model.bodies[body].position + model.bodies[body].orientation * local;
  };
  SpringSpec anchor;
  anchor.a.point = Vector3(-0.2, 0.0, 0.1);
  anchor.b = {0, Vector3(-0.1, 0.0, 0.0)};
  anchor.stiffness = stiffness;
  anchor.rest_length = rest_scale * (world_point(0, anchor.b.point) - anchor.a.point).norm();
  model.springs.push_back(anchor);
  for (int i = 0; i + 1 < n; ++i) {
    SpringSpec s;
    s.a = {topology == Topology::kChain ? i : 0, Vector3(0.1, 0.02, 0.0)};
    s.b = {i + 1, Vector3(-0.1, 0.0, 0.01)};
    s.stiffness = stiffness;
    s.rest_length =
        rest_scale * (world_point(i + 1, s.b.point) - world_point(s.a.body, s.a.point)).norm();
    model.springs.push_back(s);
  }
  return model;
}

// The factorisation the sparse system picks for the single component of `model`.
SparseSystem::Factorization factorization_of(const Model& model) {
  std::vector<Component> components = build_components(model);
  SparseNewton newton(std::move(components.front()), SolverOptions{});
  State q = model.initial_state();
  newton.component().potential.begin_step(q, model.initial_step());
  newton.solve(q);
  return newton.system().factorization();
}

constexpr Topology kTopologies[] = {Topology::kChain, Topology::kStar};

// Runs `steps` steps of the single component of `model` with Newton<System>, recording the
// state and the reports.
template <class System>
std::pair<std::vector<State>, std::vector<StepReport>> run(const Model& model, int steps,
                                                           const SolverOptions& options) {
  std::vector<Component> components = build_components(model);
  EXPECT_EQ(components.size(), 1u);
  Newton<System> newton(std::move(components.front()), options);
  State q = model.initial_state();
  Step dq = model.initial_step();
  std::vector<State> states;
  std::vector<StepReport> reports;
  for (int k = 0; k < steps; ++k) {
    const State previous = q;
    newton.component().potential.begin_step(previous, dq);
    for (std::size_t i = 0; i < q.points.size(); ++i) q.points[i] += dq.points[i];
    for (std::size_t i = 0; i < q.rotations.size(); ++i) {
      q.rotations[i] = so3::orthonormalize(dq.rotations[i] * q.rotations[i]);
    }
    reports.push_back(newton.solve(q));
    if (!reports.back().state_updated()) break;
    for (std::size_t i = 0; i < q.points.size(); ++i) dq.points[i] = q.points[i] - previous.points[i];
    for (std::size_t i = 0; i < q.rotations.size(); ++i) {
      dq.rotations[i] = so3::orthonormalize(q.rotations[i] * previous.rotations[i].transpose());
    }
    states.push_back(q);
  }
  return {states, reports};
}

// Largest difference between two state sequences (positions in m, rotations in rad).
double max_difference(const std::vector<State>& a, const std::vector<State>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0.0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) {
    for (std::size_t i = 0; i < a[k].points.size(); ++i) {
      d = std::max(d, (a[k].points[i] - b[k].points[i]).cwiseAbs().maxCoeff());
      d = std::max(d, so3::distance(a[k].rotations[i], b[k].rotations[i]));
    }
  }
  return d;
}

TEST(SparseNewton, FactorisesAChainBandedAndAStarWithCholmod) {
  EXPECT_EQ(factorization_of(chain(12, 2e3, 1.0, Topology::kChain)),
            SparseSystem::Factorization::kBanded);
  EXPECT_EQ(factorization_of(chain(12, 2e3, 1.0, Topology::kStar)),
            SparseSystem::Factorization::kCholmod);
}

TEST(SparseNewton, MatchesDenseNewtonOnSpringNetworks) {
  for (const Topology topology : kTopologies) {
    SCOPED_TRACE(topology == Topology::kChain ? "chain (banded)" : "star (CHOLMOD)");
    const Model model = chain(12, 2e3, 1.0, topology);
    SolverOptions options;
    options.tolerance = 1e-11;
    const auto [dense_states, dense_reports] =
        run<DenseSystem<Eigen::Dynamic>>(model, 50, options);
    const auto [sparse_states, sparse_reports] = run<SparseSystem>(model, 50, options);
    ASSERT_EQ(dense_states.size(), 50u);
    ASSERT_EQ(sparse_states.size(), 50u);
    // Both converge every step to ‖δ‖∞ ≤ 1e-11 from the same start, so the trajectories
    // agree to a small multiple of the tolerance (different orderings change only round-off).
    EXPECT_LT(max_difference(dense_states, sparse_states), 1e-9);
    for (std::size_t k = 0; k < sparse_reports.size(); ++k) {
      EXPECT_TRUE(sparse_reports[k].converged()) << "step " << k;
      EXPECT_EQ(sparse_reports[k].iterations, dense_reports[k].iterations) << "step " << k;
    }
    // The bodies really moved (the comparison is not between two resting states).
    EXPECT_GT((sparse_states.back().points[5] - model.bodies[5].position).norm(), 1e-3);
  }
}

TEST(SparseNewton, RegularisesIndefiniteHessiansLikeTheDensePath) {
  for (const Topology topology : kTopologies) {
    SCOPED_TRACE(topology == Topology::kChain ? "chain (banded)" : "star (CHOLMOD)");
    // Stiff springs compressed to 60 % of their rest length: indefinite spring Hessians.
    const Model model = chain(10, 1e6, 1.0 / 0.6, topology);
    SolverOptions options;
    options.tolerance = 1e-10;
    const auto [dense_states, dense_reports] =
        run<DenseSystem<Eigen::Dynamic>>(model, 20, options);
    const auto [sparse_states, sparse_reports] = run<SparseSystem>(model, 20, options);
    int regularized = 0;
    for (const StepReport& r : sparse_reports) regularized += r.regularized_iterations;
    EXPECT_GT(regularized, 0) << "the test must exercise the regularised path";
    ASSERT_EQ(sparse_reports.size(), dense_reports.size());
    for (std::size_t k = 0; k < sparse_reports.size(); ++k) {
      EXPECT_EQ(sparse_reports[k].status, dense_reports[k].status) << "step " << k;
      EXPECT_EQ(sparse_reports[k].regularized_iterations, dense_reports[k].regularized_iterations)
          << "step " << k;
    }
    EXPECT_LT(max_difference(dense_states, sparse_states), 1e-8);
  }
}

// Under the trapezoidal rule Newton solves (H + K) δ = −g (newton.hpp): the dense and the
// banded system factorise H + K by the same elimination, so they take the same iterations and
// regularise the same steps (springs compressed to 1/1.4 of their rest length: indefinite
// Hessians at the first step); CHOLMOD's fixed-point steps on H reach the same states.
// (Compressed stiffer, or in a star, the steps stall under either method: the trapezoidal
// rule does not damp what the springs' release excites.)
TEST(SparseNewton, TrapezoidalStepsMatchTheDensePath) {
  struct Case {
    Topology topology;
    double stiffness, rest_scale;
  };
  for (const Case& c : {Case{Topology::kChain, 2e3, 1.0}, Case{Topology::kStar, 2e3, 1.0},
                        Case{Topology::kChain, 5e4, 1.4}}) {
    SCOPED_TRACE(testing::Message() << (c.topology == Topology::kChain ? "chain" : "star")
                                    << " k = " << c.stiffness << " rest ×" << c.rest_scale);
    Model model = chain(10, c.stiffness, c.rest_scale, c.topology);
    model.integrator = Integrator::kTrapezoidal;
    SolverOptions options;
    options.tolerance = 1e-10;
    const auto [dense_states, dense_reports] = run<DenseSystem<Eigen::Dynamic>>(model, 20, options);
    const auto [sparse_states, sparse_reports] = run<SparseSystem>(model, 20, options);
    ASSERT_EQ(dense_reports.size(), 20u);
    ASSERT_EQ(sparse_reports.size(), 20u);
    int regularized = 0;
    for (std::size_t k = 0; k < sparse_reports.size(); ++k) {
      regularized += dense_reports[k].regularized_iterations;
      EXPECT_TRUE(dense_reports[k].converged()) << "step " << k;
      EXPECT_TRUE(sparse_reports[k].converged()) << "step " << k;
      if (c.topology == Topology::kChain) {
        EXPECT_EQ(sparse_reports[k].iterations, dense_reports[k].iterations) << "step " << k;
        EXPECT_EQ(sparse_reports[k].regularized_iterations,
                  dense_reports[k].regularized_iterations) << "step " << k;
      }
    }
    if (c.rest_scale > 1.0) {
      EXPECT_GT(regularized, 0) << "the test must exercise the regularised path";
    }
    EXPECT_LT(max_difference(dense_states, sparse_states), 1e-8);
  }
}

TEST(SparseNewton, StoresTheLowerBandOfAChainAndTheUpperTriangleOfAStar) {
  const int n = 9;
  for (const Topology topology : kTopologies) {
    SCOPED_TRACE(topology == Topology::kChain ? "chain (banded)" : "star (CHOLMOD)");
    const Model model = chain(n, 1e3, 1.0, topology);
    std::vector<Component> components = build_components(model);
    SparseNewton newton(std::move(components.front()), SolverOptions{});
    EXPECT_EQ(newton.system().stored_nonzeros(), 0);  // before the first assembly
    State q = model.initial_state();
    newton.component().potential.begin_step(q, model.initial_step());
    newton.solve(q);
    if (topology == Topology::kChain) {
      // Bodies are [x, θ] blocks in order; a spring joins body i's θ to body i+1's x and θ:
      // half-bandwidth 6 + 5 = 11, stored as 12 entries per column.
      EXPECT_EQ(newton.system().stored_nonzeros(), 6 * n * 12);
    } else {
      // Per body the [x, θ] blocks form a dense 6×6 on the diagonal: 3 stored 3×3 blocks.
      // Each spring couples the 2×2 blocks of its two bodies: 4 stored 3×3 blocks.
      EXPECT_EQ(newton.system().stored_nonzeros(), 9 * (3 * n + 4 * (n - 1)));
    }
  }
}

TEST(Simulator, UsesTheSparseSystemBeyondTheDenseLimitWithTheSameResult) {
  // 10 bodies = 60 DOFs > kDenseLimit: the simulator's component is sparse. It must agree
  // with the dense path run directly.
  static_assert(kDenseLimit < 60);
  const Model model = chain(10, 2e3, 1.0);
  SolverOptions options;
  options.tolerance = 1e-11;
  Simulator sim(model, options);
  std::vector<State> simulated;
  for (int k = 0; k < 30; ++k) {
    ASSERT_TRUE(sim.step().converged());
    simulated.push_back(sim.state());
  }
  const auto [dense_states, dense_reports] = run<DenseSystem<Eigen::Dynamic>>(model, 30, options);
  EXPECT_LT(max_difference(simulated, dense_states), 1e-9);
}

// Assembly in parts (SparseSystem's assembly_threads) must give the serial system up to the
// order of the sums: the same Ψ, gradient and Newton step to round-off, on a body chain (each
// part a run of bodies and springs) and on a rod (a run of nodes and edges).
void expect_parallel_assembly_matches_serial(const Model& model) {
  std::vector<Component> components = build_components(model);
  ASSERT_EQ(components.size(), 1u);
  Component& c = components.front();
  State q = model.initial_state();
  const Step dq = model.initial_step();
  c.potential.begin_step(q, dq);
  for (std::size_t i = 0; i < q.points.size(); ++i) q.points[i] += 3.0 * dq.points[i];
  for (std::size_t i = 0; i < q.rotations.size(); ++i) {
    q.rotations[i] = dq.rotations[i] * dq.rotations[i] * dq.rotations[i] * q.rotations[i];
  }
  SparseSystem serial(c, SparseSystem::Factorization::kBanded, 1);
  double serial_roundoff = 0.0;
  const double psi = serial.assemble(c.potential, q, &serial_roundoff);
  ASSERT_TRUE(serial.factorize(0.0));
  Eigen::VectorXd serial_delta(c.dofs);
  serial.solve(serial_delta);
  EXPECT_EQ(serial.assembly_parts(), 1);
  for (const int parts : {2, 3, 4}) {
    SCOPED_TRACE(parts);
    SparseSystem split(c, SparseSystem::Factorization::kBanded, parts);
    double roundoff = 0.0;
    const double value = split.assemble(c.potential, q, &roundoff);
    EXPECT_EQ(split.assembly_parts(), parts);
    EXPECT_NEAR(value, psi, 1e-13 * std::abs(psi));
    EXPECT_NEAR(roundoff, serial_roundoff, 1e-12 * serial_roundoff);
    const double g_scale = serial.gradient().cwiseAbs().maxCoeff();
    EXPECT_LT((split.gradient() - serial.gradient()).cwiseAbs().maxCoeff(), 1e-13 * g_scale);
    ASSERT_TRUE(split.factorize(0.0));
    Eigen::VectorXd delta(c.dofs);
    split.solve(delta);
    EXPECT_LT((delta - serial_delta).cwiseAbs().maxCoeff(),
              1e-9 * serial_delta.cwiseAbs().maxCoeff());
    // A second assembly (the buffers are reused, not re-zeroed by construction) agrees too.
    EXPECT_NEAR(split.assemble(c.potential, q, &roundoff), psi, 1e-13 * std::abs(psi));
    EXPECT_LT((split.gradient() - serial.gradient()).cwiseAbs().maxCoeff(), 1e-13 * g_scale);
  }
}

TEST(SparseSystem, ParallelAssemblyMatchesSerialOnABodyChain) {
  expect_parallel_assembly_matches_serial(chain(30, 2e3, 1.1));
}

TEST(SparseSystem, ParallelAssemblyMatchesSerialOnARod) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RodSpec rod = test_models::uniform_rod(50, 1.0, 0.2, 0.01, 1e4, 1e4, 0.05);
  for (std::size_t i = 0; i < rod.nodes.size(); ++i) {
    rod.nodes[i].z() = 0.1 * std::sin(0.3 * i);  // curved: non-zero rest Darboux vectors
  }
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  model.rods.push_back(rod);
  expect_parallel_assembly_matches_serial(model);
}

TEST(SparseSystem, AutomaticAssemblyThreadsDependOnSizeAndFactorisation) {
  auto parts = [](const Model& model, int threads) {
    std::vector<Component> components = build_components(model);
    SparseSystem system(components.front(), SparseSystem::Factorization::kUndecided, threads);
    State q = model.initial_state();
    components.front().potential.begin_step(q, model.initial_step());
    system.assemble(components.front().potential, q, nullptr);
    return system.assembly_parts();
  };
  const Model small = chain(12, 2e3, 1.0);  // 72 DOFs
  const Model large = chain(60, 2e3, 1.0);  // 360 DOFs
  static_assert(6 * 12 < SparseSystem::kParallelAssemblyMinDofs);
  static_assert(6 * 60 >= SparseSystem::kParallelAssemblyMinDofs);
  EXPECT_EQ(parts(small, 0), 1);
  EXPECT_EQ(parts(large, 0), omp_get_max_threads() >= 2 ? 2 : 1);
  EXPECT_EQ(parts(small, 2), 2);  // imposed
  // CHOLMOD's scatter follows the block order: a star assembles on one thread.
  EXPECT_EQ(parts(chain(60, 2e3, 1.0, Topology::kStar), 2), 1);
  EXPECT_THROW(SparseSystem(build_components(small).front(),
                            SparseSystem::Factorization::kUndecided, -1),
               std::invalid_argument);
}

TEST(SparseNewton, TrajectoryDoesNotDependOnAssemblyThreads) {
  const Model model = chain(12, 2e3, 1.0);
  SolverOptions options;
  options.tolerance = 1e-11;
  options.assembly_threads = 1;
  const auto [serial_states, serial_reports] = run<SparseSystem>(model, 30, options);
  options.assembly_threads = 2;
  const auto [split_states, split_reports] = run<SparseSystem>(model, 30, options);
  ASSERT_EQ(serial_states.size(), 30u);
  EXPECT_LT(max_difference(serial_states, split_states), 1e-9);
}

}  // namespace
}  // namespace liedyn
