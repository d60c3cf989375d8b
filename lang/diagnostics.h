// Diagnostics: a stable code, a primary span, notes pointing at related places, a hint.
// User mistakes are reported here, never thrown; only `main` chooses exit codes.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "lang/source.h"

namespace kanesim::lang {

// The one table of diagnostic codes: X(enumerator, "code", one-line summary).
// Codes are stable: tests and users refer to them. Add new ones at the end of a group.
#define KANESIM_DIAGNOSTICS(X)                                                                \
  /* lexer */                                                                                 \
  X(UnexpectedChar, "L001", "unexpected character")                                           \
  X(UnterminatedString, "L002", "unterminated string literal")                                \
  X(UnterminatedComment, "L003", "unterminated block comment")                                \
  X(BadNumber, "L004", "malformed number")                                                    \
  X(FileTooLarge, "L005", "file too large")                                                   \
  /* parser */                                                                                \
  X(ExpectedToken, "P101", "unexpected token")                                                \
  X(UnclosedBracket, "P102", "unclosed bracket")                                              \
  X(EndNameMismatch, "P103", "end name does not match the class name")                       \
  X(NestingTooDeep, "P104", "nesting too deep")                                               \
  X(TooManyErrors, "P105", "too many errors or warnings")                                     \
  X(ExpressionTooDeep, "P106", "expression too deep (operator chain too long)")               \
  /* elaboration */                                                                           \
  X(UnknownName, "E201", "unknown name")                                                      \
  X(UnknownClass, "E202", "unknown class")                                                    \
  X(UnknownModifier, "E203", "modifier names no element of the class")                       \
  X(TypeMismatch, "E204", "type mismatch")                                                    \
  X(SizeMismatch, "E205", "array size mismatch")                                              \
  X(FinalOverride, "E206", "modification of a final element")                                \
  X(RecursiveExtends, "E207", "recursive extends")                                            \
  X(Duplicate, "E208", "duplicate declaration")                                               \
  X(ArrayTooLarge, "E209", "array too large")                                                 \
  X(BadSet, "E210", "bad --set value")                                                        \
  X(NotParameter, "E211", "not a parameter")                                                  \
  X(BadConnect, "E212", "connect needs two frame connectors")                                 \
  X(BadValue, "E213", "parameter value out of range or not finite")                          \
  X(BadCall, "E214", "unknown function or wrong arguments")                                   \
  X(NotConstantExpr, "E215", "expression must be a parameter expression")                    \
  X(BadEquation, "E216", "equation kind not supported")                                       \
  X(WorldCount, "E217", "a mechanism needs exactly one World")                               \
  X(NotReplaceable, "E218", "redeclare of an element that is not replaceable")               \
  X(IndexOutOfRange, "E219", "index out of range")                                            \
  X(MissingValue, "E220", "parameter has no value")                                           \
  X(NotAModel, "E221", "no model to elaborate")                                               \
  X(InstanceTooLarge, "E222", "model too large")                                              \
  X(BadPrimitive, "E223", "invalid primitive declaration")                                    \
  X(PartialInstance, "E224", "instance of a partial class")                                   \
  X(BadImport, "E225", "import names nothing")                                                \
  X(ConflictingEquation, "E226", "conflicting equations")                                     \
  X(Circular, "E227", "circular definition")                                                  \
  X(WorkLimit, "E228", "elaboration exceeds its work limit")                                  \
  X(EvalTooDeep, "E229", "evaluation nested too deep")                                        \
  /* meshes (MeshBody; lang/elab_mesh.cpp) */                                                \
  X(MeshFileMissing, "E230", "mesh file not found")                                           \
  X(MeshUnreadable, "E231", "mesh file cannot be read")                                       \
  X(MeshTooLarge, "E232", "mesh over a size limit")                                           \
  X(MeshNotClosed, "E233", "mesh surface not closed")                                         \
  X(MeshOrientation, "E234", "mesh triangles inconsistently oriented")                        \
  X(MeshZeroVolume, "E235", "mesh encloses no volume")                                        \
  X(UnconnectedFrame, "W301", "frame connector is not connected")                            \
  X(MeshInsideOut, "W302", "mesh triangles face inward (flipped)")                            \
  X(MeshDegenerate, "W303", "mesh has degenerate or non-manifold parts")

enum class DiagCode {
#define KANESIM_X(e, code, summary) e,
  KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
};

const char* DiagCodeString(DiagCode c);   // "E203"
const char* DiagCodeSummary(DiagCode c);

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

// Closest candidate by edit distance, for "did you mean 'axis'?" hints; "" if none close.
std::string ClosestName(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace kanesim::lang
