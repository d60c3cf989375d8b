// Elaboration: from parsed files to the flat mechanism. Instantiates the chosen model,
// merges modifiers (outer wins; overriding a final element is an error naming both
// places), handles extends, replaceable/redeclare, arrays and `each`, conditional
// components, for/if equations, evaluates parameters (with --set overrides,
// type-checked), checks types and array sizes, and resolves connect() into frames.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "flat/mechanism.h"

namespace kanesim::lang {

class Library;  // lang/library_cache.h

// Limits (stated in docs/language.md): exceeding one is a clean error, never a hang.
inline constexpr long kMaxArraySize = 100000;        // elements in one array
inline constexpr long kMaxInstances = 600000;        // scalar variables + components
inline constexpr int kMaxExtendsDepth = 64;          // chain of extends / instantiation depth
// Steps of one elaboration: values produced by evaluating expressions, loop iterations,
// multiply-adds of matrix products (lang/elab_budget.h).
inline constexpr long kMaxElabWork = 10000000;
// Expression nodes one elaboration may make (the memory it may take: ~33 bytes each,
// lang/elab_budget.cpp ChargeNodes); the 10 000-link chain makes 860 000, 123 000 scalar
// parameters 250 000. At the limit a check peaks near 380 MB.
inline constexpr long kMaxExprNodes = 5000000;
// Nested evaluation: sub-expressions inside brackets, calls and if-expressions, plus
// parameters whose value reads another parameter. Operator chains (a + b + ...) do not
// count: they are evaluated without recursion, at any length. A thread with a small
// stack stops earlier (at half of the stack it has left), with the same diagnostic.
inline constexpr int kMaxEvalDepth = 1000;

struct ParamOverride {
  std::string name;   // dotted: "N", "rod.L", "world.g" or "world.g[2]"
  std::string value;  // text, parsed as a .mech expression
};

struct ElaborateOptions {
  std::string model;  // qualified class name; "" = the last model of the main file
  std::vector<ParamOverride> overrides;
  // The unit check (lang/elab_units.h) always runs; bench/units_cost.cpp turns it off to
  // measure its cost side by side. Nothing else does.
  bool check_units = true;
  // The data files (meshes) read from elsewhere: the path the model names (resolved, as
  // flat::Mechanism::data_files lists it) -> the file to read. When given, a file it does
  // not list is an error (an FMU reads only what it carries). Null: read the paths named.
  const std::map<std::string, std::string>* data_files = nullptr;
  // The process ends soon after (a command-line `check` or `run`): the instance tree and the
  // phases' caches are left to the exit instead of freed node by node (6-7 % of a robot's
  // front end), reachable from a static so that leak checkers do not count them. Never in a
  // process that elaborates again and again (a sweep, Python): each would stay.
  bool leave_to_exit = false;
  // Scalar components of one class side by side, modified alike, copy the first one's
  // instance tree when that is provably the same (lang/elab_share.cpp). Off only in the
  // tests that compare with instantiating each (tests/elab/sibling_share_test.cpp).
  bool share_siblings = true;
};

// Parsed program: the user's file(s) plus the standard library.
struct Program {
  // mutable: elaboration adds the text of --set values so diagnostics can show them.
  mutable SourceManager sources;
  // files[0] is the main file. The standard library's files are either in `files` too
  // (parsed for this Program), or, for the embedded library, in `library`: parsed one
  // class at a time when elaboration first looks its name up, and shared with every other
  // Program of the process (lang/library_cache.h). Either way they are source files 1...
  std::vector<std::shared_ptr<const ast::StoredDefinition>> files;
  std::shared_ptr<const Library> library;
};

// Loads and parses the main file and the standard library; diagnostics into `diags`.
// `stdlib_files` are (display name, contents) pairs; they are parsed once per process, or read
// from `stdlib_image` (their units parsed at build time, Library::Image(); stdlib::Image()).
bool LoadProgram(const std::string& path, const std::vector<std::pair<std::string, std::string>>& stdlib_files,
                 Program* program, Diagnostics& diags, std::string_view stdlib_image = {});
// Same, with the main file's text given (tests, fuzzer).
bool LoadProgramFromText(const std::string& name, const std::string& text,
                         const std::vector<std::pair<std::string, std::string>>& stdlib_files, Program* program,
                         Diagnostics& diags, std::string_view stdlib_image = {});

bool Elaborate(const Program& program, const ElaborateOptions& options, flat::Mechanism* out, Diagnostics& diags);

// Lists the instantiable (non-partial) models of the standard library, qualified.
std::vector<std::string> StdlibModels(const Program& program);

}  // namespace kanesim::lang
