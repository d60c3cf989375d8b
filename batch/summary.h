// The sweep summary file: a header line, then one complete line per finished scenario,
// the scenario id first.
//
// Crash safety: while a sweep runs, each finished scenario's line is appended with one
// write(2) and forced to disk with fsync(2) before the next is accepted, so an
// interrupted sweep leaves only complete lines (plus at most one torn last line, which
// readers drop). At the end the file is rewritten sorted by id through a temporary file
// and rename(2), which is atomic: a reader sees the old file or the new one, never a mix.
#pragma once

#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "batch/file_guard.h"  // WriteFileAtomic

namespace kanesim::batch {


struct SummaryTable {
  std::string header;
  std::map<int, std::string> rows;  // id -> the complete line, without '\n'
};

// Reads a summary; a last line without '\n' (torn by an interruption) is dropped.
bool ReadSummary(const std::string& path, SummaryTable* out, std::string* error);

// Joins shard summaries: same header everywhere; an id found in two files must have the
// same line apart from the wall_time column, else it is an error.
bool MergeSummaries(const std::vector<std::string>& paths, SummaryTable* out, std::string* error);

std::string FormatSummary(const SummaryTable& table);  // header + rows sorted by id

class SummaryFile {
 public:
  SummaryFile() = default;
  SummaryFile(const SummaryFile&) = delete;
  SummaryFile& operator=(const SummaryFile&) = delete;
  ~SummaryFile();

  // Starts `path` for a sweep with this header. With `resume`, an existing file with the
  // same header keeps its complete lines (returned in *done); a different header is an
  // error. Without it, any existing file is replaced.
  bool Open(const std::string& path, const std::string& header, bool resume, std::map<int, std::string>* done,
            std::string* error);
  // Appends one line (id first, no '\n') durably. Thread-safe.
  bool Append(int id, const std::string& line, std::string* error);
  // Rewrites the file sorted by id, atomically, and closes it.
  bool Finish(std::string* error);

 private:
  std::mutex mutex_;
  int fd_ = -1;
  std::string path_;
  SummaryTable table_;
};

}  // namespace kanesim::batch
