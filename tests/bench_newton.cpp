// Google Benchmark for the Newton step of a single rigid body (fixed-size path) and for
// whole simulator steps. The paper's anchor: 233 ns per inertia assembly on a laptop CPU;
// the goal is a whole Newton iteration (assembly + 6×6 Cholesky solve) below that.
//
// Run in Release:
//   ./build-bench/tests/liedyn_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Anti-optimisation: the state is passed through benchmark::DoNotOptimize before each
// iteration (the compiler must assume it changed), every result (value, g, H, δ) goes
// through DoNotOptimize, and ClobberMemory forces writes to memory.

#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "lib/incremental_potential.hpp"
#include "lib/so3.hpp"
#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"
#include "models.hpp"

namespace {

using liedyn::BodyPoint;
using liedyn::Component;
using liedyn::Matrix3;
using liedyn::Model;
using liedyn::SolverOptions;
using liedyn::RigidBody;
using liedyn::Simulator;
using liedyn::SpringSpec;
using liedyn::State;
using liedyn::Step;
using liedyn::StepReport;
using liedyn::Vector3;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// Butterfly bolt (Dzhanibekov effect): unstable rotation about the intermediate axis.
Model butterfly_bolt() {
  Model model;
  model.time_step = 0.01;
  RigidBody b;
  b.name = "bolt";
  b.mass = 1.0;
  b.inertia = Vector3(1.0, 2.0, 2.8).asDiagonal();
  b.angular_velocity = Vector3(0.0, 2.0, 0.01);
  model.bodies.push_back(b);
  return model;
}

// Heavy top: a spinning symmetric body whose tip is held at the world origin by a stiff
// zero-length spring, under gravity, tilted 0.3 rad from the vertical.
Model heavy_top() {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  const Matrix3 R = Eigen::AngleAxisd(0.3, Vector3::UnitX()).toRotationMatrix();
  RigidBody b;
  b.name = "top";
  b.mass = 1.0;
  b.inertia = Vector3(1.0, 1.0, 0.5).asDiagonal();
  b.orientation = R;
  b.position = R * Vector3(0.0, 0.0, 1.0);
  b.angular_velocity = R * Vector3(0.0, 0.0, 20.0);
  model.bodies.push_back(b);
  SpringSpec tip;
  tip.a = BodyPoint{-1, Vector3::Zero()};
  tip.b = BodyPoint{0, Vector3(0.0, 0.0, -1.0)};
  tip.stiffness = 1e5;
  tip.rest_length = 0.0;
  model.springs.push_back(tip);
  return model;
}

// The single component of a one-body model, with begin_step done and the iterate at the
// extrapolation q = (x + Δx, ΔR R) — the first Newton iterate of the first step.
struct OneBodyProblem {
  Component component;
  State q;

  explicit OneBodyProblem(const Model& model) {
    model.validate();
    std::vector<Component> components = liedyn::build_components(model);
    component = std::move(components.at(0));
    const State previous = model.initial_state();
    const Step step = model.initial_step();
    component.potential.begin_step(previous, step);
    q = previous;
    q.points[0] += step.points[0];
    q.rotations[0] = liedyn::so3::orthonormalize(step.rotations[0] * previous.rotations[0]);
  }
};

// ---------------------------------------------------------------------------------------
// (b) Assembly alone: Ψ, 6-vector g and 6×6 H of one rigid body (all terms): the free bolt
// (two inertia terms) and the heavy top (inertia + gravity + a 4-block spring into 6×6).
template <Model (*make_model)()>
void BM_Assemble(benchmark::State& state) {
  OneBodyProblem p(make_model());
  Vector6 g;
  Matrix6 H;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.q);
    const double psi = p.component.potential.assemble(p.q, g, H);
    benchmark::DoNotOptimize(psi);
    benchmark::DoNotOptimize(g);
    benchmark::DoNotOptimize(H);
    benchmark::ClobberMemory();
  }
}
BENCHMARK_TEMPLATE(BM_Assemble, butterfly_bolt)->Name("BM_Assemble_RigidBody");
BENCHMARK_TEMPLATE(BM_Assemble, heavy_top)->Name("BM_Assemble_HeavyTop");

// The rotational inertia term alone (value, Lie gradient, Lie Hessian): the quantity the
// paper's 233 ns anchor refers to.
void BM_RotationalInertiaTerm(benchmark::State& state) {
  OneBodyProblem p(butterfly_bolt());
  const liedyn::RotationalInertia& term = p.component.potential.terms<liedyn::RotationalInertia>().at(0);
  liedyn::LocalGradient<1> g;
  liedyn::LocalHessian<1> H;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.q);
    const double v = term.evaluate(p.q, &g, &H);
    benchmark::DoNotOptimize(v);
    benchmark::DoNotOptimize(g);
    benchmark::DoNotOptimize(H);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_RotationalInertiaTerm);

// ---------------------------------------------------------------------------------------
// (a) One Newton iteration of a single rigid body: assembly + 6×6 Cholesky + solve, as the
// library does it: DenseNewton<6>::solve at an already converged iterate computes Ψ, g, H,
// factorises H, solves H δ = −g, finds ‖δ‖∞ ≤ tolerance and returns — exactly one
// iteration (plus saving the entry state, a few copies).
template <Model (*make_model)()>
void BM_NewtonIteration(benchmark::State& state) {
  OneBodyProblem p(make_model());
  liedyn::DenseNewton<6> newton(p.component, SolverOptions{});
  const StepReport first = newton.solve(p.q);  // converge once
  if (!first.converged()) state.SkipWithError("initial solve did not converge");
  long factorizations = 0, updates = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.q);
    const StepReport r = newton.solve(p.q);
    factorizations += r.factorizations;
    updates += r.iterations;
    benchmark::DoNotOptimize(r);
    benchmark::ClobberMemory();
  }
  using benchmark::Counter;
  state.counters["factorizations"] =
      Counter(static_cast<double>(factorizations), Counter::kAvgIterations);
  state.counters["updates"] = Counter(static_cast<double>(updates), Counter::kAvgIterations);
}
BENCHMARK_TEMPLATE(BM_NewtonIteration, butterfly_bolt)->Name("BM_NewtonIteration_RigidBody");
BENCHMARK_TEMPLATE(BM_NewtonIteration, heavy_top)->Name("BM_NewtonIteration_HeavyTop");

// The same iteration written directly with Eigen::LLT<Matrix<double, 6, 6>> (what
// DenseNewton<6> used before its hand-unrolled fixed-size Cholesky), for comparison.
template <Model (*make_model)()>
void BM_NewtonIterationEigenLLT(benchmark::State& state) {
  OneBodyProblem p(make_model());
  Vector6 g, delta;
  Matrix6 H;
  Eigen::LLT<Matrix6> llt;
  for (auto _ : state) {
    benchmark::DoNotOptimize(p.q);
    const double psi = p.component.potential.assemble(p.q, g, H);
    llt.compute(H);
    delta = -llt.solve(g);
    benchmark::DoNotOptimize(psi);
    benchmark::DoNotOptimize(delta);
    benchmark::ClobberMemory();
  }
  if (llt.info() != Eigen::Success) state.SkipWithError("Hessian not positive definite");
}
BENCHMARK_TEMPLATE(BM_NewtonIterationEigenLLT, butterfly_bolt)
    ->Name("BM_NewtonIteration_RigidBody_EigenLLT");
BENCHMARK_TEMPLATE(BM_NewtonIterationEigenLLT, heavy_top)
    ->Name("BM_NewtonIteration_HeavyTop_EigenLLT");

// A full accepted Newton update as DenseNewton::solve performs it (line search accepting
// α = 1), written out with Eigen::LLT: assembly, Cholesky, solve, retraction x += δx, R ← orthonormalize(exp(δθ) R),
// and one Ψ evaluation at the trial point. The iterate is reset every time so that every
// iteration does the same work.
void BM_NewtonUpdate_RigidBody(benchmark::State& state) {
  OneBodyProblem p(butterfly_bolt());
  const State start = p.q;
  Vector6 g, delta;
  Matrix6 H;
  Eigen::LLT<Matrix6> llt;
  for (auto _ : state) {
    p.q.points[0] = start.points[0];
    p.q.rotations[0] = start.rotations[0];
    benchmark::DoNotOptimize(p.q);
    const double psi = p.component.potential.assemble(p.q, g, H);
    llt.compute(H);
    delta = -llt.solve(g);
    p.q.points[0] += delta.head<3>();
    Matrix3& R = p.q.rotations[0];
    R = liedyn::so3::orthonormalize(liedyn::so3::exp(delta.tail<3>()) * R);
    const double psi_trial = p.component.potential.value(p.q);
    benchmark::DoNotOptimize(psi);
    benchmark::DoNotOptimize(psi_trial);
    benchmark::DoNotOptimize(p.q);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_NewtonUpdate_RigidBody);

// ---------------------------------------------------------------------------------------
// Building blocks, to see where the time of an iteration goes.
// Eigen's fixed-size 6×6 LLT: factorisation + solve.
void BM_LLT6_Eigen(benchmark::State& state) {
  OneBodyProblem p(butterfly_bolt());
  Vector6 g, delta;
  Matrix6 H;
  p.component.potential.assemble(p.q, g, H);
  Eigen::LLT<Matrix6> llt;
  for (auto _ : state) {
    benchmark::DoNotOptimize(H);
    benchmark::DoNotOptimize(g);
    llt.compute(H);
    delta = -llt.solve(g);
    benchmark::DoNotOptimize(delta);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_LLT6_Eigen);

void BM_So3Exp(benchmark::State& state) {
  Vector3 theta(0.01, 0.02, -0.005);
  for (auto _ : state) {
    benchmark::DoNotOptimize(theta);
    Matrix3 R = liedyn::so3::exp(theta);
    benchmark::DoNotOptimize(R);
  }
}
BENCHMARK(BM_So3Exp);

void BM_So3Orthonormalize(benchmark::State& state) {
  Matrix3 R = liedyn::so3::exp(Vector3(0.3, -0.2, 0.1));
  for (auto _ : state) {
    benchmark::DoNotOptimize(R);
    Matrix3 Q = liedyn::so3::orthonormalize(R);
    benchmark::DoNotOptimize(Q);
  }
}
BENCHMARK(BM_So3Orthonormalize);

// ---------------------------------------------------------------------------------------
// (c), (d) Whole simulator steps: begin_step, extrapolation, Newton to convergence
// (tolerance 1e-9 on ‖δ‖∞), Δq update. Counters: Newton updates and factorisations per
// step, and the number of steps that did not converge (must be 0).
void run_steps(benchmark::State& state, const Model& model) {
  Simulator sim(model, SolverOptions{});
  long iterations = 0, factorizations = 0, not_converged = 0;
  for (auto _ : state) {
    const StepReport r = sim.step();
    iterations += r.iterations;
    factorizations += r.factorizations;
    not_converged += r.converged() ? 0 : 1;
    benchmark::DoNotOptimize(r);
    benchmark::ClobberMemory();
  }
  const Vector3 w = sim.angular_velocity(0);
  benchmark::DoNotOptimize(w);
  using benchmark::Counter;
  state.counters["newton_iters_per_step"] =
      Counter(static_cast<double>(iterations), Counter::kAvgIterations);
  state.counters["factorizations_per_step"] =
      Counter(static_cast<double>(factorizations), Counter::kAvgIterations);
  state.counters["not_converged"] = Counter(static_cast<double>(not_converged));
  state.counters["steps_per_s"] = Counter(1.0, Counter::kIsIterationInvariantRate);
  if (not_converged > 0) state.SkipWithError("a step did not converge");
}

void BM_Step_ButterflyBolt(benchmark::State& state) { run_steps(state, butterfly_bolt()); }
BENCHMARK(BM_Step_ButterflyBolt);

void BM_Step_HeavyTop(benchmark::State& state) { run_steps(state, heavy_top()); }
BENCHMARK(BM_Step_HeavyTop);

// ---------------------------------------------------------------------------------------
// Dense against sparse (CHOLMOD) linear algebra for n bodies in a chain of springs: one
// Newton iteration (assembly + factorisation + solve) at a converged iterate, as in
// BM_NewtonIteration. Picks kDenseLimit.
using liedyn::test_models::spring_chain;

template <class System>
void BM_ChainIteration(benchmark::State& state) {
  const Model model = spring_chain(static_cast<int>(state.range(0)));
  std::vector<Component> components = liedyn::build_components(model);
  liedyn::Newton<System> newton(std::move(components.at(0)), SolverOptions{});
  State q = model.initial_state();
  newton.component().potential.begin_step(q, model.initial_step());
  newton.solve(q);  // converge once (and build the sparse pattern); later calls: 1 iteration
  for (auto _ : state) {
    const StepReport r = newton.solve(q);
    benchmark::DoNotOptimize(r);
    benchmark::ClobberMemory();
  }
  state.counters["dofs"] = static_cast<double>(6 * state.range(0));
}
BENCHMARK_TEMPLATE(BM_ChainIteration, liedyn::DenseSystem<Eigen::Dynamic>)
    ->Name("BM_ChainIteration_Dense")
    ->Arg(2)->Arg(4)->Arg(5)->Arg(6)->Arg(8)->Arg(16)->Arg(32);
BENCHMARK_TEMPLATE(BM_ChainIteration, liedyn::SparseSystem)
    ->Name("BM_ChainIteration_Sparse")
    ->Arg(2)->Arg(4)->Arg(5)->Arg(6)->Arg(8)->Arg(16)->Arg(32);

}  // namespace

BENCHMARK_MAIN();
