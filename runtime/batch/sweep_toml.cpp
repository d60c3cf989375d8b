#include "runtime/batch/sweep_toml.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <toml++/toml.h>

#include "runtime/batch/toml_util.h"

#include "runtime/sim/csv.h"

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
  if (auto d = n.value<double>()) {
    out->push_back(*d);
    return true;
  }
  if (const toml::array* a = n.as_array()) {
    for (const toml::node& x : *a) {
      auto d = x.value<double>();
      if (!d) {
        *error = Where(path, x) + key + ": every element must be a number";
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
  auto d = n->value<double>();
  if (!d || !std::isfinite(*d)) {
    *error = Where(path, *n) + key + " must be a number";
    return false;
  }
  *out = *d;
  return true;
}

bool Strings(const std::string& path, const toml::table& t, const char* key, std::vector<std::string>* out,
             std::string* error) {
  const toml::node* n = t.get(key);
  if (!n) return true;
  const toml::array* a = n->as_array();
  if (!a) {
    *error = Where(path, *n) + key + " must be an array of strings";
    return false;
  }
  for (const toml::node& x : *a) {
    auto s = x.value<std::string>();
    if (!s) {
      *error = Where(path, x) + key + " must be an array of strings";
      return false;
    }
    out->push_back(*s);
  }
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
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    *error = path + ":" + std::to_string(e.source().begin.line) + ":" + std::to_string(e.source().begin.column) +
             ": " + std::string(e.description());
    return false;
  }
  *out = SweepFileSpec{};
  static const char* kKnown[] = {"model", "model_name", "set", "metrics", "start_time", "stop_time", "interval",
                                 "rtol", "atol", "integrator", "solver", "output", "trajectories", "signals",
                                 "list", "grid", "sample", "scenario"};
  for (const auto& [key, node] : root) {
    bool known = false;
    for (const char* k : kKnown) known = known || key.str() == k;
    if (!known) {
      *error = Where(path, node) + "unknown key '" + std::string(key.str()) + "'";
      return false;
    }
  }
  auto model = root["model"].value<std::string>();
  if (model) out->model = Resolve(path, *model);
  out->model_name = root["model_name"].value_or(std::string());
  out->integrator = root["integrator"].value_or(std::string());
  out->solver = root["solver"].value_or(std::string());
  if (auto o = root["output"].value<std::string>()) out->output_dir = Resolve(path, *o);
  out->trajectories = root["trajectories"].value_or(false);
  if (!Strings(path, root, "metrics", &out->metrics, error) || !Strings(path, root, "signals", &out->signals, error))
    return false;
  for (auto [key, field] : {std::pair{"start_time", &out->start_time}, {"stop_time", &out->stop_time},
                            {"interval", &out->interval}, {"rtol", &out->rtol}, {"atol", &out->atol}})
    if (!Number(path, root, key, field, error)) return false;
  if (const toml::table* set = root["set"].as_table()) {
    for (const auto& [name, v] : *set) {
      auto d = v.value<double>();
      auto b = v.is_boolean() ? v.value<bool>() : std::nullopt;
      if (b) out->sets.push_back(std::string(name.str()) + "=" + (*b ? "true" : "false"));
      else if (d) out->sets.push_back(std::string(name.str()) + "=" + sim::FormatNumber(*d));
      else if (auto s = v.value<std::string>()) out->sets.push_back(std::string(name.str()) + "=" + *s);
    }
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
  if (auto list = root["list"].value<std::string>()) {
    Block b;
    if (!ReadListCsv(Resolve(path, *list), &b, error)) return false;
    out->blocks.push_back(std::move(b));
  }
  if (const toml::table* sample = root["sample"].as_table()) {
    SampleSpec spec;
    spec.n = static_cast<int>((*sample)["n"].value_or(int64_t{0}));
    spec.seed = static_cast<std::uint64_t>((*sample)["seed"].value_or(int64_t{1}));
    spec.latin_hypercube = (*sample)["latin_hypercube"].value_or(false);
    if (spec.n <= 0) {
      *error = path + ": [sample] needs n > 0";
      return false;
    }
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
        auto d = v.value<double>();
        if (!d) {
          *error = Where(path, v) + std::string(name.str()) + " must be a number";
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
