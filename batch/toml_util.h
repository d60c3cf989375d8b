// Small helpers shared by the TOML readers (sweep.toml, golden specs).
#pragma once

#include <cmath>
#include <filesystem>
#include <string>
#include <toml++/toml.h>
#include <vector>

#include "batch/csv_util.h"
#include "sim/csv.h"

namespace kanesim::batch {

// A path written in a TOML file, relative to that file's folder unless absolute.
inline std::string ResolveRelative(const std::string& base_file, const std::string& rel) {
  std::filesystem::path p(rel);
  if (p.is_absolute()) return rel;
  return (std::filesystem::path(base_file).parent_path() / p).lexically_normal().string();
}

// "file:line: " prefix for messages about a TOML node.
inline std::string TomlWhere(const std::string& path, const toml::node& n) {
  return path + ":" + std::to_string(n.source().begin.line) + ": ";
}

// `set = { name = value, ... }` (sweep and golden files) as "name=value" strings for
// --set: a finite number, a boolean, or a string (any --set value, e.g. "{0, 0, -9.81}").
inline bool ReadSetTable(const std::string& path, const toml::node& node, std::vector<std::string>* out,
                         std::string* error) {
  const toml::table* set = node.as_table();
  if (!set) {
    *error = TomlWhere(path, node) + "set must be a table: set = { name = value }";
    return false;
  }
  for (const auto& [key, v] : *set) {
    const std::string name(key.str());
    if (v.is_boolean()) {
      out->push_back(name + "=" + (*v.value<bool>() ? "true" : "false"));
    } else if (auto d = v.is_number() ? v.value<double>() : std::nullopt; d && std::isfinite(*d)) {
      out->push_back(name + "=" + sim::FormatNumber(*d));
    } else if (auto s = v.value<std::string>()) {
      out->push_back(name + "=" + *s);
    } else {
      *error = TomlWhere(path, v) + "set." + name +
               " must be a finite number, a boolean or a string (an array as a string: \"{0, 0, -9.81}\")";
      return false;
    }
  }
  return true;
}

}  // namespace kanesim::batch
