// Located messages about a URDF file, recorded while it is read (urdf_read.cpp) and rendered
// afterwards by the language's renderer (lang/diagnostics.h) with the codes of the one table
// (flat/diagnostic_codes.h, U4xx):
// "file:line:col: error[U403]: message", the line with a caret under the element or
// attribute, a hint. expat gives lines; the column is where the named element or
// attribute (the needle) starts on that line. Internal to import/.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "flat/diagnostic_codes.h"

namespace kanesim::import {

using flat::DiagCode;

struct ImportMessage {
  bool note = false;  // a note on what is left out, else an error
  DiagCode code = DiagCode::UrdfBadXml;
  int line = 0;       // 1-based; 0: the file as a whole (its name only)
  std::string needle, message, hint;
};

// Inline, so that the reader module records into it without linking the renderer.
class Diags {
 public:
  static constexpr int kMaxErrors = 50;  // recorded; the count goes on (lang::Diagnostics caps at 50 too)
  void Error(DiagCode code, int line, std::string_view needle, std::string message, std::string hint = "") {
    if (++errors_ <= kMaxErrors)
      messages_.push_back({false, code, line, std::string(needle), std::move(message), std::move(hint)});
  }
  void Note(int line, std::string message, std::string_view needle = "") {
    messages_.push_back({true, DiagCode::UrdfBadXml, line, std::string(needle), std::move(message), ""});
  }
  int NumErrors() const { return errors_; }
  const std::vector<ImportMessage>& Messages() const { return messages_; }

 private:
  std::vector<ImportMessage> messages_;
  int errors_ = 0;
};

// The errors and, apart, the notes, rendered by lang::Diagnostics against `text` (the file's
// content, named `path`). diagnostics.cpp, on the command's side of the module boundary.
struct RenderedMessages {
  std::string errors, notes;
};
RenderedMessages RenderMessages(const Diags& diags, const std::string& path, std::string_view text);

}  // namespace kanesim::import
