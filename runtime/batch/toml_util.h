// Small helpers shared by the TOML readers (sweep.toml, golden specs).
#pragma once

#include <filesystem>
#include <string>
#include <toml++/toml.h>

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

}  // namespace kanesim::batch
