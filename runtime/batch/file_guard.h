// Guards for the files kanesim writes (docs/sweeps.md "Output directory", docs/golden_tests.md):
// - an output is never one of the command's inputs: compared by device and inode, so a
//   hard link, a symbolic link or another spelling of the same path is caught too;
// - temporary files are named <target>.tmp.<host>.<pid>, so the ones a killed process
//   left behind are recognizably ours and removed by the next run on the same machine
//   (only when that process no longer runs);
// - a file being written by one process is locked (flock(2)), so a second process that
//   would write it at the same time is refused instead of losing rows. The lock ends with
//   the process, so a killed run leaves no stale lock.
#pragma once

#include <string>
#include <vector>

namespace kanesim::batch {

// True when both paths name the same existing file (same device and inode).
bool SameFile(const std::string& a, const std::string& b);

// The first of `inputs` that writing `output` would overwrite ("" if none).
std::string OverwrittenInput(const std::string& output, const std::vector<std::string>& inputs);

// The temporary file through which `target` is written.
std::string TempPathFor(const std::string& target);

// Removes the temporaries of `target` (TempPathFor, or the older <target>.tmp.<pid>) whose
// process, on this machine, no longer runs. Returns how many were removed.
int RemoveStaleTemps(const std::string& target);
// The same for every file in `dir` ("*.tmp.<host>.<pid>", "*.tmp.<pid>").
int RemoveStaleTempsIn(const std::string& dir);

// An exclusive advisory lock on `path` (created if missing), held until destruction.
class FileLock {
 public:
  FileLock() = default;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  ~FileLock();
  // False when another process holds it: *error names `what`, and that process when known.
  bool Acquire(const std::string& path, const std::string& what, std::string* error);
  // The descriptor (the locked file itself may be the output: run -o).
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

}  // namespace kanesim::batch
