// The importer's messages rendered as the language's diagnostics (diagnostics.h): a line and
// a needle become a one-character span of the file (the caret), which lang::Diagnostics
// locates and shows.
#include "import/diagnostics.h"

#include <algorithm>

#include "lang/diagnostics.h"

namespace kanesim::import {

namespace {

// The caret: under `needle` on `line` when the line holds it, else under its first non-blank
// character; line 0 is the file as a whole (its name, no line: lang::Span's begin -1).
lang::Span SpanAt(const lang::SourceManager& sm, int file, int line, std::string_view needle) {
  const std::int32_t start = line > 0 ? sm.Offset(file, line, 1) : -1;
  if (start < 0) return lang::Span{file, -1, -1};
  const std::string_view text = sm.LineView(file, line);
  std::size_t at = needle.empty() ? std::string_view::npos : text.find(needle);
  if (at == std::string_view::npos) at = std::min(text.find_first_not_of(" \t"), text.size());
  const auto begin = start + static_cast<std::int32_t>(at);
  return lang::Span{file, begin, begin + 1};
}

}  // namespace

RenderedMessages RenderMessages(const Diags& diags, const std::string& path, std::string_view text) {
  lang::SourceManager sm;
  const int file = sm.Add(path, std::string(text));
  lang::Diagnostics errors(&sm);
  RenderedMessages out;
  for (const ImportMessage& m : diags.Messages()) {
    const lang::Span span = SpanAt(sm, file, m.line, m.needle);
    if (m.note)
      out.notes += lang::RenderNote(sm, span, m.message);
    else
      errors.Error(m.code, span, m.message).hint = m.hint;
  }
  out.errors = errors.RenderAll();
  return out;
}

}  // namespace kanesim::import
