#include "run_plots.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <ostream>
#include <string>
#include <variant>

#include "output.hpp"
#include "output_folder.hpp"
#include "recorded_run.hpp"
#include "scene.hpp"

namespace liedyn {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The folder's own name, for titles: "out" for "runs/out", "runs/out/" and, run there, ".".
std::string folder_name(const fs::path& dir) {
  fs::path path = fs::absolute(dir).lexically_normal();
  if (!path.has_filename()) path = path.parent_path();
  return path.filename().string();
}

LinePlot line_plot(const std::string& title, const std::string& x_label, const std::string& y_label,
                   bool log_y) {
  LinePlot plot;
  plot.title = title;
  plot.x_label = x_label;
  plot.y_label = y_label;
  plot.log_x = false;
  plot.log_y = log_y;
  return plot;
}

// ---- frames.csv

// A series of a run plot: the sum of its columns (the total energy) or, mostly, one column.
struct RunSeries {
  std::vector<std::string> columns;
  std::string name;
};

struct RunPlot {
  std::string file, title, y_label;
  std::vector<RunSeries> series;
  bool log_y = false, whole_y = false;
  bool per_step = false;  // a value of each step's solve: frame 0, the initial state, has none
  // A series that is 0 in every row is left out: the run had nothing to measure (no contact).
  bool zero_is_absent = false;
};

const std::vector<RunPlot>& run_plots() {
  static const std::vector<RunPlot> plots = {
      {.file = "energy.png",
       .title = "energy",
       .y_label = "energy [J]",
       .series = {{{"kinetic_energy"}, "kinetic"},
                  {{"potential_energy"}, "potential"},
                  {{"kinetic_energy", "potential_energy"}, "total"}}},
      {.file = "iterations.png",
       .title = "Newton iterations per step",
       .y_label = "Newton iterations",
       .series = {{{"newton_iterations"}, "iterations"}},
       .whole_y = true,
       .per_step = true},
      {.file = "gradient_norm.png",
       .title = "gradient norm at the end of each step",
       .y_label = "gradient norm",
       .series = {{{"gradient_norm"}, "gradient norm"}},
       .log_y = true,
       .per_step = true},
      {.file = "penetration.png",
       .title = "penetration and rod separation",
       .y_label = "distance [m]",
       .series = {{{"max_penetration"}, "max penetration"},
                  {{"min_rod_separation"}, "min rod separation"}},
       .zero_is_absent = true},
      {.file = "momentum.png",
       .title = "angular momentum about the origin",
       .y_label = "angular momentum [kg·m²/s]",
       .series = {{{"angular_momentum_x"}, "x"},
                  {{"angular_momentum_y"}, "y"},
                  {{"angular_momentum_z"}, "z"}}},
  };
  return plots;
}

using Png = std::pair<std::string, std::variant<LinePlot, ScatterPlot>>;  // file name, plot

void add_run_plots(const FramesTable& frames, const std::string& name, std::vector<Png>& pngs,
                   std::vector<std::string>& skipped) {
  const std::vector<double> time = frames.numbers("time");
  // Steps: every row but the initial state's (by its status, or frame 0 where there is none).
  const bool has_status = frames.has("status");
  const std::size_t status = has_status ? frames.column("status") : 0;
  std::vector<std::size_t> all_rows, step_rows;
  for (std::size_t r = 0; r < frames.rows.size(); ++r) {
    all_rows.push_back(r);
    const bool step = has_status ? frames.rows[r][status] != "initial" : frames.frames[r] != 0;
    if (step) step_rows.push_back(r);
  }
  std::map<std::string, std::vector<double>> columns;  // read once, only those plotted
  const auto column = [&](const std::string& c) -> const std::vector<double>& {
    auto it = columns.find(c);
    if (it == columns.end()) it = columns.emplace(c, frames.numbers(c)).first;
    return it->second;
  };
  for (const RunPlot& spec : run_plots()) {
    const std::vector<std::size_t>& rows = spec.per_step ? step_rows : all_rows;
    LinePlot plot = line_plot(spec.title + ": " + name, "time [s]", spec.y_label, spec.log_y);
    plot.whole_y = spec.whole_y;
    for (const std::size_t r : rows) plot.x.push_back(time[r]);
    std::string absent;  // the columns of the series left out
    for (const RunSeries& series : spec.series) {
      std::vector<double> y(rows.size(), 0.0);
      bool present = true;
      for (const std::string& c : series.columns) {
        if (!frames.has(c)) {
          present = false;
          break;
        }
        for (std::size_t i = 0; i < rows.size(); ++i) y[i] += column(c)[rows[i]];
      }
      const auto measured = [&](double v) { return !std::isnan(v) && !(spec.zero_is_absent && v == 0.0); };
      if (present && std::any_of(y.begin(), y.end(), measured)) {
        plot.series.push_back({series.name, y});
      } else {
        for (const std::string& c : series.columns) {
          if (absent.find(c) == std::string::npos) absent += (absent.empty() ? "" : ", ") + c;
        }
      }
    }
    if (!plot.series.empty()) {
      pngs.emplace_back(spec.file, plot);
    } else if (rows.empty()) {
      skipped.push_back(
          spec.file + ": " + frames.source +
          (frames.rows.empty() ? " holds no frame" : " holds no step (only the initial state)"));
    } else {
      skipped.push_back(spec.file + ": " + frames.source + " has no values in " + absent +
                        (spec.zero_is_absent ? " (or only zeros: nothing touched)" : ""));
    }
  }
}

// ---- history.csv and starts.csv

// The loss scale of a table's rows: loss / normalized_loss, which must be the same on every
// row where both are finite and positive; none when no row is.
std::optional<double> loss_scale_of(const CsvTable& table, const std::string& loss_column,
                                    const std::string& normalized_column) {
  const std::vector<double> loss = table.numbers(loss_column);
  const std::vector<double> normalized = table.numbers(normalized_column);
  std::optional<double> scale;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const auto usable = [](double v) { return std::isfinite(v) && v > 0; };
    if (!usable(loss[r]) || !usable(normalized[r])) continue;
    const double s = loss[r] / normalized[r];
    if (!scale) {
      scale = s;
    } else if (!(std::abs(s - *scale) <= 1e-9 * *scale)) {
      throw SceneError(table.source, "line " + std::to_string(table.lines[r]),
                       normalized_column + " is " + loss_column + " / " + format_number(s, 6) +
                           " here but " + loss_column + " / " + format_number(*scale, 6) +
                           " above (one loss scale per run)");
    }
  }
  return scale;
}

// The right-hand axis of the normalised loss, "normalized loss (loss / 0.25)", when the scale
// is known and its inverse finite.
void normalized_axis(PlotFrame& plot, std::optional<double> scale) {
  if (!scale || !std::isfinite(1 / *scale)) return;
  plot.right_label =
      "normalized " + plot.y_label + " (" + plot.y_label + " / " + format_number(*scale, 3) + ")";
  plot.right_factor = 1 / *scale;
}

void add_history_plots(const fs::path& dir, std::vector<Png>& pngs) {
  const CsvTable history = read_csv_table(dir / "history.csv", "history.csv", "iteration");
  const std::vector<double> iteration = history.numbers("iteration");
  const std::optional<double> scale = loss_scale_of(history, "loss", "normalized_loss");
  pngs.emplace_back("loss.png", loss_plot(iteration, history.numbers("loss"), scale, dir));
  LinePlot gradient =
      line_plot("loss gradient: " + folder_name(dir),
                "iteration (one per evaluation of loss and gradient)", "‖∇ loss‖", true);
  gradient.whole_x = true;
  gradient.x = iteration;
  gradient.series = {{"gradient norm", history.numbers("gradient_norm")}};
  pngs.emplace_back("loss_gradient_norm.png", gradient);
}

}  // namespace

ScatterPlot starts_plot(const CsvTable& starts, const fs::path& folder) {
  const std::vector<double> start = starts.numbers("start");
  const std::vector<double> best = starts.numbers("best_loss");
  const std::vector<double> reached = starts.numbers("reached_target");
  const std::size_t status = starts.column("status");
  ScatterPlot plot;
  plot.title = "best loss of each start: " + folder_name(folder);
  plot.x_label = "start";
  plot.y_label = "best loss";
  plot.log_x = false;
  plot.whole_x = true;
  plot.mark_pareto_front = false;
  normalized_axis(plot, loss_scale_of(starts, "best_loss", "best_normalized_loss"));
  // One series per way a start ended, in this order, those that occur.
  const std::vector<std::string> outcomes = {"reached the target", "stopped short of the target",
                                             "failed"};
  std::vector<int> outcome(starts.rows.size());
  for (std::size_t r = 0; r < starts.rows.size(); ++r) {
    outcome[r] = starts.rows[r][status] == "failed" ? 2 : reached[r] == 1 ? 0 : 1;
  }
  for (int o = 0; o < 3; ++o) {
    if (std::find(outcome.begin(), outcome.end(), o) == outcome.end()) continue;
    const int series = static_cast<int>(plot.series_names.size());
    for (std::size_t r = 0; r < starts.rows.size(); ++r) {
      if (outcome[r] == o) plot.points.push_back({start[r], best[r], "", series});
    }
    plot.series_names.push_back(outcomes[o]);
  }
  return plot;
}

LinePlot loss_plot(const std::vector<double>& iteration, const std::vector<double>& loss,
                   std::optional<double> loss_scale, const fs::path& folder) {
  LinePlot plot = line_plot("loss: " + folder_name(folder),
                            "iteration (one per evaluation of loss and gradient)", "loss", true);
  plot.whole_x = true;
  plot.x = iteration;
  std::vector<double> best;
  double lowest = kNaN;
  for (const double l : loss) {
    if (std::isfinite(l) && !(l >= lowest)) lowest = l;
    best.push_back(lowest);
  }
  plot.series = {{"loss at each evaluation", loss}, {"best so far", best}};
  normalized_axis(plot, loss_scale);
  return plot;
}

void write_plots(const fs::path& dir, const fs::path& out, std::ostream& report) {
  if (!fs::is_directory(dir)) throw SceneError(dir.string(), "", "is not a folder");
  std::vector<Png> pngs;
  std::vector<std::string> skipped;
  const bool frames = fs::exists(dir / "frames.csv"), history = fs::exists(dir / "history.csv"),
             starts = fs::exists(dir / "starts.csv");
  if (!frames && !history && !starts) {
    throw SceneError(dir.string(), "",
                     "holds no frames.csv, history.csv or starts.csv: nothing to plot");
  }
  if (history) add_history_plots(dir, pngs);
  if (starts) pngs.emplace_back("starts.png", starts_plot(read_csv_table(dir / "starts.csv", "starts.csv", "start"), dir));
  if (frames) add_run_plots(read_frames_table(dir / "frames.csv"), folder_name(dir), pngs, skipped);
  if (pngs.empty()) {
    std::string reasons;
    for (const std::string& s : skipped) reasons += (reasons.empty() ? "" : "; ") + s;
    throw SceneError(dir.string(), "", "nothing to plot: " + reasons);
  }

  OutputFolder folder(out, "plot " + dir.string(), nullptr);
  for (const Png& png : pngs) {
    std::visit(
        [&](const auto& plot) {
          write_png(plot, folder.add(png.first), (out / png.first).string());
        },
        png.second);
  }
  folder.commit();
  for (const auto& png : pngs) report << "wrote " << (out / png.first).string() << '\n';
  for (const std::string& s : skipped) report << "skipped " << s << '\n';
}

}  // namespace liedyn
