// Small helpers shared by the TOML readers (sweep.toml, golden specs).
#pragma once

#include <cmath>
#include <filesystem>
#include <initializer_list>
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

// `text` parsed as TOML into *root; a syntax error as "path:line:column: what".
inline bool ParseTomlText(const std::string& path, const std::string& text, toml::table* root, std::string* error) {
  try {
    *root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    *error = path + ":" + std::to_string(e.source().begin.line) + ":" + std::to_string(e.source().begin.column) +
             ": " + std::string(e.description());
    return false;
  }
  return true;
}

// Every top-level key of `root` one of `known` (a misspelt key is an error, never ignored).
inline bool OnlyKnownKeys(const std::string& path, const toml::table& root, std::initializer_list<const char*> known,
                          std::string* error) {
  for (const auto& [key, node] : root) {
    bool found = false;
    for (const char* k : known) found = found || key.str() == k;
    if (!found) {
      *error = TomlWhere(path, node) + "unknown key '" + std::string(key.str()) + "'";
      return false;
    }
  }
  return true;
}

// A string-valued key: absent (*out untouched), or a string (never silently another type).
inline bool OptionalTomlString(const std::string& path, const toml::table& t, const char* key, std::string* out,
                               std::string* error) {
  const toml::node* n = t.get(key);
  if (!n) return true;
  auto s = n->value<std::string>();
  if (!s) {
    *error = TomlWhere(path, *n) + key + " must be a string";
    return false;
  }
  *out = *s;
  return true;
}

// An array of strings under `key`: absent (nothing appended), or each element a string,
// appended to *out; anything else is "<key> must be an array of <what>" at its node.
inline bool OptionalTomlStrings(const std::string& path, const toml::table& t, const char* key, const char* what,
                                std::vector<std::string>* out, std::string* error) {
  const toml::node* n = t.get(key);
  if (!n) return true;
  const toml::array* a = n->as_array();
  if (!a) {
    *error = TomlWhere(path, *n) + key + " must be an array of " + what;
    return false;
  }
  for (const toml::node& x : *a) {
    auto s = x.value<std::string>();
    if (!s) {
      *error = TomlWhere(path, x) + key + " must be an array of " + what;
      return false;
    }
    out->push_back(*s);
  }
  return true;
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
