#include "multistart.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "json_reader.hpp"
#include "output.hpp"
#include "output_folder.hpp"
#include "parallel.hpp"
#include "process_group.hpp"
#include "run_plots.hpp"

namespace liedyn {
namespace {

using nlohmann::json;

// A uniform variate in [0, 1) from the top 53 bits, and a standard normal by Box–Muller.
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
double normal(std::mt19937_64& rng) {
  const double u = 1.0 - uniform(rng);  // (0, 1]: the logarithm is finite
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * uniform(rng));
}

struct StartResult {
  int start = 0;
  OptimizationResult result;
};

json to_json(const StartResult& s) {
  const Eigen::VectorXd& x = s.result.best_x;
  return {{"start", s.start},
          {"evaluations", s.result.evaluations},
          {"iterations", s.result.iterations},
          {"best_loss", s.result.best_loss},
          {"status", s.result.status},
          {"message", s.result.message},
          {"seconds", s.result.seconds},
          {"best", std::vector<double>(x.data(), x.data() + x.size())}};
}

// One start's result from a checkpoint or a rank's message; SceneError naming `where`.
StartResult start_from_json(const json& j, int starts, int size, double loss_scale,
                            double target, const std::string& source, const std::string& where) {
  scene_json::ObjectReader r(j, where, source,
                             {"start", "evaluations", "iterations", "best_loss", "status", "message", "seconds", "best"});
  StartResult s;
  s.start = r.integer("start", 0, starts - 1);
  s.result.evaluations = r.integer("evaluations", 0);
  s.result.iterations = r.integer("iterations", 0);
  // A start whose every evaluation failed has no loss: +∞, which JSON writes as null.
  s.result.best_loss = r.get("best_loss").is_null() ? std::numeric_limits<double>::infinity() : r.number("best_loss");
  s.result.status = r.string("status");
  s.result.message = r.string("message");
  s.result.seconds = r.number("seconds");
  const json& best = r.array("best");
  if (static_cast<int>(best.size()) != size) {
    r.fail(r.field("best"), "must be " + std::to_string(size) + " numbers (the problem's parameters)");
  }
  s.result.best_x.resize(size);
  for (int i = 0; i < size; ++i) s.result.best_x(i) = r.to_number(best[i], r.field("best") + "[" + std::to_string(i) + "]");
  r.finish();
  s.result.best_normalized_loss = s.result.best_loss / loss_scale;
  s.result.reached_target = target > 0.0 && s.result.best_normalized_loss <= target;
  return s;
}

std::string starts_csv(const std::map<int, StartResult>& finished) {
  std::ostringstream os;
  os << std::setprecision(17)
     << "start,evaluations,iterations,best_loss,best_normalized_loss,status,reached_target,seconds,message\n";
  for (const auto& [k, s] : finished) {
    const OptimizationResult& r = s.result;
    os << k << ',' << r.evaluations << ',' << r.iterations << ',' << r.best_loss << ','
       << r.best_normalized_loss << ',' << r.status << ',' << (r.reached_target ? 1 : 0) << ','
       << r.seconds << ',' << csv_field(r.message) << '\n';
  }
  return os.str();
}

// The best finished start: the lowest best loss (failed starts count with what they reached).
const StartResult* best_of(const std::map<int, StartResult>& finished) {
  const StartResult* best = nullptr;
  for (const auto& [k, s] : finished) {
    if (std::isfinite(s.result.best_loss) && (best == nullptr || s.result.best_loss < best->result.best_loss)) {
      best = &s;
    }
  }
  return best;
}

}  // namespace

std::vector<Eigen::VectorXd> draw_starts(const Eigen::VectorXd& gamma0, const Eigen::VectorXd& lower,
                                         const Eigen::VectorXd& upper, int count, std::uint64_t seed,
                                         double spread) {
  std::mt19937_64 rng(seed);
  std::vector<Eigen::VectorXd> starts{gamma0};
  for (int k = 1; k < count; ++k) {
    Eigen::VectorXd x(gamma0.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double lo = lower(i), hi = upper(i);
      if (std::isfinite(lo) && std::isfinite(hi)) {
        x(i) = lo + (hi - lo) * uniform(rng);
        continue;
      }
      x(i) = gamma0(i) + spread * normal(rng);
      if (x(i) < lo) x(i) = lo + (lo - x(i));
      if (x(i) > hi) x(i) = hi - (x(i) - hi);
    }
    starts.push_back(std::move(x));
  }
  return starts;
}

int run_multistart(const Scene& scene, const OptimizeOptions& options, std::ostream& out) {
  ProcessGroup& group = options.group != nullptr ? *options.group : single_process();
  if (options.starts < 1) throw SceneError(scene.source, "--starts", "must be ≥ 1");
  if (options.jobs < 1) throw SceneError(scene.source, "-j", "must be ≥ 1");
  if (!(std::isfinite(options.spread) && options.spread >= 0.0)) {
    throw SceneError(scene.source, "--spread", "must be a finite number ≥ 0");
  }
  const DifferentiableSimulation sim = make_differentiable_simulation(scene);
  const OptimizerOptions optimizer = resolve_optimizer(scene, options);
  const Bounds bounds = optimizer_bounds(scene, sim, optimizer.optimizer,
                                         options.optimizer ? "--optimizer" : "optimization.optimizer");
  const int n = sim.parameters().size();
  const double inf = std::numeric_limits<double>::infinity();
  const Eigen::VectorXd lower = bounds.lower.size() == n ? bounds.lower : Eigen::VectorXd::Constant(n, -inf);
  const Eigen::VectorXd upper = bounds.upper.size() == n ? bounds.upper : Eigen::VectorXd::Constant(n, inf);
  const std::vector<Eigen::VectorXd> starts =
      draw_starts(sim.initial_parameters(), lower, upper, options.starts, options.seed, options.spread);
  json problem = problem_identity(scene, optimizer);
  problem["starts"] = options.starts;
  problem["seed"] = options.seed;
  problem["spread"] = options.spread;

  // Every rank computes the same loss scale (a deterministic forward run).
  double loss_scale = scene.optimization->loss_scale;
  if (loss_scale == 0.0) loss_scale = sim.evaluate(starts[0], nullptr).loss;
  if (!(loss_scale > 0.0)) {
    if (group.rank() == 0) {
      out << "the initial loss is " << loss_scale
          << ": nothing to minimise (set optimization.loss_scale to normalise otherwise)\n";
    }
    return 4;
  }
  const double target = optimizer.target_normalized_loss;

  // Rank 0 locks the folder and reads the checkpoint; every rank keeps the same starts.
  const bool root = group.rank() == 0;
  const std::filesystem::path checkpoint_file = options.out / "checkpoint.json";
  std::optional<OutputFolder> folder;
  const std::string checkpoint_text =
      open_output_on_root(group, folder, options.out, "optimize --starts " + scene.source,
                          options.resume ? checkpoint_file : std::filesystem::path());
  std::map<int, StartResult> finished;
  if (options.resume) {
    const std::string source = checkpoint_file.string();
    json j;
    try {
      j = json::parse(checkpoint_text);
      check_problem_identity(j.at("problem"), problem, source);
    } catch (const json::exception& e) {
      throw SceneError(source, "", std::string("not a multi-start checkpoint (") + e.what() + ")");
    }
    const json& rows = j.contains("finished") ? j["finished"] : json();
    if (!rows.is_array()) throw SceneError(source, "finished", "must be an array");
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::string where = "finished[" + std::to_string(i) + "]";
      StartResult s = start_from_json(rows[i], options.starts, n, loss_scale, target, source, where);
      // Trust no stored number: the best loss must be the loss at the best point.
      // (A failed start has no loss to check; its best point is never the run's result.)
      const double loss = std::isfinite(s.result.best_loss) ? sim.evaluate(s.result.best_x, nullptr).loss
                                                            : s.result.best_loss;
      if (std::isfinite(loss) &&
          !(std::abs(loss - s.result.best_loss) <= 1e-9 * std::max(std::abs(loss), loss_scale))) {
        throw SceneError(source, where + ".best_loss",
                         "is " + format_number(s.result.best_loss, 17) + ", but the loss at its best point is " +
                             format_number(loss, 17) + " (the checkpoint was edited or is stale)");
      }
      finished[s.start] = std::move(s);
    }
    if (root) out << "resuming from " << source << ": " << finished.size() << " of " << options.starts << " starts finished\n";
  }

  std::vector<int> mine;  // this rank's starts left to run
  for (int k = 0; k < options.starts; ++k) {
    if (k % group.size() == group.rank() && finished.count(k) == 0) mine.push_back(k);
  }
  std::map<int, StartResult> mine_finished;
  std::mutex mutex;
  const auto report = [&](const StartResult& s) {
    const OptimizationResult& r = s.result;
    out << "start " << s.start << "/" << options.starts << ": " << r.status << ", " << r.evaluations
        << " evaluations, best normalized loss " << std::setprecision(4) << r.best_normalized_loss
        << " (" << r.seconds << " s)\n" << std::flush;
  };
  const auto take_messages = [&](bool wait) {
    for (const ProcessGroup::Message& m : group.receive(wait)) {
      std::vector<StartResult> results;
      try {
        const json rows = json::parse(m.text);
        for (std::size_t i = 0; i < rows.size(); ++i) {
          results.push_back(start_from_json(rows[i], options.starts, n, loss_scale, target,
                                            "rank " + std::to_string(m.rank), "finished"));
        }
      } catch (const std::exception& e) {  // not bad input: a fault between ranks (abort them all)
        throw std::runtime_error("rank " + std::to_string(m.rank) + " sent a result rank 0 cannot read: " + e.what());
      }
      for (StartResult& s : results) {
        if (finished.count(s.start) == 0) report(s);
        finished[s.start] = std::move(s);
      }
    }
  };
  // The last checkpoint also draws starts.png (problems/run_plots.hpp) from its starts.csv.
  const auto write_checkpoint = [&](bool last) {
    json rows = json::array();
    for (const auto& [k, s] : finished) rows.push_back(to_json(s));
    folder->add("checkpoint.json") << json{{"problem", problem}, {"loss_scale", loss_scale}, {"finished", rows}}.dump() << '\n';
    const std::string csv = starts_csv(finished);
    folder->add("starts.csv") << csv;
    if (last) {
      const std::filesystem::path file = options.out / "starts.png";
      write_png(starts_plot(parse_csv_table(csv, (options.out / "starts.csv").string(), "starts.csv", "start"), options.out),
                folder->add("starts.png"), file.string());
    }
    folder->commit();
  };
  const auto messages_of_mine = [&] {
    json rows = json::array();
    for (const auto& [k, s] : mine_finished) rows.push_back(to_json(s));
    return rows.dump();
  };

  parallel_for(static_cast<int>(mine.size()), options.jobs, [&](int t) {
    const int k = mine[t];
    // Each start its own simulation: nothing shared between threads but the scene.
    const DifferentiableSimulation start_sim = make_differentiable_simulation(scene);
    StartResult s{k, minimize(objective_of(start_sim), starts[k], loss_scale, optimizer, {}, bounds)};
    const std::lock_guard<std::mutex> lock(mutex);
    if (!root) {
      mine_finished[k] = std::move(s);
      group.send(messages_of_mine(), false);
      return;
    }
    report(s);
    finished[k] = std::move(s);
    take_messages(false);
    write_checkpoint(false);
  });
  if (!root) {
    group.send(messages_of_mine(), true);
    return 0;
  }
  take_messages(true);
  write_checkpoint(true);

  const StartResult* best = best_of(finished);
  if (best == nullptr) {
    out << "every start failed: no loss was evaluated\n";
    return 4;
  }
  write_best_run(*folder, scene, sim, best->result.best_x);
  int reached = 0;
  for (const auto& [k, s] : finished) reached += s.result.reached_target ? 1 : 0;
  out << "optimizer " << to_string(optimizer.optimizer) << ", " << options.starts << " starts (seed "
      << options.seed << ", spread " << options.spread << "): " << reached << " reached the target "
      << target << "\n"
      << "best: start " << best->start << ", " << best->result.status << ", best loss "
      << std::setprecision(6) << best->result.best_loss << ", normalized "
      << best->result.best_normalized_loss << "\n"
      << "outputs in " << options.out.string() << " (starts.csv and starts.png, parameters.csv of the best start)\n";
  const bool all_failed = std::all_of(finished.begin(), finished.end(),
                                      [](const auto& f) { return f.second.result.status == "failed"; });
  if (all_failed) return 4;
  return best->result.reached_target ? 0 : 3;
}

}  // namespace liedyn
