// Diagnostics: a stable code, a primary span, notes pointing at related places, a hint.
// User mistakes are reported here, never thrown; only `main` chooses exit codes.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "lang/source.h"
#include "flat/diagnostic_codes.h"

namespace kanesim::lang {

// The codes: flat/diagnostic_codes.h (one table with the compiler's).
using flat::DiagCode;
using flat::DiagCodeString;
using flat::DiagCodeSummary;

enum class Severity { Error, Warning };

struct DiagNote {
  Span span;
  std::string message;
};

struct Diagnostic {
  Severity severity = Severity::Error;
  DiagCode code = DiagCode::UnexpectedChar;
  std::string message;
  Span span;
  std::vector<DiagNote> notes;
  std::string hint;
};

// Output stays bounded whatever the input (limits in docs/language.md §10): at most
// kMaxErrors errors and kMaxWarnings warnings are kept (the last of each is P105), each
// renders at most kMaxNotesShown notes, and Render clips long messages and source lines
// (lang/text.h) and escapes control characters.
class Diagnostics {
 public:
  static constexpr int kMaxErrors = 50;
  static constexpr int kMaxWarnings = 50;
  static constexpr std::size_t kMaxNotesShown = 8;

  explicit Diagnostics(const SourceManager* sources) : sources_(sources) {}

  // Returns the diagnostic so callers can add notes and a hint.
  Diagnostic& Error(DiagCode code, Span span, std::string message);
  Diagnostic& Warning(DiagCode code, Span span, std::string message);

  bool HasErrors() const { return num_errors_ > 0; }
  int NumErrors() const { return num_errors_; }
  bool Full() const { return num_errors_ >= kMaxErrors; }
  const std::vector<Diagnostic>& All() const { return diags_; }
  const SourceManager& Sources() const { return *sources_; }

  // "file:line:col: error[E203]: message\n  12 | text\n     |   ^~~~\n  note: ...\n  hint: ..."
  std::string Render(const Diagnostic& d) const;
  std::string RenderAll() const;

 private:
  const SourceManager* sources_;
  std::vector<Diagnostic> diags_;
  Diagnostic overflow_;  // sink once the cap is reached
  int num_errors_ = 0;
  int num_warnings_ = 0;
};

// Renders a location snippet: the line, clipped around the span and escaped, and a caret
// line (used for compiler messages too).
std::string RenderSnippet(const SourceManager& sm, Span span);

// A note of its own, not attached to a diagnostic: "file:line:col: note: message" and the
// snippet (the URDF importer's notes on what it leaves out).
std::string RenderNote(const SourceManager& sm, Span span, const std::string& message);

// Closest candidate by edit distance, for "did you mean 'axis'?" hints; "" if none close.
std::string ClosestName(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace kanesim::lang
