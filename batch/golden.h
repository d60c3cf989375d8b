// Golden-output regression tests (`kanesim test`, docs/golden_tests.md).
//
// A golden test is two files side by side:
//   NAME.toml  the spec, written by a person: the model, its settings, the signals and
//              their tolerances, invariants;
//   NAME.csv   the stored output, written by `kanesim test --update`: '#' provenance
//              lines (kanesim version, hashes of the model and standard-library files,
//              of the run settings), then `time,<signals>` rows with 17 digits.
//
// Comparison: the new run is interpolated linearly in time at each golden instant (the
// grids are equal when nothing changed, and the interpolation is then exact); a signal
// fails at instant t when |new - golden| > abs + rel * |golden|. For each failing signal
// the report gives the largest deviation (where and how large, and its ratio to the
// tolerance there) and the first time the tolerance was exceeded.
#pragma once

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "batch/scenario.h"

namespace kanesim::batch {

struct Tolerance {
  std::string pattern;  // a glob over signal names (sim::GlobMatch)
  double abs = 0.0, rel = 0.0;
};

struct Invariant {
  std::string kind;  // "energy_balance", "constraint_residual", "constraint_work"
  double tol = 0.0;
  double from = kUnset, to = kUnset;  // time window (NaN = whole run)
};

// The most instants a golden stores (it is kept in memory and in version control).
inline constexpr long kMaxGoldenRows = 1'000'000;

struct GoldenSpec {
  std::string spec_path;    // NAME.toml
  std::string golden_path;  // NAME.csv (or `golden = "..."`), resolved
  std::string name;         // NAME
  std::string model;        // resolved path of the .mech file
  std::string model_name;
  std::vector<std::string> sets;  // "name=value"
  std::vector<std::string> input_files;  // the model's input tables (resolved), as --input-file
  double start_time = kUnset, stop_time = kUnset, interval = kUnset, rtol = kUnset, atol = kUnset;
  std::string integrator = "auto", solver = "auto";
  std::string energy_check = "on";   // on | off | report (docs/integrators.md "The energy guard")
  std::vector<std::string> signals;  // globs; empty: the model's default signals
  Tolerance default_tol{"*", 1e-8, 1e-6};
  std::vector<Tolerance> tolerances;  // the last matching pattern wins over the default
  std::vector<Invariant> invariants;
};

bool ReadGoldenSpec(const std::string& path, GoldenSpec* out, std::string* error);
// The same from the file's text (`path` names it in messages and anchors relative paths).
bool ReadGoldenSpecText(const std::string& path, const std::string& text, GoldenSpec* out, std::string* error);
// The text hashed into the `settings` provenance line: what the run depends on.
std::string SettingsText(const GoldenSpec& spec);

struct Trajectory {
  std::vector<std::string> names;  // signals (time excluded)
  std::vector<double> t;
  std::vector<std::vector<double>> rows;  // rows[k][j]
  std::map<std::string, std::string> provenance;  // "# key = value" lines
  int Column(const std::string& name) const;      // -1 if absent
};

// Reads a stored output; false with the reason when it is unreadable or corrupt: a last
// line cut off, no rows, a field that is not a finite number (a golden holds finite
// values only), times that decrease (an event's time stands twice: its left and right
// limits), or a row count or checksum that differs from the `rows` and `data` provenance
// lines written with it.
bool ReadTrajectoryCsv(const std::string& path, Trajectory* out, std::string* error);
bool ReadTrajectoryCsvText(const std::string& path, const std::string& text, Trajectory* out, std::string* error);
// Provenance lines (with `rows` = the row count and `data` = fnv1a64 of the row lines
// added), header, rows.
std::string FormatTrajectoryCsv(const Trajectory& t);

// "" when both hold the same instants (count, first and last time); else what differs.
// With unchanged settings the grids of a golden and of a new run are equal.
std::string CompareGrids(const Trajectory& golden, const Trajectory& run);

// Linear interpolation of column j at time t (clamped to the run's ends).
double Interpolate(const Trajectory& tr, int j, double t);

struct SignalDeviation {
  std::string signal;
  double max_dev = 0.0;    // largest |new - golden|
  double t_max = 0.0;      // where
  double tol_at_max = 0.0;
  double worst_ratio = 0.0;  // largest |new - golden| / tolerance
  double first_exceed = kUnset;  // first time beyond tolerance (NaN: never)
  bool failed() const { return !std::isnan(first_exceed); }
};

struct CompareResult {
  bool pass = true;
  std::vector<SignalDeviation> signals;  // every compared signal
  std::vector<std::string> problems;     // missing signals, shorter run, ...
};

// Each golden row against the run interpolated at its time; an event's two rows against the
// same sides of the run's event nearest in time (docs/golden_tests.md "Events").
CompareResult Compare(const GoldenSpec& spec, const Trajectory& golden, const Trajectory& actual);

struct InvariantResult {
  enum class Status { kPass, kFail, kSkipped };
  Status status = Status::kPass;
  std::string text;  // what was checked and the number found, or why it was skipped
};

// Signals an invariant needs from the run ("" entries: none). `available` are the
// program's signals; an invariant whose signals do not exist is skipped, not failed.
std::vector<std::string> InvariantSignals(const Invariant& inv, const std::vector<std::string>& available);
InvariantResult CheckInvariant(const Invariant& inv, const Trajectory& actual,
                               const std::vector<std::string>& available);

}  // namespace kanesim::batch
