// Source files and spans. Every phase keeps spans so that a diagnostic can point at the
// user's text, however late it is found.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace kanesim::lang {

struct Span {
  std::int32_t file = -1;  // index into SourceManager; -1 = no location
  std::int32_t begin = 0;  // byte offsets [begin, end); begin -1: the file as a whole (no line)
  std::int32_t end = 0;
  bool valid() const { return file >= 0; }
};

struct LineCol {
  int line = 0;  // 1-based
  int col = 0;   // 1-based, in bytes
};

// One file's name, text and line starts, immutable once made. The standard library's
// files are made once per process and shared by every SourceManager (AddShared), so a
// load neither copies their text nor recomputes their line starts.
struct SourceFile {
  std::string name;
  std::string text;
  std::vector<std::int32_t> line_starts;
};
// A UTF-8 byte-order mark opening `contents` is dropped, as by SourceManager::Add.
std::shared_ptr<const SourceFile> MakeSourceFile(std::string name, std::string contents);

class SourceManager {
 public:
  // Limits on input (stated in docs/language.md).
  static constexpr std::size_t kMaxFileBytes = 4u << 20;  // 4 MiB

  // A UTF-8 byte-order mark opening `contents` is dropped (offsets count from after it).
  int Add(std::string name, std::string contents);
  int AddShared(std::shared_ptr<const SourceFile> file);
  // For a long-lived driver that parses the standard library once and reuses it (the
  // fuzzers): gives file `file` new contents, or drops every file from `num_files` on.
  void Replace(int file, std::string contents);
  void Truncate(int num_files);
  const std::string& Name(int file) const { return files_[static_cast<size_t>(file)]->name; }
  const std::string& Text(int file) const { return files_[static_cast<size_t>(file)]->text; }
  int NumFiles() const { return static_cast<int>(files_.size()); }
  LineCol Locate(int file, std::int32_t offset) const;
  std::string LineText(int file, int line) const;  // without newline
  std::string_view LineView(int file, int line) const;  // the same, without a copy
  // Byte offset of 1-based (line, col), clamped to the file; -1 if there is no such line.
  std::int32_t Offset(int file, int line, int col) const;

 private:
  std::vector<std::shared_ptr<const SourceFile>> files_;
};

// Reads a model file for SourceManager::Add: a regular file, or a pipe read to its end,
// of at most kMaxFileBytes. A directory, device or socket is refused with a message that
// says what the path is; so is a file that cannot be opened (with the system's reason).
enum class ReadStatus { Ok, CannotOpen, NotAFile, TooLarge };
ReadStatus ReadSourceFile(const std::string& path, std::string* text, std::string* message);

}  // namespace kanesim::lang
