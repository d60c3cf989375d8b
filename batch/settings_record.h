// What a sweep summary was made with, recorded beside it (docs/sweeps.md "Settings
// record"): DIR/summary.settings for DIR/summary.csv, summary.shard-K-of-N.settings for a
// shard. `key = value` lines in a fixed order, e.g.
//   model_text = fnv1a64:4f2c...       (hash of the .mech file's bytes)
//   set = F0=0; c=0
//   rtol = 1e-08
//   scenarios = 10 fnv1a64:9a0b...     (the scenario definitions: names, values, overrides)
// `sweep --resume` and `sweep merge` compare two records and refuse to mix summaries
// whose records differ in any key but the informational ones (kInformationalKeys).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace kanesim::batch {

struct SettingsRecord {
  std::vector<std::pair<std::string, std::string>> entries;  // key, value; in order
  void Set(const std::string& key, const std::string& value);
  const std::string* Find(const std::string& key) const;
  bool empty() const { return entries.empty(); }
};

// Keys that describe without deciding the results: shown, never compared.
inline constexpr const char* kInformationalKeys[] = {"model", "kanesim_version", "shard"};

// DIR/summary.csv -> DIR/summary.settings (the extension replaced).
std::string SettingsPathFor(const std::string& summary_path);
// DIR/summary.csv -> DIR/summary.scenarios: the scenario sources (scenario.h FormatBlocks).
std::string ScenariosPathFor(const std::string& summary_path);

std::string FormatSettings(const SettingsRecord& record);
bool ReadSettings(const std::string& path, SettingsRecord* out, std::string* error);

// One line per compared key whose values differ: "rtol: 1e-06 (recorded), 1e-08 (this
// run)". `recorded_name` and `now_name` label the two sides.
std::vector<std::string> SettingsDifferences(const SettingsRecord& recorded, const SettingsRecord& now,
                                             const std::string& recorded_name, const std::string& now_name);

}  // namespace kanesim::batch
