// The standard library parsed once per process.
//
// Every load (a `kanesim run`, each scenario of a sweep that changes a structural
// parameter, every test, every fuzzer input) needs the same library ASTs. They are
// parsed on first use and shared read-only by all Programs after that, across threads.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lang/ast.h"

namespace kanesim::lang {

struct ParsedLibrary {
  std::vector<std::pair<std::string, std::string>> files;  // (display name, contents)
  // files[i] parsed as source file i + 1 (file 0 is the model being loaded).
  std::vector<std::shared_ptr<const ast::StoredDefinition>> defs;
};

// The parsed library for `files`, or null when it does not parse cleanly (the caller
// then parses it itself, so that its diagnostics reach the user). Thread-safe; the
// result stays valid while a Program holds it, even if later calls ask for other files.
std::shared_ptr<const ParsedLibrary> SharedParsedLibrary(const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace kanesim::lang
