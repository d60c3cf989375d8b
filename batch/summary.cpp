#include "batch/summary.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "batch/csv_util.h"
#include "batch/file_guard.h"

namespace kanesim::batch {
namespace {

bool WriteAll(int fd, const std::string& s) {
  size_t off = 0;
  while (off < s.size()) {
    ssize_t n = ::write(fd, s.data() + off, s.size() - off);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    off += static_cast<size_t>(n);
  }
  return true;
}

bool ParseId(const std::string& line, int* id) {
  size_t comma = line.find(',');
  std::string f = line.substr(0, comma);
  if (f.empty()) return false;
  char* end = nullptr;
  long v = std::strtol(f.c_str(), &end, 10);
  if (end != f.c_str() + f.size() || v < 0 || v > INT_MAX) return false;  // ids fit an int (scenario.cpp)
  *id = static_cast<int>(v);
  return true;
}

// The line with the wall_time field blanked (column index `wall`, -1: unchanged).
std::string WithoutColumn(const std::string& line, int wall) {
  if (wall < 0) return line;
  std::vector<std::string> f = SplitCsvLine(line);
  if (static_cast<size_t>(wall) < f.size()) f[static_cast<size_t>(wall)].clear();
  std::string out;
  for (size_t i = 0; i < f.size(); ++i) out.append(i ? "," : "").append(QuoteCsv(f[i]));
  return out;
}

}  // namespace

bool ReadSummary(const std::string& path, SummaryTable* out, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot read '" + path + "'";
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  *out = SummaryTable{};
  size_t pos = 0;
  bool first = true;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) break;  // torn last line
    std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (first) {
      out->header = line;
      first = false;
      continue;
    }
    if (line.empty()) continue;
    int id = 0;
    if (!ParseId(line, &id)) {
      *error = "'" + path + "': a row does not start with a scenario id: '" + line.substr(0, 40) + "'";
      return false;
    }
    out->rows[id] = line;
  }
  if (first) {
    *error = "'" + path + "' has no header";
    return false;
  }
  return true;
}

bool MergeSummaries(const std::vector<std::string>& paths, SummaryTable* out, std::string* error) {
  *out = SummaryTable{};
  int wall = -1;
  for (size_t i = 0; i < paths.size(); ++i) {
    SummaryTable t;
    if (!ReadSummary(paths[i], &t, error)) return false;
    if (i == 0) {
      out->header = t.header;
      std::vector<std::string> cols = SplitCsvLine(t.header);
      for (size_t c = 0; c < cols.size(); ++c)
        if (cols[c] == "wall_time") wall = static_cast<int>(c);
    } else if (t.header != out->header) {
      *error = "'" + paths[i] + "' has a different header than '" + paths[0] + "' (another sweep?)";
      return false;
    }
    for (auto& [id, line] : t.rows) {
      auto it = out->rows.find(id);
      if (it != out->rows.end() && WithoutColumn(it->second, wall) != WithoutColumn(line, wall)) {
        *error = "scenario " + std::to_string(id) + " differs between the inputs ('" + paths[i] + "')";
        return false;
      }
      out->rows.emplace(id, line);
    }
  }
  return true;
}

std::string FormatSummary(const SummaryTable& table) {
  std::string s = table.header + "\n";
  for (const auto& [id, line] : table.rows) s.append(line).append("\n");
  return s;
}

SummaryFile::~SummaryFile() {
  if (fd_ >= 0) ::close(fd_);
}

bool SummaryFile::Open(const std::string& path, const std::string& header, bool resume,
                       std::map<int, std::string>* done, std::string* error) {
  path_ = path;
  table_ = SummaryTable{};
  table_.header = header;
  if (resume && ::access(path.c_str(), F_OK) == 0) {
    SummaryTable old;
    if (!ReadSummary(path, &old, error)) return false;
    if (old.header != header) {
      *error = "cannot resume: '" + path + "' was written by a different sweep (its columns differ)";
      return false;
    }
    table_.rows = old.rows;
  }
  if (done) *done = table_.rows;
  // Start from exactly the complete rows (this drops a torn line), then append.
  if (!WriteFileAtomic(path, FormatSummary(table_), error)) return false;
  fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd_ < 0) {
    *error = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  return true;
}

bool SummaryFile::Append(int id, const std::string& line, std::string* error) {
  std::lock_guard<std::mutex> lock(mutex_);
  table_.rows[id] = line;
  if (!WriteAll(fd_, line + "\n") || ::fsync(fd_) != 0) {
    *error = "cannot append to '" + path_ + "': " + std::strerror(errno);
    return false;
  }
  return true;
}

bool SummaryFile::Finish(std::string* error) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  return WriteFileAtomic(path_, FormatSummary(table_), error);
}

}  // namespace kanesim::batch
