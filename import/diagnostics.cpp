// Located messages about a URDF file (diagnostics.h).
#include "import/diagnostics.h"

#include <algorithm>

namespace kanesim::import {

const char* ImportCodeString(ImportCode c) {
  switch (c) {
#define KANESIM_X(e, code, summary) \
  case ImportCode::e:               \
    return code;
    KANESIM_IMPORT_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  }
  return "U400";
}

namespace {

constexpr std::size_t kMaxShown = 160;  // a longer line (or message) is clipped around the caret

// Control characters and bytes a terminal would interpret, as '?'.
std::string Printable(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 && c != '\t') c = '?';
  return out;
}

}  // namespace

Diags::Diags(std::string path, std::string_view text) : path_(std::move(path)) {
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines_.push_back(line);
    start = end + 1;
  }
}

void Diags::Add(const char* severity, const char* code, int line, std::string_view needle,
                const std::string& message, const std::string& hint, std::string* into) {
  std::string where = Printable(path_.size() > kMaxShown ? "..." + path_.substr(path_.size() - kMaxShown) : path_);
  std::string_view text;
  std::size_t col = 0;
  if (line > 0 && static_cast<std::size_t>(line) <= lines_.size()) {
    text = lines_[static_cast<std::size_t>(line) - 1];
    std::size_t at = needle.empty() ? std::string_view::npos : text.find(needle);
    if (at == std::string_view::npos) at = std::min(text.find_first_not_of(" \t"), text.size());
    col = at;
    where += ":" + std::to_string(line) + ":" + std::to_string(col + 1);
  }
  std::string head = where + ": " + severity + (*code ? std::string("[") + code + "]" : "") + ": ";
  std::string msg = message.size() > 4 * kMaxShown ? message.substr(0, 4 * kMaxShown) + "..." : message;
  *into += head + Printable(msg) + "\n";
  if (line > 0 && static_cast<std::size_t>(line) <= lines_.size()) {
    // Clip long lines (a whole URDF on one line) to a window around the caret.
    std::size_t from = col > kMaxShown / 2 ? col - kMaxShown / 2 : 0;
    std::string shown = Printable(text.substr(from, kMaxShown));
    std::string num = std::to_string(line);
    std::string marks(col - from, ' ');
    for (std::size_t i = 0; i < marks.size(); ++i)
      if (shown[i] == '\t') marks[i] = '\t';
    *into += " " + num + " | " + (from > 0 ? "..." : "") + shown + "\n " + std::string(num.size(), ' ') + " | " +
             (from > 0 ? "   " : "") + marks + "^\n";
  }
  if (!hint.empty()) *into += "  hint: " + Printable(hint) + "\n";
}

void Diags::Error(ImportCode code, int line, std::string_view needle, const std::string& message,
                  const std::string& hint) {
  ++errors_;
  if (errors_ > kMaxErrors) return;
  if (errors_ == kMaxErrors) {
    out_ += path_ + ": error: too many errors; the rest are not shown\n";
    return;
  }
  Add("error", ImportCodeString(code), line, needle, message, hint, &out_);
}

void Diags::Warning(ImportCode code, int line, std::string_view needle, const std::string& message,
                    const std::string& hint) {
  Add("warning", ImportCodeString(code), line, needle, message, hint, &out_);
}

void Diags::Note(int line, const std::string& message, std::string_view needle) {
  Add("note", "", line, needle, message, "", &notes_);
}

}  // namespace kanesim::import
