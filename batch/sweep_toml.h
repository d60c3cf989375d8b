// sweep.toml: a sweep written down (docs/sweeps.md has a full example).
//
//   model = "spring_mass.mech"      # relative to this file
//   model_name = ""                 # optional: which model of the file
//   set = { F0 = 0 }                # fixed overrides for every scenario (like --set)
//   metrics = ["final:slider.q", "cross:slider.q=0"]
//   stop_time = 5                   # optional run defaults: start_time, stop_time,
//   rtol = 1e-8                     # interval, rtol, atol, integrator, solver
//   output = "sweep-out"            # optional: directory (-o)
//   trajectories = false            # optional: one CSV per scenario
//   signals = ["slider.q"]          # optional: trajectory columns
//   list = "scenarios.csv"          # optional: like --list
//   [grid]                          # like --grid; axes in alphabetical order
//   k = "10:10:50"                  #   "a:step:b", "v1,v2,...", [v1, v2], or one number
//   [sample]                        # like --sample
//   n = 20
//   seed = 7
//   latin_hypercube = true
//   uniform = { c = [0.1, 1.0] }    # [low, high]
//   normal = { F0 = [1.0, 0.1] }    # [mean, sd]
//   [[scenario]]                    # explicit scenarios, each with its own overrides
//   k = 50                          #   of stop_time, rtol and atol
//   stop_time = 2
// Sources combine as on the command line: grid axes, then the list, then the sample,
// then the explicit scenarios, as one Cartesian product.
#pragma once

#include <string>
#include <vector>

#include "batch/scenario.h"

namespace kanesim::batch {

struct SweepFileSpec {
  std::string model;       // resolved against the TOML file's folder
  std::string model_name;
  std::vector<std::string> sets;  // "name=value"
  std::vector<Block> blocks;
  std::vector<std::string> metrics;
  double start_time = kUnset, stop_time = kUnset, interval = kUnset, rtol = kUnset, atol = kUnset;
  std::string integrator, solver;  // "" = not given
  std::string output_dir;          // "" = not given
  bool trajectories = false;
  std::vector<std::string> signals;
};

bool ReadSweepToml(const std::string& path, SweepFileSpec* out, std::string* error);
// The same from the file's text (`path` names it in messages and anchors relative paths).
bool ReadSweepTomlText(const std::string& path, const std::string& text, SweepFileSpec* out, std::string* error);

}  // namespace kanesim::batch
