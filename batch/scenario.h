// Scenarios of a sweep: where they come from (grids, lists, random samples, Latin
// hypercube, explicit TOML entries) and how the sources combine.
//
// Every source yields a Block: named columns and rows of values (NaN = keep the model's
// value), plus optional per-row run settings (stop time, tolerances). The scenarios of a
// sweep are the Cartesian product of its blocks, the first block varying slowest, so
// `--grid m=1:1:3 --grid L=0.5,1` gives (1,0.5) (1,1) (2,0.5) (2,1) (3,0.5) (3,1).
// Scenario ids are the 0-based positions in that product: they depend only on the
// sweep's definition (never on threads, shards or ranks), which is what makes --resume,
// --shard and merge well defined.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace kanesim::batch {

inline constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();
// The most scenarios one sweep may have (ids are ints; the summary is one line each).
inline constexpr int kMaxScenarios = 10'000'000;

// Per-scenario run settings; NaN = the sweep's default.
struct RunOverride {
  double stop_time = kUnset;
  double rtol = kUnset;
  double atol = kUnset;
};

struct Block {
  std::vector<std::string> names;          // parameter names (dotted, as for --set)
  std::vector<std::vector<double>> rows;   // rows[i][j] is names[j] in row i; NaN = model value
  std::vector<RunOverride> run;            // empty, or one per row
};

struct Scenario {
  int id = 0;                  // position in the product of blocks
  std::vector<double> values;  // aligned with the sweep's parameter names; NaN = model value
  RunOverride run;
};

// "a:step:b" (inclusive, values a + i*step computed without accumulation; the end is
// included when it is within 1e-9 steps) or "v1,v2,..." (a list). False with a message
// on malformed text, a zero or wrongly signed step, or more than 1e6 values.
bool ParseValues(const std::string& text, std::vector<double>* out, std::string* error);

// "--grid name=VALUES": one column block.
bool ParseGrid(const std::string& text, Block* out, std::string* error);

struct Distribution {
  enum class Kind { Uniform, Normal };
  std::string name;
  Kind kind = Kind::Uniform;
  double a = 0.0, b = 0.0;  // Uniform: [a, b); Normal: mean a, standard deviation b
};
// "--uniform name=a:b" (also "a,b") or "--normal name=mean,sd" (also "mean:sd").
bool ParseDistribution(const std::string& text, Distribution::Kind kind, Distribution* out, std::string* error);

struct SampleSpec {
  int n = 0;
  std::uint64_t seed = 1;
  bool latin_hypercube = false;  // one draw per stratum of probability 1/n in every dimension
  std::vector<Distribution> dists;
};

// The n draws of every distribution, reproducible from the seed on every platform: the
// bits come from std::mt19937_64 (whose output the C++ standard fixes), uniforms are the
// top 53 bits, normals are Box-Muller (plain) or the inverse normal CDF of a stratified
// uniform (Latin hypercube). Dimensions draw in the order given.
Block SampleBlock(const SampleSpec& spec);

// A CSV file with a header of parameter names (and optionally the run-setting columns
// stop_time, rtol, atol) and one row per scenario; '#' lines and blank lines ignored,
// an empty field keeps the model's value.
bool ReadListCsv(const std::string& path, Block* out, std::string* error);
bool ReadListCsvText(const std::string& path, const std::string& text, Block* out, std::string* error);

// The Cartesian product of the blocks. A parameter may appear in one block only.
bool CombineBlocks(const std::vector<Block>& blocks, std::vector<std::string>* names, std::vector<Scenario>* out,
                   std::string* error);

// The scenario sources written down exactly (values as %.17g, NaN as an empty field), one
// block after another:
//   block NCOLS NROWS RUN            RUN: 1 when the rows carry stop_time, rtol, atol
//   name1,name2                      the block's parameter names (CSV)
//   v11,v12[,stop_time,rtol,atol]    NROWS rows
// Written beside a sweep's summary (ScenariosPathFor), so `sweep merge` can rebuild every
// scenario and check each row's parameter values against its id.
std::string FormatBlocks(const std::vector<Block>& blocks);
bool ParseBlocks(const std::string& text, std::vector<Block>* out, std::string* error);

// "N fnv1a64:H", H over the scenario definitions (names, every scenario's values and
// overrides): the settings record's `scenarios` (settings_record.h).
std::string ScenarioDefinitionsDigest(const std::vector<std::string>& names, const std::vector<Scenario>& scenarios);

// Inverse of the standard normal CDF (Acklam's rational approximation refined by one
// Halley step; relative error below 1e-15 on (0, 1)).
double InverseNormalCdf(double p);

}  // namespace kanesim::batch
