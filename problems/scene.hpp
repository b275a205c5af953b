#pragma once
// Scene files (JSON) → Model + solver options. The schema is documented in
// docs/scene-format.md; every field is checked and unknown keys are rejected.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "../lib/objective.hpp"
#include "../lib/parameters.hpp"
#include "../solvers/newton.hpp"
#include "../solvers/optimizer.hpp"

namespace liedyn {

// Bad scene input. what() reads "<file>: <field>: <reason>".
class SceneError : public std::runtime_error {
 public:
  SceneError(std::string file, std::string field, std::string reason);
  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, field_, reason_;
};

// A scene's "optimization" block (docs/scene-format.md): what γ is, the objective, and the
// outer optimiser (solvers/optimizer.hpp).
struct OptimizationSpec {
  ParameterSet parameters{0};
  Objective objective;
  OptimizerOptions optimizer;
  double loss_scale = 0.0;  // normalises the loss; 0: the loss at the initial parameters
};

// Closed-form solutions a scene can declare with "analytic" (problems/analytic.hpp), which
// `liedyn sweep` measures errors against.
enum class AnalyticSolution {
  kNone,
  kFreeBody,      // "free_body": a torque-free axisymmetric rigid body (gravity allowed)
  kCantilever,    // "cantilever": small tip load on a clamped straight rod (Euler–Bernoulli)
  kAxialStretch,  // "axial_stretch": axial tip load on a straight rod fixed at node 0
};

// The most frames a scene may ask for: frame counters and loops are `int`, and 1e9 steps
// are already beyond any run that fits in a session (so the cap refuses nothing real).
inline constexpr int kMaxFrames = 1'000'000'000;

// The largest scene file read (scenes are a few kB; generated ones a few MB).
inline constexpr std::uintmax_t kMaxSceneFileBytes = 64u << 20;

struct Scene {
  std::string source;  // file name (or a label) used in messages
  std::string description;
  std::string identity;  // a hash of the scene's content (checkpoints name their problem by it)
  int frames = 0;      // time steps to simulate; frame 0 is the initial state, ≤ kMaxFrames
  Model model;
  SolverOptions solver;
  std::optional<OptimizationSpec> optimization;
  AnalyticSolution analytic = AnalyticSolution::kNone;
};

// Parses and validates JSON text; `source` names it in error messages. Relative file names in
// it (meshes) are read from `folder`, by default the folder of `source` taken as a path (give
// it when `source` is a label: "scene.json [settings]").
Scene parse_scene(const std::string& json_text, const std::string& source,
                  const std::filesystem::path& folder = {});

// The text of a scene file. Throws SceneError (unreadable file, a directory).
std::string read_scene_file(const std::filesystem::path& file);

// The text of any file liedyn reads beside a scene (a checkpoint, sweep.json, a run's CSV),
// checked as problems/input_file.hpp does, at most `max_bytes`; SceneError naming the file and
// why it was not read.
std::string read_named_input(const std::filesystem::path& file, std::uintmax_t max_bytes,
                             const std::string& kind);

// Reads and parses a scene file. Throws SceneError (also for an unreadable file).
Scene load_scene(const std::filesystem::path& file);

// Relative tolerance on ‖q‖ − 1 for "orientation" quaternions; within it the quaternion is
// normalised, beyond it the scene is rejected.
inline constexpr double kQuaternionNormTolerance = 1e-6;

}  // namespace liedyn
