// Source files and spans. Every phase keeps spans so that a diagnostic can point at the
// user's text, however late it is found.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace kanesim::lang {

struct Span {
  std::int32_t file = -1;  // index into SourceManager; -1 = no location
  std::int32_t begin = 0;  // byte offsets [begin, end)
  std::int32_t end = 0;
  bool valid() const { return file >= 0; }
};

struct LineCol {
  int line = 0;  // 1-based
  int col = 0;   // 1-based, in bytes
};

class SourceManager {
 public:
  // Limits on input (stated in docs/language.md).
  static constexpr std::size_t kMaxFileBytes = 4u << 20;  // 4 MiB

  int Add(std::string name, std::string contents);
  const std::string& Name(int file) const { return files_[static_cast<size_t>(file)].name; }
  const std::string& Text(int file) const { return files_[static_cast<size_t>(file)].text; }
  int NumFiles() const { return static_cast<int>(files_.size()); }
  LineCol Locate(int file, std::int32_t offset) const;
  std::string LineText(int file, int line) const;  // without newline

 private:
  struct File {
    std::string name;
    std::string text;
    std::vector<std::int32_t> line_starts;
  };
  std::vector<File> files_;
};

}  // namespace kanesim::lang
