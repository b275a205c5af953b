#include "bench.hpp"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>
#include <vector>

#include "../solvers/simulator.hpp"
#include "output.hpp"
#include "run.hpp"

namespace liedyn {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double TimedRun::assembly_us() const {
  return 1e6 * sum.assembly_seconds / std::max(sum.assemblies, 1);
}
double TimedRun::solve_us() const { return 1e6 * sum.solve_seconds / std::max(sum.assemblies, 1); }

TimedRun time_scene(const Scene& scene, SolverOptions options,
                    const std::function<void(const Simulator&)>& observe) {
  using Clock = std::chrono::steady_clock;
  options.measure_time = true;
  TimedRun run;
  Simulator sim(scene.model, options);
  for (int k = 1; k <= scene.frames; ++k) {
    const auto start = Clock::now();
    const StepReport report = sim.step();
    run.total_seconds += std::chrono::duration<double>(Clock::now() - start).count();
    if (!report.state_updated()) {
      run.failed = true;
      run.failure = step_failure_message(k, scene.model.time_step, options.backend, report);
      break;
    }
    ++run.frames;
    run.sum.iterations += report.iterations;
    run.sum.factorizations += report.factorizations;
    run.sum.assemblies += report.assemblies;
    run.sum.reused_factorizations += report.reused_factorizations;
    run.sum.reuse_error = std::max(run.sum.reuse_error, report.reuse_error);
    run.sum.assembly_seconds += report.assembly_seconds;
    run.sum.solve_seconds += report.solve_seconds;
    run.max_iterations_in_frame = std::max(run.max_iterations_in_frame, report.iterations);
    if (!report.converged()) ++run.unconverged_steps;
    if (observe) observe(sim);
  }
  return run;
}

BenchResult bench_scene(const Scene& scene, int repeats) {
  BenchResult result;
  result.scene = scene.source;
  result.frames = scene.frames;
  result.time_step = scene.model.time_step;
  result.repeats = std::max(repeats, 1);
  for (const Component& c : build_components(scene.model)) result.dofs += c.dofs;

  std::vector<double> total, assembly, solve, iterations, assemblies, factorizations, reused;
  for (int r = 0; r < result.repeats; ++r) {
    const TimedRun run = time_scene(scene, scene.solver);
    total.push_back(run.total_seconds);
    assembly.push_back(run.assembly_us());
    solve.push_back(run.solve_us());
    iterations.push_back(run.frames > 0 ? double(run.sum.iterations) / run.frames : 0.0);
    assemblies.push_back(run.frames > 0 ? double(run.sum.assemblies) / run.frames : 0.0);
    factorizations.push_back(run.frames > 0 ? double(run.sum.factorizations) / run.frames : 0.0);
    reused.push_back(run.frames > 0 ? double(run.sum.reused_factorizations) / run.frames : 0.0);
    result.reuse_error = run.sum.reuse_error;
    result.max_iterations_in_frame = run.max_iterations_in_frame;
    result.unconverged_steps = run.unconverged_steps;
    result.failed = run.failed;
    result.failure = run.failure;
    if (result.failed) break;
  }
  result.total_seconds = median(total);
  result.assembly_us = median(assembly);
  result.solve_us = median(solve);
  result.iterations_per_frame = median(iterations);
  result.assemblies_per_frame = median(assemblies);
  result.factorizations_per_frame = median(factorizations);
  result.reused_per_frame = median(reused);
  return result;
}

std::string format_bench(const BenchResult& r) {
  std::ostringstream os;
  os << std::setprecision(4);
  os << "scene        " << r.scene << "\n";
  os << "size         " << r.dofs << " DOFs, " << r.frames << " frames, h = " << r.time_step
     << " s; medians of " << r.repeats << " runs\n";
  os << "iterations   " << r.iterations_per_frame << " per frame (max "
     << r.max_iterations_in_frame << "), " << r.assemblies_per_frame
     << " assemblies and " << r.factorizations_per_frame
     << " factorisations per frame (iterations + assembled convergence checks)\n";
  if (r.reused_per_frame > 0.0) {
    os << "reuse        " << r.reused_per_frame
       << " solves per frame ended on a reused factorisation (solver.hessian_reuse); their steps' "
          "largest measured relative error "
       << r.reuse_error << "\n";
  }
  os << "assembly     " << r.assembly_us << " µs per assembly\n";
  os << "solve        " << r.solve_us << " µs per factorisation + solve\n";
  os << "iteration    " << r.assembly_us + r.solve_us
     << " µs per Newton iteration (assembly + solve; the line search not included)\n";
  os << "total        " << r.total_seconds << " s\n";
  if (r.unconverged_steps > 0) os << "unconverged  " << r.unconverged_steps << " steps\n";
  if (r.failed) os << "FAILED       " << r.failure << "\n";
  return os.str();
}

std::string bench_json(const BenchResult& r) {
  std::ostringstream os;
  os << std::setprecision(9);
  os << "{\"scene\": " << json_quoted(r.scene) << ", \"dofs\": " << r.dofs << ", \"frames\": " << r.frames
     << ", \"time_step\": " << r.time_step << ", \"repeats\": " << r.repeats
     << ", \"total_seconds\": " << r.total_seconds << ", \"assembly_us\": " << r.assembly_us
     << ", \"solve_us\": " << r.solve_us
     << ", \"iteration_us\": " << r.assembly_us + r.solve_us << ", \"iterations_per_frame\": "
     << r.iterations_per_frame << ", \"assemblies_per_frame\": " << r.assemblies_per_frame
     << ", \"factorizations_per_frame\": " << r.factorizations_per_frame
     << ", \"reused_per_frame\": " << r.reused_per_frame << ", \"reuse_error\": " << r.reuse_error
     << ", \"max_iterations_in_frame\": " << r.max_iterations_in_frame
     << ", \"unconverged_steps\": " << r.unconverged_steps
     << ", \"failed\": " << (r.failed ? "true" : "false") << "}\n";
  return os.str();
}

}  // namespace liedyn
