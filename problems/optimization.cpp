#include "optimization.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <sstream>

#include "../lib/so3.hpp"
#include "json_reader.hpp"
#include "letters.hpp"
#include "multistart.hpp"
#include "output.hpp"
#include "process_group.hpp"
#include "run.hpp"
#include "run_plots.hpp"

namespace liedyn {

namespace {

using nlohmann::json;
using scene_json::item_path;
using scene_json::ObjectReader;

// Most frames an optimisation may simulate: the adjoint keeps all of them, and a
// projected_trajectory one target point each (docs/scene-format.md#optimization).
constexpr int kMaxOptimizationFrames = 1000000;

int body_named(ObjectReader& r, const Scene& scene) {
  const std::string name = r.string("body");
  for (std::size_t i = 0; i < scene.model.bodies.size(); ++i) {
    if (scene.model.bodies[i].name == name) return static_cast<int>(i);
  }
  r.fail(r.field("body"), "no body is named \"" + name + "\"");
}

int rod_named(ObjectReader& r, const Scene& scene) {
  const std::string name = r.string("rod");
  for (std::size_t i = 0; i < scene.model.rods.size(); ++i) {
    if (scene.model.rods[i].name == name) return static_cast<int>(i);
  }
  r.fail(r.field("rod"), "no rod is named \"" + name + "\"");
}

// Frame index: −1 (last) or 0 … frames.
int frame_of(ObjectReader& r, const Scene& scene) {
  return r.has("frame") ? r.integer("frame", -1, scene.frames) : -1;
}

std::vector<Vector3> points_of(const json& v, const std::string& field, const ObjectReader& r) {
  if (!v.is_array() || v.size() < 2) r.fail(field, "must be an array of at least 2 points");
  std::vector<Vector3> out;
  for (std::size_t i = 0; i < v.size(); ++i) out.push_back(r.to_vector<3>(v[i], item_path(field, i)));
  return out;
}

void parse_parameter(ObjectReader& r, const Scene& scene, OptimizationSpec& spec,
                     const std::string& path) {
  const std::string name = r.string("kind");
  const auto kind = parse_parameter_kind(name);
  if (!kind) r.fail(r.field("kind"), "unknown parameter kind \"" + name + "\" (see docs/scene-format.md)");
  int index = 0, sub = -1;
  switch (*kind) {
    case ParameterKind::kBodyLinearVelocity:
    case ParameterKind::kBodyAngularVelocity:
    case ParameterKind::kBodyPosition:
    case ParameterKind::kBodyOrientation:
      index = body_named(r, scene);
      break;
    case ParameterKind::kForce:
    case ParameterKind::kTorque:
    case ParameterKind::kSpringStiffness:
    case ParameterKind::kJointMotor:
      index = r.integer("index", 0);
      break;
    case ParameterKind::kNodeForce:
      index = rod_named(r, scene);
      sub = r.integer("node_force", 0);
      break;
    case ParameterKind::kCableTension:
      index = rod_named(r, scene);
      sub = r.integer("cable", 0);
      break;
    default:
      index = rod_named(r, scene);
      break;
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double lower = r.number("lower", -kInf), upper = r.number("upper", kInf);
  r.finish();
  spec.parameters.add(scene.model, *kind, index, sub, path);
  if (r.has("lower") || r.has("upper")) {
    spec.parameters.set_bounds(lower, upper, r.field(r.has("lower") ? "lower" : "upper"));
  }
}

// The first entry of γ outside its block's bounds: its block, which bound, and the reason,
// e.g. "the value 2.5 of rods[1].cables[1].tension.frame[1] is above its upper bound (2)".
struct BoundViolation {
  std::size_t block = 0;
  bool below = false;  // under the lower bound (else over the upper one)
  std::string reason;
};
std::optional<BoundViolation> bound_violation(const ParameterSet& parameters, const Model& model,
                                              const Eigen::VectorXd& gamma, const char* what) {
  const std::vector<ParameterBlock>& blocks = parameters.blocks();
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    for (int i = blocks[b].offset; i < blocks[b].offset + blocks[b].size; ++i) {
      if (blocks[b].lower <= gamma(i) && gamma(i) <= blocks[b].upper) continue;
      const bool below = !(gamma(i) >= blocks[b].lower);
      std::ostringstream reason;
      reason << std::setprecision(17) << "the " << what << ' ' << gamma(i) << " of "
             << parameters.describe(model, i) << " is "
             << (below ? "below its lower" : "above its upper") << " bound ("
             << (below ? blocks[b].lower : blocks[b].upper) << ")";
      return BoundViolation{b, below, reason.str()};
    }
  }
  return std::nullopt;
}

// The scene's initial γ must lie within the bounds (the optimisers start there).
void check_initial_within_bounds(const OptimizationSpec& spec, const Scene& scene,
                                 const ObjectReader& o) {
  const Eigen::VectorXd gamma = spec.parameters.initial_values(scene.model);
  if (const auto v = bound_violation(spec.parameters, scene.model, gamma, "initial value")) {
    o.fail(item_path(o.field("parameters"), v->block) + (v->below ? ".lower" : ".upper"),
           v->reason);
  }
}

// The 2×3 orthographic projection onto two world axes, "xy", "xz" or "yz".
Eigen::Matrix<double, 2, 3> projection_of(ObjectReader& r) {
  const std::string plane = r.string("plane", "xy");
  const std::string axes = "xyz";
  if (plane.size() != 2 || axes.find(plane[0]) == std::string::npos ||
      axes.find(plane[1]) == std::string::npos || plane[0] == plane[1]) {
    r.fail(r.field("plane"), "must be two different axes such as \"xy\" or \"xz\" (got \"" + plane + "\")");
  }
  Eigen::Matrix<double, 2, 3> P = Eigen::Matrix<double, 2, 3>::Zero();
  for (int row = 0; row < 2; ++row) P(row, static_cast<int>(plane[row] - 'x')) = 1.0;
  return P;
}

void parse_term(ObjectReader& r, const Scene& scene, OptimizationSpec& spec) {
  const std::string term = r.string("term");
  const double weight = r.number("weight", 1.0);
  if (!(weight >= 0.0)) r.fail(r.field("weight"), "must be ≥ 0");
  const Model& model = scene.model;
  if (term == "point_targets") {
    const int rod = rod_named(r, scene);
    const int frame = frame_of(r, scene);
    const int n = model.rods[rod].node_count();
    std::vector<Vector3> targets;
    const int sources = int(r.has("targets")) + int(r.has("polyline")) + int(r.has("letter"));
    if (sources != 1) r.fail(r.field("targets"), "give exactly one of targets, polyline or letter");
    if (r.has("targets")) {
      targets = points_of(r.get("targets"), r.field("targets"), r);
      if (static_cast<int>(targets.size()) != n) {
        r.fail(r.field("targets"), "has " + std::to_string(targets.size()) +
                                       " points, but the rod has " + std::to_string(n) + " nodes");
      }
    } else if (r.has("polyline")) {
      try {
        targets = resample_polyline(points_of(r.get("polyline"), r.field("polyline"), r), n);
      } catch (const std::invalid_argument& e) {
        r.fail(r.field("polyline"), e.what());
      }
    } else {
      const std::string letter = r.string("letter");
      const double height = r.number("height", 1.0);
      if (letter.size() != 1) r.fail(r.field("letter"), "must be one character");
      if (!(height > 0.0)) r.fail(r.field("height"), "must be positive");
      try {
        targets = letter_target(letter[0], height, r.vector<3>("origin", Vector3::Zero()), n);
      } catch (const std::invalid_argument& e) {
        r.fail(r.field("letter"), e.what());
      }
    }
    std::vector<int> points;
    for (int i = 0; i < n; ++i) points.push_back(model.rod_point(rod, i));
    r.finish();
    spec.objective.add(std::make_shared<PointTargets>(points, targets, frame, weight));
  } else if (term == "body_pose") {
    const int body = body_named(r, scene);
    const int frame = frame_of(r, scene);
    const bool has_position = r.has("position");
    const Vector3 position = r.vector<3>("position", Vector3::Zero());
    const Vector3 position_weights =
        r.vector<3>("position_weights", has_position ? Vector3::Ones() : Vector3::Zero());
    if ((position_weights.array() < 0.0).any()) r.fail(r.field("position_weights"), "must be ≥ 0");
    Matrix3 orientation = Matrix3::Identity();
    const bool has_orientation = r.has("orientation");
    if (has_orientation) {
      const Eigen::Vector4d wxyz = r.vector<4>("orientation");
      if (std::abs(wxyz.norm() - 1.0) > kQuaternionNormTolerance) {
        r.fail(r.field("orientation"), "must be a unit quaternion [w, x, y, z]");
      }
      orientation = so3::from_quaternion(Eigen::Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3)));
    }
    const double orientation_weight = r.number("orientation_weight", has_orientation ? 1.0 : 0.0);
    if (!(orientation_weight >= 0.0)) r.fail(r.field("orientation_weight"), "must be ≥ 0");
    // The term's weights are these times "weight": finite factors can overflow to Inf.
    if (!(weight * position_weights).allFinite()) {
      r.fail(r.field("position_weights"), "times \"weight\" overflows a double (must be finite)");
    }
    if (!std::isfinite(orientation_weight * weight)) {
      r.fail(r.field("orientation_weight"), "times \"weight\" overflows a double (must be finite)");
    }
    r.finish();
    spec.objective.add(std::make_shared<BodyPose>(body, frame, position, weight * position_weights,
                                                  orientation, orientation_weight * weight));
  } else if (term == "projected_trajectory") {
    int point = -1;
    if (r.has("body")) {
      point = body_named(r, scene);
    } else {
      const int rod = rod_named(r, scene);
      const int node = r.integer("node", 0, model.rods[rod].node_count() - 1);
      point = model.rod_point(rod, node);
    }
    const Eigen::Matrix<double, 2, 3> P = projection_of(r);
    const json& curve = r.array("curve");
    std::vector<Vector3> polyline;
    for (std::size_t i = 0; i < curve.size(); ++i) {
      const Eigen::Vector2d uv = r.to_vector<2>(curve[i], item_path(r.field("curve"), i));
      polyline.push_back(Vector3(uv(0), uv(1), 0.0));
    }
    // A curve of exactly one point per frame is taken as is; any other is resampled by arc
    // length to one point per frame.
    if (static_cast<int>(polyline.size()) != scene.frames) {
      if (polyline.size() < 2) r.fail(r.field("curve"), "needs at least 2 points");
      try {
        polyline = resample_polyline(polyline, std::max(scene.frames, 2));
      } catch (const std::invalid_argument& e) {
        r.fail(r.field("curve"), e.what());
      }
      polyline.resize(scene.frames);
    }
    std::vector<Eigen::Vector2d> points;
    for (const Vector3& p : polyline) points.emplace_back(p.x(), p.y());
    r.finish();
    spec.objective.add(std::make_shared<ProjectedTrajectory>(point, P, points, weight));
  } else if (term == "effort") {
    std::vector<int> which;
    if (r.has("parameters")) {
      const json& list = r.array("parameters");
      for (std::size_t i = 0; i < list.size(); ++i) {
        which.push_back(r.to_integer(list[i], item_path(r.field("parameters"), i), 0,
                                     static_cast<int>(spec.parameters.blocks().size()) - 1));
      }
    } else {
      for (std::size_t i = 0; i < spec.parameters.blocks().size(); ++i) which.push_back(int(i));
    }
    r.finish();
    for (int b : which) {
      const ParameterBlock& block = spec.parameters.blocks()[b];
      spec.objective.add(std::make_shared<Effort>(block.offset, block.offset + block.size, weight));
    }
  } else {
    r.fail(r.field("term"), "unknown objective term \"" + term +
                                "\" (expected point_targets, body_pose, projected_trajectory or effort)");
  }
}

}  // namespace

OptimizationSpec parse_optimization(const json& value, const Scene& scene) {
  const std::string& source = scene.source;
  ObjectReader o(value, "optimization", source,
                 {"parameters", "objective", "optimizer", "max_iterations",
                  "target_normalized_loss", "lbfgs_memory", "loss_scale"});
  if (scene.frames < 1) o.fail("frames", "an optimisation needs at least one frame");
  if (scene.frames > kMaxOptimizationFrames) {
    o.fail("frames", "an optimisation keeps every frame in memory: at most " +
                         std::to_string(kMaxOptimizationFrames) + " frames");
  }
  OptimizationSpec spec;
  spec.parameters = ParameterSet(scene.frames);
  const json& parameters = o.array("parameters");
  if (parameters.empty()) o.fail(o.field("parameters"), "must list at least one parameter");
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    const std::string path = item_path(o.field("parameters"), i);
    // The keys of each kind (parse_parameter, docs/scene-format.md#optimization).
    ObjectReader r(parameters[i], path, source, {"lower", "upper"},
                   {"kind",
                    {{"body_linear_velocity", {"body"}},
                     {"body_angular_velocity", {"body"}},
                     {"body_position", {"body"}},
                     {"body_orientation", {"body"}},
                     {"rod_node_velocities", {"rod"}},
                     {"force", {"index"}},
                     {"torque", {"index"}},
                     {"node_force", {"rod", "node_force"}},
                     {"cable_tension", {"rod", "cable"}},
                     {"joint_motor", {"index"}},
                     {"rest_darboux", {"rod"}},
                     {"rest_darboux_per_frame", {"rod"}},
                     {"spring_stiffness", {"index"}},
                     {"stretch_stiffness", {"rod"}},
                     {"shear_stiffness", {"rod"}},
                     {"bending_stiffness", {"rod"}}}});
    parse_parameter(r, scene, spec, path);
  }
  const json& objective = o.array("objective");
  if (objective.empty()) o.fail(o.field("objective"), "must list at least one term");
  for (std::size_t i = 0; i < objective.size(); ++i) {
    // The keys of each term (parse_term): a projected_trajectory's "node" in a point_targets
    // term is refused before its "targets" are read.
    ObjectReader r(objective[i], item_path(o.field("objective"), i), source, {"weight"},
                   {"term",
                    {{"point_targets",
                      {"rod", "frame", "targets", "polyline", "letter", "height", "origin"}},
                     {"body_pose",
                      {"body", "frame", "position", "position_weights", "orientation",
                       "orientation_weight"}},
                     {"projected_trajectory", {"body", "rod", "node", "plane", "curve"}},
                     {"effort", {"parameters"}}}});
    parse_term(r, scene, spec);
  }
  const std::string optimizer = o.string("optimizer", to_string(spec.optimizer.optimizer));
  if (const auto parsed = parse_optimizer(optimizer)) {
    spec.optimizer.optimizer = *parsed;
  } else {
    o.fail(o.field("optimizer"), "unknown optimizer \"" + optimizer +
                                     "\" (expected nlopt-lbfgs, ceres-lbfgs or ipopt-lbfgs)");
  }
  if (o.has("max_iterations")) spec.optimizer.max_iterations = o.integer("max_iterations", 1);
  spec.optimizer.target_normalized_loss =
      o.number("target_normalized_loss", spec.optimizer.target_normalized_loss);
  if (o.has("lbfgs_memory")) spec.optimizer.lbfgs_memory = o.integer("lbfgs_memory", 1);
  spec.loss_scale = o.number("loss_scale", 0.0);
  if (spec.loss_scale < 0.0) o.fail(o.field("loss_scale"), "must be > 0 (or absent: the initial loss)");
  o.finish();
  spec.optimizer.validate();
  check_initial_within_bounds(spec, scene, o);
  return spec;
}

DifferentiableSimulation make_differentiable_simulation(const Scene& scene) {
  if (!scene.optimization) {
    throw SceneError(scene.source, "optimization", "is required but missing (nothing to differentiate)");
  }
  return DifferentiableSimulation(scene.model, scene.optimization->parameters,
                                  scene.optimization->objective, scene.solver);
}

namespace {

// γ from a parameters.csv ("parameter,value", then one row per entry of γ, named as
// ParameterSet::describe names it); the names must be the scene's, in order. Each line is
// read without surrounding whitespace (a CRLF file reads as an LF one); blank lines are
// skipped; the line numbers in errors are the file's.
Eigen::VectorXd read_parameters(const std::filesystem::path& file,
                                const DifferentiableSimulation& sim, const Model& model) {
  const std::string source = file.string();
  std::ifstream in(file);
  if (!std::filesystem::is_regular_file(file) || !in) {
    throw SceneError(source, "", "cannot open the parameters file (not a readable file)");
  }
  int number = 0;
  std::string line;
  const auto next = [&] {  // the next non-blank line, trimmed; false at the end
    while (std::getline(in, line)) {
      ++number;
      const std::size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos) continue;
      line = line.substr(first, line.find_last_not_of(" \t\r") - first + 1);
      return true;
    }
    return false;
  };
  const auto where = [&] { return "line " + std::to_string(number); };
  if (!next()) throw SceneError(source, "", "is empty (expected the header \"parameter,value\")");
  if (line != "parameter,value") {
    throw SceneError(source, where(), "must be the header \"parameter,value\" (got \"" + line + "\")");
  }
  Eigen::VectorXd gamma(sim.parameters().size());
  for (int i = 0; i < gamma.size(); ++i) {
    const std::string name = sim.parameters().describe(model, i);
    if (!next()) {
      throw SceneError(source, "line " + std::to_string(number + 1),
                       "missing: the scene has " + std::to_string(gamma.size()) +
                           " parameters, the file " + std::to_string(i));
    }
    const std::size_t comma = line.rfind(',');
    if (comma == std::string::npos || line.substr(0, comma) != csv_field(name)) {
      throw SceneError(source, where(), "expected the parameter " + name + " (got \"" + line + "\")");
    }
    const std::string value = line.substr(comma + 1);
    std::size_t used = 0;
    try {
      gamma(i) = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (value.empty() || std::isspace(static_cast<unsigned char>(value[0])) ||
        used != value.size() || !std::isfinite(gamma(i))) {
      throw SceneError(source, where(), "the value of " + name + " must be a finite number (got \"" +
                                            value + "\")");
    }
  }
  if (next()) {
    throw SceneError(source, where(),
                     "more rows than the scene's " + std::to_string(gamma.size()) + " parameters");
  }
  return gamma;
}

}  // namespace

int run_gradcheck(const Scene& scene, const GradientCheckOptions& options, bool verbose,
                  std::ostream& out, const std::filesystem::path& parameters_file) {
  const DifferentiableSimulation sim = make_differentiable_simulation(scene);
  const Eigen::VectorXd gamma = parameters_file.empty()
                                    ? sim.initial_parameters()
                                    : read_parameters(parameters_file, sim, scene.model);
  const GradientCheckResult r = check_gradient(sim, gamma, options);
  out << std::setprecision(6);
  if (verbose) {
    out << "parameter,adjoint,finite_difference,relative_error\n";
    for (const GradientCheckEntry& e : r.entries) {
      out << csv_field(sim.parameters().describe(scene.model, e.index)) << ',' << e.adjoint << ','
          << e.finite_difference << ',' << e.relative_error << '\n';
    }
  }
  out << "loss " << r.loss << "; one forward pass " << r.forward_seconds << " s, backward pass "
      << r.backward_seconds << " s (" << (r.forward_seconds > 0 ? r.backward_seconds / r.forward_seconds : 0.0)
      << "× forward)\n";
  if (r.worst >= 0) {
    out << "worst: " << sim.parameters().describe(scene.model, r.worst) << '\n';
  }
  out << "gradcheck: max_rel_error=" << std::setprecision(3) << std::scientific
      << r.max_relative_error << " params=" << r.entries.size() << " tolerance=" << options.tolerance
      << std::defaultfloat << '\n';
  return r.passed() ? 0 : 1;
}

namespace {

struct HistoryRow {
  int iteration = 0;
  double loss = 0, normalized_loss = 0, gradient_norm = 0, seconds = 0;
};

struct Checkpoint {
  std::vector<HistoryRow> history;
  Eigen::VectorXd best;
  double best_loss = INFINITY;
  double loss_scale = 0.0;
  double seconds = 0.0;  // wall time of earlier runs
  json problem;          // what the checkpoint belongs to (problem_identity)
};

void write_history(std::ostream& f, const std::vector<HistoryRow>& rows) {
  f << std::setprecision(17) << "iteration,loss,normalized_loss,gradient_norm,seconds\n";
  for (const HistoryRow& h : rows) {
    f << h.iteration << ',' << h.loss << ',' << h.normalized_loss << ',' << h.gradient_norm << ','
      << h.seconds << '\n';
  }
}

void write_checkpoint(std::ostream& f, const Checkpoint& c) {
  json j;
  j["problem"] = c.problem;
  j["best"] = std::vector<double>(c.best.data(), c.best.data() + c.best.size());
  j["best_loss"] = c.best_loss;
  j["loss_scale"] = c.loss_scale;
  j["seconds"] = c.seconds;
  json rows = json::array();
  for (const HistoryRow& h : c.history) {
    rows.push_back({h.iteration, h.loss, h.normalized_loss, h.gradient_norm, h.seconds});
  }
  j["history"] = rows;
  f << j.dump() << '\n';
}

// The checkpoint at `file`, refused (SceneError naming the file and the field) unless it
// belongs to `problem`, has `size` parameters and finite values.
Checkpoint read_checkpoint(const std::filesystem::path& file, const json& problem, int size) {
  const std::string source = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw SceneError(source, "", "cannot resume: no checkpoint (not a regular file)");
  }
  std::ifstream in(file);
  if (!in) throw SceneError(source, "", "cannot open the checkpoint to resume from");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw SceneError(source, "", std::string("not a checkpoint (") + e.what() + ")");
  }
  Checkpoint c;
  try {
    if (!j.contains("problem")) {
      throw SceneError(source, "problem",
                       "is missing: the checkpoint does not say which problem it belongs to "
                       "(written by an older liedyn?); start without --resume");
    }
    c.problem = j.at("problem");
    check_problem_identity(c.problem, problem, source);
    const std::vector<double> best = j.at("best").get<std::vector<double>>();
    if (static_cast<int>(best.size()) != size) {
      throw SceneError(source, "best",
                       "has " + std::to_string(best.size()) + " parameters, the scene " +
                           std::to_string(size));
    }
    c.best = Eigen::Map<const Eigen::VectorXd>(best.data(), size);
    c.best_loss = j.at("best_loss").get<double>();
    c.loss_scale = j.at("loss_scale").get<double>();
    c.seconds = j.at("seconds").get<double>();
    for (const json& row : j.at("history")) {
      c.history.push_back({row.at(0).get<int>(), row.at(1).get<double>(), row.at(2).get<double>(),
                           row.at(3).get<double>(), row.at(4).get<double>()});
    }
  } catch (const json::exception& e) {
    throw SceneError(source, "", std::string("not a checkpoint of this format (") + e.what() + ")");
  }
  if (!c.best.allFinite()) throw SceneError(source, "best", "must be finite numbers");
  if (!(std::isfinite(c.loss_scale) && c.loss_scale > 0.0)) {
    throw SceneError(source, "loss_scale", "must be a finite number > 0");
  }
  return c;
}

}  // namespace

json problem_identity(const Scene& scene, const OptimizerOptions& optimizer) {
  return {{"scene", scene.identity},
          {"optimizer", to_string(optimizer.optimizer)},
          {"lbfgs_memory", optimizer.lbfgs_memory},
          {"target_normalized_loss", optimizer.target_normalized_loss}};
}

void check_problem_identity(const json& stored, const json& expected, const std::string& source) {
  for (const auto& [key, value] : expected.items()) {
    if (!stored.contains(key) || stored[key] != value) {
      throw SceneError(source, "problem." + key,
                       "is " + (stored.contains(key) ? stored[key].dump() : "missing") +
                           ", this run's " + value.dump() +
                           ": the checkpoint belongs to another problem (" +
                           (key == "scene" ? "the scene's content differs"
                                           : "the optimiser or start settings differ") +
                           ")");
    }
  }
}

OptimizerOptions resolve_optimizer(const Scene& scene, const OptimizeOptions& options) {
  OptimizerOptions optimizer = scene.optimization->optimizer;
  if (options.optimizer) optimizer.optimizer = *options.optimizer;
  if (options.max_iterations) optimizer.max_iterations = *options.max_iterations;
  optimizer.validate();
  return optimizer;
}

void write_best_run(OutputFolder& folder, const Scene& scene, const DifferentiableSimulation& sim,
                    const Eigen::VectorXd& best) {
  std::ostream& p = folder.add("parameters.csv");
  p << std::setprecision(17) << "parameter,value\n";
  for (int i = 0; i < best.size(); ++i) {
    p << csv_field(sim.parameters().describe(scene.model, i)) << ',' << best(i) << '\n';
  }
  Scene optimized = scene;
  optimized.model = sim.parameters().apply(scene.model, best);
  optimized.optimization.reset();
  simulate_into(optimized, &folder, nullptr);
  folder.commit();
}

Bounds optimizer_bounds(const Scene& scene, const DifferentiableSimulation& sim,
                        Optimizer optimizer, const std::string& field) {
  if (!sim.parameters().bounded()) return {};
  if (optimizer == Optimizer::kCeresLbfgs) {
    throw SceneError(scene.source, field,
                     std::string("the parameters have bounds, and ") + kCeresHasNoBounds);
  }
  return {sim.parameters().lower_bounds(), sim.parameters().upper_bounds()};
}

ObjectiveFunction objective_of(const DifferentiableSimulation& sim) {
  return [&sim](const Eigen::VectorXd& gamma, Eigen::VectorXd& gradient) {
    try {
      return sim.evaluate(gamma, &gradient).loss;
    } catch (const SimulationFailed& e) {
      throw InfeasiblePoint(e.what());
    } catch (const ModelError& e) {
      throw InfeasiblePoint(e.what());
    }
  };
}

int run_optimize(const Scene& scene, const OptimizeOptions& options, std::ostream& out) {
  if (options.starts > 1 || (options.group != nullptr && options.group->size() > 1)) {
    return run_multistart(scene, options, out);
  }
  const DifferentiableSimulation sim = make_differentiable_simulation(scene);
  OptimizerOptions optimizer = resolve_optimizer(scene, options);
  // Bad input, before anything is written.
  const Bounds bounds = optimizer_bounds(scene, sim, optimizer.optimizer,
                                         options.optimizer ? "--optimizer" : "optimization.optimizer");
  const std::filesystem::path checkpoint_file = options.out / "checkpoint.json";

  // The folder is locked from here to the end: no other run mixes its files in, and the
  // checkpoint cannot change under us.
  OutputFolder folder(options.out, "optimize " + scene.source, &std::cerr);
  Checkpoint checkpoint;
  checkpoint.problem = problem_identity(scene, optimizer);
  Eigen::VectorXd start = sim.initial_parameters();
  if (options.resume) {
    // A missing, foreign or edited checkpoint is bad input (exit 2).
    checkpoint = read_checkpoint(checkpoint_file, checkpoint.problem, sim.parameters().size());
    start = checkpoint.best;
    optimizer.warm_start = true;  // continue from there, not begin (Ipopt: a monotone barrier)
    // The scene's bounds may have changed since the checkpoint was written.
    if (const auto v = bound_violation(sim.parameters(), scene.model, start, "value")) {
      throw SceneError(checkpoint_file.string(), "best",
                       v->reason + " in the scene: resume cannot start there");
    }
    // Trust no stored number: the best loss must be the loss at the best point.
    double loss = NAN;
    try {
      loss = sim.evaluate(start, nullptr).loss;
    } catch (const std::exception& e) {
      throw SceneError(checkpoint_file.string(), "best",
                       std::string("cannot be evaluated: ") + e.what());
    }
    if (!(std::abs(loss - checkpoint.best_loss) <= 1e-9 * std::max(std::abs(loss), checkpoint.loss_scale))) {
      throw SceneError(checkpoint_file.string(), "best_loss",
                       "is " + format_number(checkpoint.best_loss, 17) +
                           ", but the loss at the checkpoint's best point is " +
                           format_number(loss, 17) + " (the checkpoint was edited or is stale)");
    }
    out << "resuming from " << checkpoint_file.string() << ": " << checkpoint.history.size()
        << " evaluations, best normalized loss " << checkpoint.best_loss / checkpoint.loss_scale
        << '\n';
  } else {
    checkpoint.loss_scale = scene.optimization->loss_scale;
    if (checkpoint.loss_scale == 0.0) checkpoint.loss_scale = sim.evaluate(start, nullptr).loss;
    if (!(checkpoint.loss_scale > 0.0)) {
      out << "the initial loss is " << checkpoint.loss_scale
          << ": nothing to minimise (set optimization.loss_scale to normalise otherwise)\n";
      return 4;
    }
  }
  const int first_iteration =
      checkpoint.history.empty() ? 0 : checkpoint.history.back().iteration + 1;
  const double earlier_seconds = checkpoint.seconds;

  const ObjectiveFunction f = objective_of(sim);
  auto last_progress = std::chrono::steady_clock::now();
  bool progress_shown = false;
  const EvaluationCallback record = [&](const Evaluation& e, const Eigen::VectorXd& gamma,
                                        const Eigen::VectorXd&) {
    checkpoint.history.push_back({first_iteration + e.evaluation - 1, e.loss, e.normalized_loss,
                                  e.gradient_norm, earlier_seconds + e.seconds});
    if (e.loss < checkpoint.best_loss) {
      checkpoint.best_loss = e.loss;
      checkpoint.best = gamma;
    }
    checkpoint.seconds = earlier_seconds + e.seconds;
    if (options.progress != nullptr) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_progress > std::chrono::milliseconds(250)) {
        std::ostringstream line;  // formatted apart so the caller's stream keeps its settings
        line << std::setprecision(4) << "\revaluation " << checkpoint.history.size() << ": loss "
             << e.normalized_loss << ", best " << checkpoint.best_loss / checkpoint.loss_scale
             << " (normalised), " << checkpoint.seconds << " s   ";
        *options.progress << line.str() << std::flush;
        last_progress = now;
        progress_shown = true;
      }
    }
    write_history(folder.add("history.csv"), checkpoint.history);
    write_checkpoint(folder.add("checkpoint.json"), checkpoint);
    folder.commit();
  };
  const OptimizationResult result =
      minimize(f, start, checkpoint.loss_scale, optimizer, record, bounds);
  if (progress_shown) *options.progress << '\n';

  const Eigen::VectorXd& best =
      checkpoint.best.size() == start.size() ? checkpoint.best : result.best_x;
  // The best γ, its trajectory and the plot of the loss that led there, replaced together.
  std::vector<double> iterations, losses;
  for (const HistoryRow& h : checkpoint.history) {
    iterations.push_back(h.iteration);
    losses.push_back(h.loss);
  }
  write_png(loss_plot(iterations, losses, checkpoint.loss_scale, options.out),
            folder.add("loss.png"), (options.out / "loss.png").string());
  write_best_run(folder, scene, sim, best);

  out << "optimizer " << to_string(optimizer.optimizer) << ": " << result.status
      << (result.message.empty() ? "" : " (" + result.message + ")") << '\n'
      << "iterations " << result.iterations << ", evaluations " << result.evaluations << ", "
      << std::setprecision(4) << result.seconds << " s\n"
      << "best loss " << checkpoint.best_loss << ", normalized " << checkpoint.best_loss / checkpoint.loss_scale
      << " (target " << optimizer.target_normalized_loss << ")\n"
      << "outputs in " << options.out.string() << '\n';
  if (result.status == "failed") return 4;
  return checkpoint.best_loss / checkpoint.loss_scale <= optimizer.target_normalized_loss ? 0 : 3;
}

}  // namespace liedyn
