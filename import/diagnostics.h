// Located messages about a URDF file, in the form of the language's (lang/diagnostics.h):
// "file:line:col: error[U403]: message", the line with a caret under the element or attribute,
// a hint. tinyxml2 gives lines; the column is where the named element or attribute starts on
// that line. Internal to import/.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace kanesim::import {

// X(enumerator, "code", one-line summary): the importer's codes, stable (docs/import.md).
#define KANESIM_IMPORT_DIAGNOSTICS(X)                                                   \
  X(BadXml, "U401", "malformed XML")                                                   \
  X(NotUrdf, "U402", "not a URDF robot")                                               \
  X(Missing, "U403", "missing element or attribute")                                   \
  X(BadNumber, "U404", "number malformed, not finite or out of range")                 \
  X(DuplicateName, "U405", "duplicate link or joint name")                             \
  X(UnknownLink, "U406", "joint names a link that does not exist")                     \
  X(NotATree, "U407", "links and joints do not form one tree")                         \
  X(BadJointType, "U408", "unknown joint type")                                        \
  X(TooLarge, "U409", "file over a size limit")                                        \
  X(Entities, "U410", "DTD entity declarations are not read")                          \
  X(ReaderMissing, "U411", "the URDF reader library cannot be loaded")                 \
  X(MimicDropped, "W421", "mimic joint imported as an independent joint")

enum class ImportCode {
#define KANESIM_X(e, code, summary) e,
  KANESIM_IMPORT_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
};
const char* ImportCodeString(ImportCode c);

class Diags {
 public:
  Diags(std::string path, std::string_view text);
  // At `line` (1-based; 0: no location), the caret under `needle` when the line holds it.
  void Error(ImportCode code, int line, std::string_view needle, const std::string& message,
             const std::string& hint = "");
  void Warning(ImportCode code, int line, std::string_view needle, const std::string& message,
               const std::string& hint = "");
  void Note(int line, const std::string& message, std::string_view needle = "");
  int NumErrors() const { return errors_; }
  const std::string& Rendered() const { return out_; }
  const std::string& Path() const { return path_; }
  // The rendered notes, kept apart so that a caller can leave them out.
  const std::string& Notes() const { return notes_; }
  static constexpr int kMaxErrors = 50;  // then one line says how many more

 private:
  void Add(const char* severity, const char* code, int line, std::string_view needle, const std::string& message,
           const std::string& hint, std::string* into);
  std::string path_;
  std::vector<std::string_view> lines_;
  std::string out_, notes_;
  int errors_ = 0;
};

}  // namespace kanesim::import
