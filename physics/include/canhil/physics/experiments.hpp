// canhil/physics/experiments.hpp — calibration experiments on the physics.
//
// Each experiment builds its own world from the given parameters, runs it and
// returns a table, the headline figures with their targets (from
// reference-figures.md / issue 3), and time series for plotting. The `canhil
// experiment` command renders them as a table, JSON or SVG.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/physics/params.hpp"

namespace canhil::physics {

struct Figure {
  std::string name;  ///< e.g. "rest_time_s"
  double value = 0;
  std::string target;  ///< human text, e.g. "2.81 +- 0.1"; empty when none
  bool met = true;     ///< false when a target exists and is missed
};

struct Series {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
};

struct Plot {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<Series> series;
};

struct ExperimentResult {
  std::string name;
  std::string description;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  std::vector<Figure> figures;
  std::vector<Plot> plots;
  bool all_met() const;
};

struct ExperimentOptions {
  std::optional<double> height_m;                  ///< ball-drop: height of the ball's bottom
  std::optional<double> speed_mps;                 ///< ball-roll: initial speed
  std::optional<bool> low;                         ///< kick: low (direct) instead of high (lob)
  std::optional<int> power;                        ///< kick: 1..max_power
  std::optional<double> vx_mps, vy_mps, va_radps;  ///< drive: one command instead of the three standard ones
  double duration_s = 0;                           ///< 0 = the experiment's default
};

/// Names: ball-drop, ball-roll, kick, drive, tour.
std::vector<std::string> experiment_names();
/// Throws SetupError for an unknown name.
ExperimentResult run_experiment(const std::string& name, const WorldParams& base, const ExperimentOptions& options);

}  // namespace canhil::physics
