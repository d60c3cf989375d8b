// The model's inputs as functions of time (rt::InputSource): tables read from CSV files
// (`kanesim run --input-file`), and constants that a caller changes between steps (the
// stepping core, sim/simulator.h). docs/cli.md "Input tables" is the user's description.
//
// A table file: optional comment lines first ("# interpolation = hold" sets the file's
// default, "linear" otherwise), then a header `time,u,f[1],...`, then rows of numbers.
// A column's name may end in ":hold" or ":linear", which overrides the file's default for
// that input. Times strictly increase; a time outside the table is an error, never an
// extrapolation.
//   linear: u(t) = u_i + (t - t_i) (u_{i+1} - u_i) / (t_{i+1} - t_i),  t_i <= t <= t_{i+1}
//           du/dt = the segment's slope (the right segment's at a row, the last one's at the end)
//   hold:   u(t) = u_i for t_i <= t < t_{i+1} (the last row's value at its time), du/dt = 0
#pragma once

#include <string>
#include <vector>

#include "runtime/program/program.h"  // rt::InputSource
#include "runtime/runtime.h"

namespace kanesim::sim {

class InputTable final : public rt::InputSource {
 public:
  // `names`: the program's inputs (rt::InputName), in order.
  explicit InputTable(std::vector<std::string> names) : names_(std::move(names)), column_of_(names_.size()) {}

  // Reads one file and adds its columns. False with *error ("path:line:col: what") on a
  // malformed file, an unknown input name, or an input that another file already gives.
  bool Read(const std::string& path, std::string* error);

  // Which inputs have no column yet (names), in order.
  std::vector<std::string> Missing() const;
  // Why [start, stop] is not covered by every file ("" when it is).
  std::string CheckSpan(double start, double stop) const;
  // The files read, in order (their hashes are part of a run's inputs: batch/settings_record.h).
  std::vector<std::string> Files() const;

  int Values(double t, double* u, double* du_dt, std::string* error) const override;

 private:
  struct File {
    std::string path;
    std::vector<double> times;
  };
  struct Column {
    int file = -1;               // index into files_ (-1: no column)
    bool hold = false;
    std::vector<double> values;  // one per row of its file
  };
  std::vector<std::string> names_;
  std::vector<File> files_;
  std::vector<Column> column_of_;  // per input
};

// Constants that the caller sets between steps: every workspace that holds this source reads
// the new values at its next evaluation.
class ConstantInputs final : public rt::InputSource {
 public:
  explicit ConstantInputs(int n) : values(static_cast<size_t>(n), 0.0) {}
  int Values(double /*t*/, double* u, double* du_dt, std::string* /*error*/) const override {
    for (size_t i = 0; i < values.size(); ++i) {
      u[i] = values[i];
      du_dt[i] = 0.0;
    }
    return 0;
  }
  std::vector<double> values;
};

}  // namespace kanesim::sim
