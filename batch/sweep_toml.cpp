#include "batch/sweep_toml.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <toml++/toml.h>

#include "batch/toml_util.h"

#include "sim/csv.h"

namespace kanesim::batch {
namespace {

std::string Resolve(const std::string& base_file, const std::string& rel) { return ResolveRelative(base_file, rel); }
std::string Where(const std::string& path, const toml::node& n) { return TomlWhere(path, n); }

// A number, "a:step:b", "v1,v2", or an array of numbers.
bool NodeValues(const std::string& path, const std::string& key, const toml::node& n, std::vector<double>* out,
                std::string* error) {
  out->clear();
  if (auto s = n.value<std::string>()) {
    std::string e;
    if (ParseValues(*s, out, &e)) return true;
    *error = Where(path, n) + key + ": " + e;
    return false;
  }
  if (auto d = n.is_number() ? n.value<double>() : std::nullopt) {
    if (!std::isfinite(*d)) {
      *error = Where(path, n) + key + ": " + sim::FormatNumber(*d) + " is not a finite number";
      return false;
    }
    out->push_back(*d);
    return true;
  }
  if (const toml::array* a = n.as_array()) {
    if (a->size() > static_cast<size_t>(kMaxScenarios)) {
      *error = Where(path, n) + key + ": more than " + std::to_string(kMaxScenarios) + " values";
      return false;
    }
    for (const toml::node& x : *a) {
      auto d = x.is_number() ? x.value<double>() : std::nullopt;
      if (!d || !std::isfinite(*d)) {
        *error = Where(path, x) + key + ": every element must be a finite number";
        return false;
      }
      out->push_back(*d);
    }
    return true;
  }
  *error = Where(path, n) + key + ": expected a number, an array of numbers or \"a:step:b\"";
  return false;
}

bool Number(const std::string& path, const toml::table& t, const char* key, double* out, std::string* error) {
  const toml::node* n = t.get(key);
  if (!n) return true;
  auto d = n->is_number() ? n->value<double>() : std::nullopt;
  if (!d || !std::isfinite(*d)) {
    *error = Where(path, *n) + key + " must be a finite number";
    return false;
  }
  *out = *d;
  return true;
}

// Keys of one type: absent, or that type (never silently ignored); strings: OptionalTomlString.
bool Bool(const std::string& path, const toml::table& t, const char* key, bool* out, std::string* error) {
  const toml::node* n = t.get(key);
  if (!n) return true;
  auto b = n->is_boolean() ? n->value<bool>() : std::nullopt;
  if (!b) {
    *error = Where(path, *n) + key + " must be true or false";
    return false;
  }
  *out = *b;
  return true;
}

bool Distributions(const std::string& path, const toml::table& sample, const char* key, Distribution::Kind kind,
                   SampleSpec* spec, std::string* error) {
  const toml::node* n = sample.get(key);
  if (!n) return true;
  const toml::table* t = n->as_table();
  if (!t) {
    *error = Where(path, *n) + std::string("sample.") + key + " must be a table name = [a, b]";
    return false;
  }
  for (const auto& [name, v] : *t) {
    std::vector<double> ab;
    if (!NodeValues(path, std::string(name.str()), v, &ab, error)) return false;
    if (ab.size() != 2) {
      *error = Where(path, v) + std::string(name.str()) + ": expected two numbers";
      return false;
    }
    std::string text = std::string(name.str()) + "=" + sim::FormatNumber(ab[0]) + "," + sim::FormatNumber(ab[1]);
    Distribution d;
    if (!ParseDistribution(text, kind, &d, error)) {
      *error = Where(path, v) + *error;
      return false;
    }
    spec->dists.push_back(d);
  }
  return true;
}

}  // namespace

bool ReadSweepToml(const std::string& path, SweepFileSpec* out, std::string* error) {
  std::string text;
  return ReadTextFile(path, kMaxSpecBytes, &text, error) && ReadSweepTomlText(path, text, out, error);
}

bool ReadSweepTomlText(const std::string& path, const std::string& text, SweepFileSpec* out, std::string* error) {
  toml::table root;
  if (!ParseTomlText(path, text, &root, error)) return false;
  *out = SweepFileSpec{};
  if (!OnlyKnownKeys(path, root,
                     {"model", "model_name", "set", "metrics", "start_time", "stop_time", "interval", "rtol", "atol",
                      "integrator", "solver", "output", "trajectories", "signals", "list", "grid", "sample", "scenario"},
                     error))
    return false;
  std::string model, output, list;
  auto string = [&](const char* key, std::string* field) { return OptionalTomlString(path, root, key, field, error); };
  if (!string("model", &model) || !string("model_name", &out->model_name) || !string("integrator", &out->integrator) ||
      !string("solver", &out->solver) || !string("output", &output) || !string("list", &list) ||
      !Bool(path, root, "trajectories", &out->trajectories, error))
    return false;
  if (!model.empty()) out->model = Resolve(path, model);
  if (!output.empty()) out->output_dir = Resolve(path, output);
  if (!OptionalTomlStrings(path, root, "metrics", "strings", &out->metrics, error) ||
      !OptionalTomlStrings(path, root, "signals", "strings", &out->signals, error))
    return false;
  for (auto [key, field] : {std::pair{"start_time", &out->start_time}, {"stop_time", &out->stop_time},
                            {"interval", &out->interval}, {"rtol", &out->rtol}, {"atol", &out->atol}})
    if (!Number(path, root, key, field, error)) return false;
  for (auto [key, value] : {std::pair{"interval", out->interval}, {"rtol", out->rtol}, {"atol", out->atol}})
    if (!(std::isnan(value) || value > 0.0)) {
      *error = Where(path, *root.get(key)) + key + " must be positive";
      return false;
    }
  if (out->stop_time < out->start_time) {  // false when either is not given (NaN)
    *error = Where(path, *root.get("stop_time")) + "stop_time (" + sim::FormatNumber(out->stop_time) +
             ") is before start_time (" + sim::FormatNumber(out->start_time) + ")";
    return false;
  }
  if (const toml::node* set = root.get("set"))
    if (!ReadSetTable(path, *set, &out->sets, error)) return false;
  for (const char* key : {"grid", "sample"})
    if (const toml::node* n = root.get(key); n && !n->is_table()) {
      *error = Where(path, *n) + key + " must be a table ([" + key + "])";
      return false;
    }
  if (const toml::node* n = root.get("scenario"); n && !n->is_array_of_tables()) {
    *error = Where(path, *n) + "scenario must be an array of tables ([[scenario]])";
    return false;
  }
  if (const toml::table* grid = root["grid"].as_table()) {
    for (const auto& [name, v] : *grid) {
      std::vector<double> values;
      if (!NodeValues(path, std::string(name.str()), v, &values, error)) return false;
      Block b;
      b.names = {std::string(name.str())};
      for (double x : values) b.rows.push_back({x});
      out->blocks.push_back(std::move(b));
    }
  }
  if (!list.empty()) {
    Block b;
    if (!ReadListCsv(Resolve(path, list), &b, error)) return false;
    out->blocks.push_back(std::move(b));
  }
  if (const toml::table* sample = root["sample"].as_table()) {
    SampleSpec spec;
    for (const auto& [k, v] : *sample) {
      const std::string key(k.str());
      if (key != "n" && key != "seed" && key != "latin_hypercube" && key != "uniform" && key != "normal") {
        *error = Where(path, v) + "unknown key 'sample." + key + "' (n, seed, latin_hypercube, uniform, normal)";
        return false;
      }
    }
    // Integers are checked as integers before any narrowing: n = 2^32 + 5 is not 5.
    const toml::node* n = sample->get("n");
    auto count = n ? n->value_exact<int64_t>() : std::nullopt;
    if (!count || *count < 1 || *count > kMaxScenarios) {
      *error = (n ? Where(path, *n) : path + ": ") + "[sample] needs n, an integer from 1 to " +
               std::to_string(kMaxScenarios);
      return false;
    }
    spec.n = static_cast<int>(*count);
    if (const toml::node* seed = sample->get("seed")) {
      auto s = seed->value_exact<int64_t>();
      if (!s) {
        *error = Where(path, *seed) + "sample.seed must be an integer";
        return false;
      }
      spec.seed = static_cast<std::uint64_t>(*s);  // modulo 2^64, as --seed
    }
    if (!Bool(path, *sample, "latin_hypercube", &spec.latin_hypercube, error)) return false;
    if (!Distributions(path, *sample, "uniform", Distribution::Kind::Uniform, &spec, error) ||
        !Distributions(path, *sample, "normal", Distribution::Kind::Normal, &spec, error))
      return false;
    out->blocks.push_back(SampleBlock(spec));
  }
  if (const toml::array* scenarios = root["scenario"].as_array()) {
    Block b;
    std::vector<const toml::table*> tables;
    for (const toml::node& n : *scenarios) {
      const toml::table* t = n.as_table();
      if (!t) {
        *error = Where(path, n) + "scenario entries must be tables ([[scenario]])";
        return false;
      }
      tables.push_back(t);
      for (const auto& [name, v] : *t) {
        std::string k(name.str());
        if (k != "stop_time" && k != "rtol" && k != "atol" &&
            std::find(b.names.begin(), b.names.end(), k) == b.names.end())
          b.names.push_back(k);
      }
    }
    for (const toml::table* t : tables) {
      std::vector<double> row(b.names.size(), kUnset);
      RunOverride run;
      for (const auto& [name, v] : *t) {
        auto d = v.is_number() ? v.value<double>() : std::nullopt;
        if (!d || !std::isfinite(*d)) {
          *error = Where(path, v) + std::string(name.str()) + " must be a finite number";
          return false;
        }
        std::string k(name.str());
        if (k == "stop_time") run.stop_time = *d;
        else if (k == "rtol") run.rtol = *d;
        else if (k == "atol") run.atol = *d;
        else row[static_cast<size_t>(std::find(b.names.begin(), b.names.end(), k) - b.names.begin())] = *d;
      }
      b.rows.push_back(std::move(row));
      b.run.push_back(run);
    }
    out->blocks.push_back(std::move(b));
  }
  return true;
}

}  // namespace kanesim::batch
