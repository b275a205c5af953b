#include "bench.hpp"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>
#include <vector>

#include "../solvers/simulator.hpp"

namespace liedyn {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

BenchResult bench_scene(const Scene& scene, int repeats) {
  BenchResult result;
  result.scene = scene.source;
  result.frames = scene.frames;
  result.time_step = scene.model.time_step;
  result.repeats = std::max(repeats, 1);
  for (const Component& c : build_components(scene.model)) result.dofs += c.dofs;

  NewtonOptions options = scene.solver;
  options.measure_time = true;
  std::vector<double> total, assembly, solve, iterations, assemblies;
  for (int r = 0; r < result.repeats; ++r) {
    Simulator sim(scene.model, options);
    StepReport sum;
    int frames = 0, unconverged = 0, max_iterations = 0;
    const auto start = std::chrono::steady_clock::now();
    for (int k = 1; k <= scene.frames; ++k) {
      const StepReport report = sim.step();
      if (!report.state_updated()) {
        result.failed = true;
        result.failure = "step " + std::to_string(k) + " failed: " + to_string(report.status);
        break;
      }
      ++frames;
      sum.iterations += report.iterations;
      sum.assemblies += report.assemblies;
      sum.assembly_seconds += report.assembly_seconds;
      sum.solve_seconds += report.solve_seconds;
      max_iterations = std::max(max_iterations, report.iterations);
      if (!report.converged()) ++unconverged;
    }
    total.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    const double n_assemblies = std::max(sum.assemblies, 1);
    assembly.push_back(1e6 * sum.assembly_seconds / n_assemblies);
    solve.push_back(1e6 * sum.solve_seconds / n_assemblies);
    iterations.push_back(frames > 0 ? double(sum.iterations) / frames : 0.0);
    assemblies.push_back(frames > 0 ? double(sum.assemblies) / frames : 0.0);
    result.max_iterations_in_frame = max_iterations;
    result.unconverged_steps = unconverged;
    if (result.failed) break;
  }
  result.total_seconds = median(total);
  result.assembly_us = median(assembly);
  result.solve_us = median(solve);
  result.iterations_per_frame = median(iterations);
  result.assemblies_per_frame = median(assemblies);
  return result;
}

std::string format_bench(const BenchResult& r) {
  std::ostringstream os;
  os << std::setprecision(4);
  os << "scene        " << r.scene << "\n";
  os << "size         " << r.dofs << " DOFs, " << r.frames << " frames, h = " << r.time_step
     << " s; medians of " << r.repeats << " runs\n";
  os << "newton       " << r.iterations_per_frame << " iterations per frame (max "
     << r.max_iterations_in_frame << "), " << r.assemblies_per_frame
     << " assemblies per frame (iterations + convergence checks)\n";
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
  std::string escaped;
  for (char ch : r.scene) {
    if (ch == '"' || ch == '\\') escaped += '\\';
    escaped += ch;
  }
  os << "{\"scene\": \"" << escaped << "\", \"dofs\": " << r.dofs << ", \"frames\": " << r.frames
     << ", \"time_step\": " << r.time_step << ", \"repeats\": " << r.repeats
     << ", \"total_seconds\": " << r.total_seconds << ", \"assembly_us\": " << r.assembly_us
     << ", \"solve_us\": " << r.solve_us
     << ", \"iteration_us\": " << r.assembly_us + r.solve_us << ", \"iterations_per_frame\": "
     << r.iterations_per_frame << ", \"assemblies_per_frame\": " << r.assemblies_per_frame
     << ", \"max_iterations_in_frame\": " << r.max_iterations_in_frame
     << ", \"unconverged_steps\": " << r.unconverged_steps
     << ", \"failed\": " << (r.failed ? "true" : "false") << "}\n";
  return os.str();
}

}  // namespace liedyn
