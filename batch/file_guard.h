// Guards for the files kanesim writes (docs/sweeps.md "Output directory", docs/golden_tests.md):
// - an output is never one of the command's inputs: compared by device and inode, so a
//   hard link, a symbolic link or another spelling of the same path is caught too;
// - temporary files are named <target>.tmp.<host>.<pid>, so the ones a killed process
//   left behind are recognizably ours and removed by the next run on the same machine
//   (only when that process no longer runs);
// - a file being written by one process is locked (flock(2)), so a second process that
//   would write it at the same time is refused instead of losing rows. The lock ends with
//   the process, so a killed run leaves no stale lock.
// - a file is replaced only through a temporary beside it, flushed to disk and renamed
//   over it (AtomicFile, WriteFileAtomic): a full disk, a kill or a crash leaves the old
//   contents or the new ones, never a torn mix; and only a regular file is replaced (a
//   FIFO, a device, a directory or a socket named as the target is refused: renaming over
//   it would destroy it).
#pragma once

#include <cstdio>
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

// "" when `path` is absent or a regular file (through symbolic links), else what it is
// ("a FIFO (named pipe)", "a character device", "a directory", ...).
std::string NotRegularFile(const std::string& path);

// The file a write to `path` replaces: `path`, or the file its symbolic link(s) name (so
// the link stays a link and its target gets the new contents).
std::string ReplacedFile(const std::string& path);

// One file written through a temporary beside its target:
//   AtomicFile f; f.Open(target, &err); write to f.file(); f.Commit(&err);
// Open refuses a target that exists and is not a regular file; Commit flushes, fsyncs,
// renames over the target (keeping an existing target's permissions) and fsyncs the
// folder. Destroyed without Commit (an error, an exception), the temporary is removed and
// the target is untouched. A killed process leaves the temporary, named TempPathFor(target),
// which RemoveStaleTemps removes later.
class AtomicFile {
 public:
  AtomicFile() = default;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();
  bool Open(const std::string& target, std::string* error);
  std::FILE* file() const { return file_; }
  const std::string& temp_path() const { return temp_; }
  bool Commit(std::string* error);
  void Abandon();  // remove the temporary; the target stays as it was

 private:
  std::FILE* file_ = nullptr;
  std::string target_, temp_;
};

// `contents` into `path` through an AtomicFile.
bool WriteFileAtomic(const std::string& path, const std::string& contents, std::string* error);

// The temporary made by Commit's rename durable: fsync of the folder holding `path`.
void SyncParentDir(const std::string& path);

// An exclusive advisory lock on `path` (created if missing), held until destruction.
class FileLock {
 public:
  FileLock() = default;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  ~FileLock();
  // False when another process holds it: *error names `what`, and that process when known.
  // `remove_at_end`: `path` is a lock file of its own (not the output), removed when the
  // lock ends normally (a killed process leaves it, empty and unlocked). Safe against a
  // second process that opened the file just before: it checks, once it holds the lock,
  // that the path still names the file it locked, and starts over if not.
  bool Acquire(const std::string& path, const std::string& what, std::string* error, bool remove_at_end = false);
  // The descriptor (the locked file itself may be the output: run -o).
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::string remove_;  // the lock file to remove at the end, or ""
};

}  // namespace kanesim::batch
