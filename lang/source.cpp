#include "lang/source.h"

#include <algorithm>

namespace kanesim::lang {

int SourceManager::Add(std::string name, std::string contents) {
  File f;
  f.name = std::move(name);
  f.text = std::move(contents);
  f.line_starts.push_back(0);
  for (size_t i = 0; i < f.text.size(); ++i)
    if (f.text[i] == '\n') f.line_starts.push_back(static_cast<std::int32_t>(i + 1));
  files_.push_back(std::move(f));
  return static_cast<int>(files_.size() - 1);
}

LineCol SourceManager::Locate(int file, std::int32_t offset) const {
  if (file < 0 || file >= NumFiles()) return {};
  const File& f = files_[static_cast<size_t>(file)];
  auto it = std::upper_bound(f.line_starts.begin(), f.line_starts.end(), offset);
  int line = static_cast<int>(it - f.line_starts.begin());
  int col = offset - f.line_starts[static_cast<size_t>(line - 1)] + 1;
  return {line, col};
}

std::string SourceManager::LineText(int file, int line) const {
  if (file < 0 || file >= NumFiles()) return {};
  const File& f = files_[static_cast<size_t>(file)];
  if (line < 1 || static_cast<size_t>(line) > f.line_starts.size()) return {};
  size_t b = static_cast<size_t>(f.line_starts[static_cast<size_t>(line - 1)]);
  size_t e = f.text.find('\n', b);
  if (e == std::string::npos) e = f.text.size();
  std::string s = f.text.substr(b, e - b);
  if (!s.empty() && s.back() == '\r') s.pop_back();
  return s;
}

}  // namespace kanesim::lang
