#include "lang/source.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace kanesim::lang {

// A UTF-8 byte-order mark (EF BB BF) that opens a file is dropped: offsets and columns then
// count from the first character the user sees.
static std::string WithoutBom(std::string text) {
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
  return text;
}

static std::vector<std::int32_t> LineStarts(const std::string& text) {
  std::vector<std::int32_t> starts;
  starts.reserve(text.size() / 32 + 16);  // most lines are longer than 32 bytes: one allocation
  starts.push_back(0);
  const char* const begin = text.data();
  const char* const end = begin + text.size();
  for (const char* p = begin; (p = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p))));)
    starts.push_back(static_cast<std::int32_t>(++p - begin));
  return starts;
}

std::shared_ptr<const SourceFile> MakeSourceFile(std::string name, std::string contents) {
  auto f = std::make_shared<SourceFile>();
  f->name = std::move(name);
  f->text = WithoutBom(std::move(contents));
  f->line_starts = LineStarts(f->text);
  return f;
}

int SourceManager::Add(std::string name, std::string contents) {
  return AddShared(MakeSourceFile(std::move(name), std::move(contents)));
}

int SourceManager::AddShared(std::shared_ptr<const SourceFile> file) {
  files_.push_back(std::move(file));
  return static_cast<int>(files_.size() - 1);
}

void SourceManager::Replace(int file, std::string contents) {
  auto& f = files_.at(static_cast<size_t>(file));
  f = MakeSourceFile(f->name, std::move(contents));
}

void SourceManager::Truncate(int num_files) {
  if (num_files >= 0 && static_cast<size_t>(num_files) < files_.size()) files_.resize(static_cast<size_t>(num_files));
}

LineCol SourceManager::Locate(int file, std::int32_t offset) const {
  if (file < 0 || file >= NumFiles()) return {};
  const SourceFile& f = *files_[static_cast<size_t>(file)];
  auto it = std::upper_bound(f.line_starts.begin(), f.line_starts.end(), offset);
  int line = static_cast<int>(it - f.line_starts.begin());
  int col = offset - f.line_starts[static_cast<size_t>(line - 1)] + 1;
  return {line, col};
}

std::string_view SourceManager::LineView(int file, int line) const {
  if (file < 0 || file >= NumFiles()) return {};
  const SourceFile& f = *files_[static_cast<size_t>(file)];
  if (line < 1 || static_cast<size_t>(line) > f.line_starts.size()) return {};
  size_t b = static_cast<size_t>(f.line_starts[static_cast<size_t>(line - 1)]);
  size_t e = f.text.find('\n', b);
  if (e == std::string::npos) e = f.text.size();
  std::string_view s(f.text.data() + b, e - b);
  if (!s.empty() && s.back() == '\r') s.remove_suffix(1);
  return s;
}

std::string SourceManager::LineText(int file, int line) const { return std::string(LineView(file, line)); }

std::int32_t SourceManager::Offset(int file, int line, int col) const {
  if (file < 0 || file >= NumFiles()) return -1;
  const SourceFile& f = *files_[static_cast<size_t>(file)];
  if (line < 1 || static_cast<size_t>(line) > f.line_starts.size()) return -1;
  const std::int32_t begin = f.line_starts[static_cast<size_t>(line - 1)];
  const std::int32_t length = static_cast<std::int32_t>(LineView(file, line).size());
  return begin + std::clamp(col - 1, 0, length);
}

namespace {

const char* FileKind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

ReadStatus ReadSourceFile(const std::string& path, std::string* text, std::string* message) {
  // O_NONBLOCK: opening a pipe nobody writes to must not wait; cleared again below.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *message = "cannot open '" + path + "': " + std::strerror(errno);
    return ReadStatus::CannotOpen;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !(S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode))) {
    *message = "'" + path + "' is " + FileKind(st.st_mode) + ", not a model file";
    ::close(fd);
    return ReadStatus::NotAFile;
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  const auto too_large = [&] {
    *message = "'" + path + "' is larger than " + std::to_string(SourceManager::kMaxFileBytes) + " bytes";
    ::close(fd);
    return ReadStatus::TooLarge;
  };
  if (S_ISREG(st.st_mode) && static_cast<std::size_t>(st.st_size) > SourceManager::kMaxFileBytes) return too_large();
  // Read at most one byte past the limit: a pipe or a growing file is cut there. Straight
  // into the string (a buffer on the stack was a copy more and up to 16 fresh pages): a
  // regular file in one read of its size and one that sees its end.
  constexpr std::size_t kLimit = SourceManager::kMaxFileBytes + 1;
  std::size_t used = 0;
  text->resize(S_ISREG(st.st_mode) ? static_cast<std::size_t>(st.st_size) + 1 : std::size_t{1} << 16);
  while (used < kLimit) {
    if (used == text->size()) text->resize(std::min(2 * text->size(), kLimit));
    const ssize_t got = ::read(fd, text->data() + used, text->size() - used);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      *message = "cannot read '" + path + "': " + std::strerror(errno);
      ::close(fd);
      return ReadStatus::CannotOpen;
    }
    if (got == 0) break;
    used += static_cast<std::size_t>(got);
  }
  text->resize(used);
  if (used > SourceManager::kMaxFileBytes) return too_large();
  ::close(fd);
  return ReadStatus::Ok;
}

}  // namespace kanesim::lang
