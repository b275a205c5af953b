// No heap allocation inside the Newton loop after the first step (solvers/newton.hpp:
// "solve() allocates nothing"). This executable replaces the global allocation functions
// with counting versions:
//   * every replaceable operator new / new[] (plain, nothrow, aligned, aligned + nothrow)
//     and the matching operator delete / delete[] overloads;
//   * on glibc without sanitizers, also malloc / calloc / realloc / aligned_alloc /
//     posix_memalign / memalign / valloc / pvalloc, because Eigen's dynamic matrices (the
//     DenseNewton<Eigen::Dynamic> path) allocate through std::malloc, not operator new.
//     They forward to glibc's own allocator (__libc_malloc & co.), so every pointer is
//     still released by the same allocator whichever entry point frees it.
// Counting is off except inside a CountAllocations scope.

#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/newton.hpp"
#include "solvers/simulator.hpp"
#include "models.hpp"

namespace {

std::atomic<bool> g_counting{false};
std::atomic<long> g_operator_new_calls{0};
std::atomic<long> g_malloc_calls{0};

inline void count_new() {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_operator_new_calls.fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------
// malloc family (glibc only; sanitizers bring their own malloc, which must not be replaced).
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define LIEDYN_COUNT_MALLOC 1
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void* __libc_valloc(std::size_t size);
void* __libc_pvalloc(std::size_t size);
void __libc_free(void* p);
}

namespace {
inline void count_malloc() {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_malloc_calls.fetch_add(1, std::memory_order_relaxed);
  }
}
}  // namespace

extern "C" {
void* malloc(std::size_t size) {
  count_malloc();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  count_malloc();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  count_malloc();
  return __libc_realloc(p, size);
}
void free(void* p) { __libc_free(p); }
void* memalign(std::size_t alignment, std::size_t size) {
  count_malloc();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  count_malloc();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  count_malloc();
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return 22;  // EINVAL
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr && size != 0) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void* valloc(std::size_t size) {
  count_malloc();
  return __libc_valloc(size);
}
void* pvalloc(std::size_t size) {
  count_malloc();
  return __libc_pvalloc(size);
}
}  // extern "C"
#else
#define LIEDYN_COUNT_MALLOC 0
#endif

// ---------------------------------------------------------------------------------------
// operator new / delete. Allocation goes to malloc / aligned allocation directly; with the
// malloc family counted too, one `new` is seen by both counters (tests check each).
namespace {

void* allocate(std::size_t size) {
  if (size == 0) size = 1;
  for (;;) {
    if (void* p = std::malloc(size)) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

void* allocate_aligned(std::size_t size, std::align_val_t alignment) {
  std::size_t a = static_cast<std::size_t>(alignment);
  if (a < sizeof(void*)) a = sizeof(void*);
  if (size == 0) size = 1;
  for (;;) {
    void* p = nullptr;
    if (posix_memalign(&p, a, size) == 0 && p != nullptr) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

void* operator new(std::size_t size) {
  count_new();
  return allocate(size);
}
void* operator new[](std::size_t size) {
  count_new();
  return allocate(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  count_new();
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  count_new();
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  count_new();
  return allocate_aligned(size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  count_new();
  return allocate_aligned(size, alignment);
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  count_new();
  try {
    return allocate_aligned(size, alignment);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t alignment,
                     const std::nothrow_t&) noexcept {
  count_new();
  try {
    return allocate_aligned(size, alignment);
  } catch (...) {
    return nullptr;
  }
}

// Every replacement delete frees through this one function. Out of line on purpose: GCC
// inlines a replaced operator delete into code whose `new` it still takes for the standard
// one, and then warns that free() gets a pointer from operator new (-Wmismatched-new-delete;
// a false positive: our operator new allocates with malloc or posix_memalign).
namespace {
[[gnu::noinline]] void release(void* p) noexcept { std::free(p); }
}  // namespace

void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete(void* p, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }

// ---------------------------------------------------------------------------------------
namespace {

using liedyn::BodyPoint;
using liedyn::ForceSpec;
using liedyn::Matrix3;
using liedyn::Model;
using liedyn::SolverOptions;
using liedyn::RigidBody;
using liedyn::Simulator;
using liedyn::SpringSpec;
using liedyn::StepReport;
using liedyn::TorqueSpec;
using liedyn::Vector3;

// Counts allocations between construction and counts(); counting stops on destruction.
class CountAllocations {
 public:
  CountAllocations() {
    g_operator_new_calls = 0;
    g_malloc_calls = 0;
    g_counting = true;
  }
  ~CountAllocations() { g_counting = false; }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;

  void stop() { g_counting = false; }
  long operator_new_calls() const { return g_operator_new_calls.load(); }
  long malloc_calls() const { return g_malloc_calls.load(); }
};

// Keeps the optimiser from eliding an allocation whose result is otherwise unused.
template <class T>
void escape(T* p) {
  asm volatile("" : : "g"(p) : "memory");
}

RigidBody butterfly_bolt() {
  RigidBody b;
  b.name = "bolt";
  b.mass = 1.0;
  b.inertia = Vector3(1.0, 2.0, 2.8).asDiagonal();
  b.angular_velocity = Vector3(0.0, 2.0, 0.01);
  return b;
}

struct Outcome {
  long operator_new_calls = 0;
  long malloc_calls = 0;
  int steps_converged = 0;
  int total_iterations = 0;
  int reused_factorizations = 0;  // solves ended on a reused factorisation (hessian_reuse)
};

// One warm-up step, then `steps` steps counted.
Outcome run_counted(Simulator& sim, int steps) {
  const StepReport warm = sim.step();
  EXPECT_TRUE(warm.converged()) << liedyn::to_string(warm.status);
  Outcome out;
  {
    CountAllocations counter;
    for (int i = 0; i < steps; ++i) {
      const StepReport r = sim.step();
      out.steps_converged += r.converged() ? 1 : 0;
      out.total_iterations += r.iterations;
      out.reused_factorizations += r.reused_factorizations;
    }
    counter.stop();
    out.operator_new_calls = counter.operator_new_calls();
    out.malloc_calls = counter.malloc_calls();
  }
  return out;
}

void expect_no_allocation(const Outcome& out, int steps) {
  EXPECT_EQ(out.operator_new_calls, 0) << "operator new called inside Simulator::step()";
  EXPECT_EQ(out.malloc_calls, 0) << "malloc family called inside Simulator::step()";
  EXPECT_EQ(out.steps_converged, steps);
  EXPECT_GT(out.total_iterations, 0) << "the Newton loop must actually iterate";
}

constexpr int kSteps = 100;

// ---------------------------------------------------------------------------------------
TEST(Allocation, CounterSeesOperatorNew) {
  long seen = 0;
  {
    CountAllocations counter;
    std::vector<double> v(100, 1.0);
    escape(v.data());
    auto* p = new int(7);
    escape(p);
    delete p;
    counter.stop();
    seen = counter.operator_new_calls();
  }
  EXPECT_GE(seen, 2);
}

TEST(Allocation, CounterSeesEigenDynamicAllocation) {
#if LIEDYN_COUNT_MALLOC
  long seen = 0;
  {
    CountAllocations counter;
    Eigen::VectorXd v(64);
    v.setOnes();
    escape(v.data());
    counter.stop();
    seen = counter.malloc_calls();
  }
  EXPECT_GE(seen, 1);
#else
  GTEST_SKIP() << "malloc is not counted in this build (sanitizer or non-glibc)";
#endif
}

TEST(Allocation, CounterOffOutsideScope) {
  g_operator_new_calls = 0;
  std::vector<double> v(100, 1.0);
  escape(v.data());
  EXPECT_EQ(g_operator_new_calls.load(), 0);
}

// Simulator::step() begins with `previous_ = state_` (and the same for Step): copying
// std::vectors of equal size reuses their capacity. A larger source must allocate, which
// shows the check is live.
TEST(Allocation, EqualSizeStateCopyReusesCapacity) {
  liedyn::State a, b;
  a.points.assign(3, Vector3::Ones());
  a.rotations.assign(3, Matrix3::Identity());
  b.points.assign(3, Vector3::Zero());
  b.rotations.assign(3, Matrix3::Zero());
  liedyn::State bigger = a;
  bigger.points.resize(4, Vector3::Zero());
  long equal_size = 0, grown = 0;
  {
    CountAllocations counter;
    b = a;
    counter.stop();
    equal_size = counter.operator_new_calls() + counter.malloc_calls();
  }
  {
    CountAllocations counter;
    b = bigger;
    counter.stop();
    grown = counter.operator_new_calls();
  }
  EXPECT_EQ(equal_size, 0);
  EXPECT_GE(grown, 1);
  EXPECT_EQ(b.points.size(), 4u);
}

// (a) One free rigid body: DenseNewton<6>.
TEST(Allocation, FreeRigidBodyStepDoesNotAllocate) {
  Model model;
  model.time_step = 0.01;
  model.bodies.push_back(butterfly_bolt());
  Simulator sim(model, SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// (b) One body on a spring to a world anchor, gravity, a force at a body point, a torque.
TEST(Allocation, LoadedBodyStepDoesNotAllocate) {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RigidBody body = butterfly_bolt();
  body.position = Vector3(0.0, 0.0, -1.0);
  body.linear_velocity = Vector3(0.3, 0.0, 0.0);
  model.bodies.push_back(body);
  SpringSpec spring;
  spring.a = BodyPoint{-1, Vector3::Zero()};
  spring.b = BodyPoint{0, Vector3(0.0, 0.0, 0.2)};
  spring.stiffness = 200.0;
  spring.rest_length = 0.5;
  model.springs.push_back(spring);
  ForceSpec force;
  force.at = BodyPoint{0, Vector3(0.1, 0.0, 0.0)};
  force.force = Vector3(0.0, 1.0, 0.5);
  model.forces.push_back(force);
  TorqueSpec torque;
  torque.body = 0;
  torque.torque = Vector3(0.1, 0.0, 0.2);
  model.torques.push_back(torque);
  Simulator sim(model, SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// n bodies joined by springs into one component (tests/models.hpp).
using liedyn::test_models::spring_chain;

// (c) Three bodies coupled by springs: the dynamic-size dense path (18 DOFs).
static_assert(18 <= liedyn::kDenseLimit);
TEST(Allocation, ThreeCoupledBodiesStepDoesNotAllocate) {
  Simulator sim(spring_chain(3), SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// (d) Eight coupled bodies: 48 DOFs, beyond kDenseLimit, so the sparse path.
TEST(Allocation, EightCoupledBodiesStepDoesNotAllocate) {
  Simulator sim(spring_chain(8), SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// (e) Twenty coupled bodies: 120 DOFs > kDenseLimit, the sparse CHOLMOD path
// (pattern and symbolic analysis at the first step; numeric factorisation and solve2 with
// reused workspaces afterwards). CHOLMOD allocates through malloc, which is counted too.
TEST(Allocation, TwentyCoupledBodiesSparseStepDoesNotAllocate) {
  static_assert(6 * 20 > liedyn::kDenseLimit);
  Simulator sim(spring_chain(20), SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// (f) A clamped Cosserat rod (40 edges, 237 DOFs) bending under gravity: the sparse path
// with rod terms, assembled on one thread and in two parts on two (OpenMP's team is created
// at the first step and reused).
Model clamped_rod() {
  Model model;
  model.time_step = 0.01;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  liedyn::RodSpec rod;
  rod.name = "rod";
  for (int i = 0; i <= 40; ++i) rod.nodes.push_back(Vector3(0.025 * i, 0.0, 0.0));
  rod.mass = 0.1;
  rod.radius = 0.005;
  rod.stretch_stiffness = 1e4;
  rod.shear_stiffness = 1e4;
  rod.bending_stiffness = Vector3(0.05, 0.05, 0.04);
  rod.fixed_nodes = {0};
  rod.fixed_edges = {0};
  model.rods.push_back(rod);
  return model;
}

TEST(Allocation, ClampedRodStepDoesNotAllocate) {
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    SolverOptions options;
    options.assembly_threads = threads;
    Simulator sim(clamped_rod(), options);
    expect_no_allocation(run_counted(sim, kSteps), kSteps);
  }
}

// The second-order integrators. Trapezoidal (lib/history.hpp): the history's gradient
// assemblies at the two earlier states, the scratch state q_{k−2}, the torque fields
// re-referenced at every Newton iteration and the skew corrections' solves. BDF2: the step
// before kept by the simulator, the initial acceleration's gradient and corrected step at the
// second step. On the three kinds of linear system.
TEST(Allocation, SecondOrderStepsDoNotAllocate) {
  Model bolt;
  bolt.time_step = 0.01;
  bolt.bodies.push_back(butterfly_bolt());
  Model chain = spring_chain(8);
  Model rod = clamped_rod();
  for (const auto integrator : {liedyn::Integrator::kTrapezoidal, liedyn::Integrator::kBdf2}) {
    for (Model* model : {&bolt, &chain, &rod}) {
      model->integrator = integrator;
      Simulator sim(*model, SolverOptions{});
      expect_no_allocation(run_counted(sim, kSteps), kSteps);
    }
  }
}

// Reused factorisations (SolverOptions::hessian_reuse; sparse systems only): chord steps,
// the error measured at a new factorisation, under backward Euler and the trapezoidal rule,
// on a banded rod and a CHOLMOD chain of bodies (the trapezoidal rule's skew corrections).
TEST(Allocation, StepsOnReusedFactorisationsDoNotAllocate) {
  Model chain = spring_chain(20);
  Model rod = clamped_rod();
  rod.time_step = 1e-3;  // at 10 ms its solves take Newton iterations that chord steps cannot
  for (const auto integrator : {liedyn::Integrator::kBackwardEuler, liedyn::Integrator::kTrapezoidal}) {
    for (Model* model : {&chain, &rod}) {
      model->integrator = integrator;
      SCOPED_TRACE(std::to_string(model->bodies.size()) + " bodies, " +
                   std::to_string(model->rods.size()) + " rods, " + liedyn::to_string(integrator));
      SolverOptions options;
      options.hessian_reuse = 4;
      Simulator sim(*model, options);
      const Outcome out = run_counted(sim, kSteps);
      expect_no_allocation(out, kSteps);
      EXPECT_GT(out.reused_factorizations, 0);
    }
  }
}

// Rotation vectors (chart, save/restore of its r's and J's) and quaternions, on the three
// kinds of linear system.
TEST(Allocation, RotationVectorAndQuaternionStepsDoNotAllocate) {
  Model bolt;
  bolt.time_step = 0.01;
  bolt.bodies.push_back(butterfly_bolt());
  for (const auto rotation : {liedyn::RotationParameterization::kRotationVector,
                              liedyn::RotationParameterization::kQuaternion}) {
    for (const Model& model : {bolt, spring_chain(3), clamped_rod()}) {
      SCOPED_TRACE(std::string(liedyn::to_string(rotation)) + ", " +
                   std::to_string(model.bodies.size()) + " bodies, " +
                   std::to_string(model.rods.size()) + " rods");
      SolverOptions options;
      options.rotation = rotation;
      Simulator sim(model, options);
      expect_no_allocation(run_counted(sim, kSteps), kSteps);
    }
  }
}

// Mixed: a free body and a coupled pair in one simulator (both solver vectors).
TEST(Allocation, MixedComponentsStepDoesNotAllocate) {
  Model model = spring_chain(2);
  RigidBody free_body = butterfly_bolt();
  free_body.position = Vector3(0.0, 5.0, 0.0);
  model.bodies.push_back(free_body);
  Simulator sim(model, SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// The same islands on two threads (SolverOptions::island_threads): after the warm-up step,
// which starts OpenMP's threads, neither thread allocates (the counters are global).
TEST(Allocation, IslandsOnTwoThreadsDoNotAllocate) {
  Model model = spring_chain(2);
  RigidBody free_body = butterfly_bolt();
  free_body.position = Vector3(0.0, 5.0, 0.0);
  model.bodies.push_back(free_body);
  SolverOptions options;
  options.island_threads = 2;
  Simulator sim(model, options);
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
}

// Islands that change (solvers/islands.hpp): a ball joint between a link hung on a spring and
// a free one holds in steps 2–3 only, so the run has two sets of islands (two, then one),
// each built the first time it holds. From step 4 on the first set holds again: it is not
// built again, and the steps allocate nothing.
TEST(Allocation, IslandsThatHoldAgainAreNotBuiltAgain) {
  Model model = spring_chain(2);
  model.springs.pop_back();  // the spring between the links
  liedyn::JointSpec ball;
  ball.a = liedyn::JointEnd::body(1, Vector3(-0.1, 0.0, 0.0));
  ball.b = liedyn::JointEnd::body(0, Vector3(0.2, 0.0, 0.0));
  ball.compliance = ball.compliance_rotation = 1e-5;
  ball.first_frame = 2;
  ball.last_frame = 3;
  model.joints.push_back(ball);
  Simulator sim(model, SolverOptions{});
  EXPECT_EQ(sim.islands(), 2);
  for (int k = 1; k <= 2; ++k) ASSERT_TRUE(sim.step().converged()) << k;
  EXPECT_EQ(sim.islands(), 1);
  expect_no_allocation(run_counted(sim, kSteps), kSteps);  // steps 3 (warm) to 103
  EXPECT_EQ(sim.islands(), 2);
  EXPECT_EQ(sim.island_sets(), 2);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// DenseNewton<6> factorises with a hand-unrolled fixed-size Cholesky (solvers/newton.cpp),
// DenseNewton<Eigen::Dynamic> with Eigen::LLT. On the same one-body component both must
// take the same path (iterations, regularisations, factorisations) to the same state.
// Kept here because this executable already owns the allocation-free fixed-size path.
namespace {

struct NewtonRun {
  StepReport report;
  liedyn::State q;
};

template <int N>
NewtonRun solve_first_step(const Model& model) {
  std::vector<liedyn::Component> components = liedyn::build_components(model);
  liedyn::DenseNewton<N> newton(std::move(components.at(0)), SolverOptions{});
  const liedyn::State previous = model.initial_state();
  const liedyn::Step step = model.initial_step();
  newton.component().potential.begin_step(previous, step);
  NewtonRun run{StepReport{}, previous};
  run.q.points[0] += step.points[0];
  run.q.rotations[0] = step.rotations[0] * previous.rotations[0];
  run.report = newton.solve(run.q);
  return run;
}

void expect_same_newton_path(const Model& model) {
  const NewtonRun fixed = solve_first_step<6>(model);
  const NewtonRun dynamic = solve_first_step<Eigen::Dynamic>(model);
  EXPECT_EQ(fixed.report.status, dynamic.report.status);
  EXPECT_EQ(fixed.report.iterations, dynamic.report.iterations);
  EXPECT_EQ(fixed.report.regularized_iterations, dynamic.report.regularized_iterations);
  EXPECT_EQ(fixed.report.factorizations, dynamic.report.factorizations);
  EXPECT_NEAR((fixed.q.points[0] - dynamic.q.points[0]).norm(), 0.0, 1e-12);
  EXPECT_NEAR((fixed.q.rotations[0] - dynamic.q.rotations[0]).norm(), 0.0, 1e-12);
}

TEST(FixedSizeNewton, MatchesEigenLLTOnFreeBody) {
  Model model;
  model.bodies.push_back(butterfly_bolt());
  expect_same_newton_path(model);
}

TEST(FixedSizeNewton, MatchesEigenLLTOnLoadedBody) {
  Model model;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RigidBody body = butterfly_bolt();
  body.position = Vector3(0.0, 0.0, 1.0);
  model.bodies.push_back(body);
  SpringSpec tip;
  tip.a = BodyPoint{-1, Vector3::Zero()};
  tip.b = BodyPoint{0, Vector3(0.0, 0.0, -1.0)};
  tip.stiffness = 1e5;
  model.springs.push_back(tip);
  TorqueSpec torque;
  torque.body = 0;
  torque.torque = Vector3(0.5, -0.2, 1.0);
  model.torques.push_back(torque);
  expect_same_newton_path(model);
}

// A strongly compressed spring makes H indefinite: the regularised retries (H + μI) must
// happen, and identically, on both paths.
TEST(FixedSizeNewton, MatchesEigenLLTWhenRegularizing) {
  Model model;
  model.time_step = 0.1;
  RigidBody body = butterfly_bolt();
  body.position = Vector3(0.0, 0.0, 0.1);
  model.bodies.push_back(body);
  SpringSpec s;
  s.a = BodyPoint{-1, Vector3::Zero()};
  s.b = BodyPoint{0, Vector3(0.3, 0.0, 0.0)};
  s.stiffness = 1e4;
  s.rest_length = 2.0;
  model.springs.push_back(s);
  const NewtonRun fixed = solve_first_step<6>(model);
  EXPECT_GT(fixed.report.regularized_iterations, 0) << "the case must exercise regularisation";
  expect_same_newton_path(model);
}

// Contact and friction (lib/contact.hpp, lib/friction.hpp): a body with samples landing on a
// plane and a clamped rod hanging into a tube, with friction, through first contact (the
// SDF evaluations, the lagged friction state and the changing active set).
TEST(Allocation, ContactAndFrictionStepsDoNotAllocate) {
  Model model = clamped_rod();
  liedyn::Collider floor;
  floor.shape = liedyn::PlaneShape{};
  floor.position = Vector3(0.0, 0.0, -0.3);
  liedyn::Collider tube;
  tube.shape = liedyn::TubeShape{{Vector3(-1, 0, 0), Vector3(0.5, 0, 0.1), Vector3(2, 0, 0)}, 0.5};
  tube.inside = true;
  model.colliders = {floor, tube};
  model.rods[0].contact.stiffness = 1e3;
  model.rods[0].contact.radius = 0.005;
  model.rods[0].contact.friction = 0.3;
  RigidBody box = butterfly_bolt();
  box.position = Vector3(0.5, 0.0, -0.28);
  for (int s = 0; s < 8; ++s) {
    box.contact_points.push_back(Vector3(s & 1 ? 0.05 : -0.05, s & 2 ? 0.05 : -0.05, s & 4 ? 0.05 : -0.05));
  }
  box.contact.stiffness = 1e4;
  box.contact.friction = 0.5;
  model.bodies.push_back(box);
  Simulator sim(model, SolverOptions{});
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
  EXPECT_GT(sim.max_penetration(), 0.0);  // the run is in contact
}

// Contact between rods (lib/edge_contact.hpp): a clamped rod resting across another clamped
// one, pressed by gravity. Once the set of edge pairs within reach holds, a step searches
// all 1600 candidate pairs, evaluates the contact terms and solves the coupled island without
// allocating (the island set was built when the pairs first met).
TEST(Allocation, StepsWhoseRodContactsHoldDoNotAllocate) {
  Model model = clamped_rod();
  model.rods[0].contact.stiffness = 1e3;
  model.rods[0].contact.radius = 0.01;
  liedyn::RodSpec across = model.rods[0];
  across.name = "across";
  for (int i = 0; i <= 40; ++i) across.nodes[i] = Vector3(0.5, -0.5 + 0.025 * i, -0.03);
  across.fixed_nodes = {0, 40};
  across.fixed_edges = {0, 39};
  model.rods.push_back(across);
  ASSERT_EQ(model.edge_pairs().size(), 1600u);
  Simulator sim(model, SolverOptions{});
  for (int k = 1; k <= 50; ++k) ASSERT_TRUE(sim.step().converged()) << k;  // they meet and settle
  ASSERT_LT(sim.min_rod_separation(), 0.0);
  const int sets = sim.island_sets();
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
  EXPECT_LT(sim.min_rod_separation(), 0.0);  // still in contact
  EXPECT_EQ(sim.island_sets(), sets);
}

}  // namespace

namespace liedyn {
namespace {

// Kinematic bodies (lib/kinematic.hpp): a box carried on a moving belt, with friction. Once the
// pair holds, moving the belt to its pose (keyframes: the span search) and solving the box's
// island allocate nothing.
TEST(Allocation, StepsDrivenByAKinematicBodyDoNotAllocate) {
  Model model;
  model.time_step = 0.005;
  model.gravity = Vector3(0.0, 0.0, -9.81);
  RigidBody box;
  box.name = "box";
  box.mass = 1.0;
  box.inertia = Matrix3::Identity() * 1e-3;
  box.position = Vector3(0.0, 0.0, 0.05);
  box.shape = std::make_shared<const Collider>(Collider{"", BoxShape{Vector3::Constant(0.05), 0.0}});
  for (int s = 0; s < 8; ++s) {
    box.contact_points.push_back(Vector3(s & 1 ? 0.05 : -0.05, s & 2 ? 0.05 : -0.05, s & 4 ? 0.05 : -0.05));
  }
  box.contact.stiffness = 1e5;
  box.contact.friction = 0.5;
  RigidBody belt;
  belt.name = "belt";
  belt.position = Vector3(0.0, 0.0, -0.05);
  belt.shape = std::make_shared<const Collider>(Collider{"", BoxShape{Vector3(5.0, 1.0, 0.05), 0.0}});
  belt.kinematic = KinematicMotion{};
  belt.kinematic->keyframes = {{1.0, Vector3(0.5, 0.0, -0.05), Matrix3::Identity()},
                               {10.0, Vector3(5.0, 0.0, -0.05), Matrix3::Identity()}};
  model.bodies = {box, belt};
  Simulator sim(model, SolverOptions{});
  for (int k = 1; k <= 20; ++k) ASSERT_TRUE(sim.step().converged()) << k;  // the box settles on it
  const int sets = sim.island_sets();
  expect_no_allocation(run_counted(sim, kSteps), kSteps);
  EXPECT_EQ(sim.island_sets(), sets);
  EXPECT_GT(sim.state().points[0].x(), 0.05);  // carried along
}

}  // namespace
}  // namespace liedyn
