#include "batch/file_guard.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <signal.h>

namespace kanesim::batch {
namespace {

std::string HostName() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0 || buf[0] == '\0') return "localhost";
  std::string h(buf);
  for (char& c : h)
    if (c == '/' || c == '.') c = '_';  // one path component, and '.' separates the pid
  return h;
}

bool AllDigits(const std::string& s) {
  if (s.empty() || s.size() > 9) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

// The pid of a temporary name's tail "<host>.<pid>" or "<pid>" when it is ours to judge
// (this machine), else 0.
long OwnPid(const std::string& tail, const std::string& host) {
  if (AllDigits(tail)) return std::stol(tail);
  size_t dot = tail.rfind('.');
  if (dot == std::string::npos || tail.substr(0, dot) != host || !AllDigits(tail.substr(dot + 1))) return 0;
  return std::stol(tail.substr(dot + 1));
}

bool Running(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

// Removes `entry` when its name is <prefix>.tmp.<tail> with a dead pid of this machine.
bool RemoveIfStale(const std::filesystem::path& entry, const std::string& prefix, const std::string& host) {
  const std::string name = entry.filename().string();
  const std::string marker = ".tmp.";
  size_t at = prefix.empty() ? name.rfind(marker) : prefix.size();
  if (at == std::string::npos || name.compare(0, at, prefix.empty() ? name.substr(0, at) : prefix) != 0 ||
      name.compare(at, marker.size(), marker) != 0)
    return false;
  const long pid = OwnPid(name.substr(at + marker.size()), host);
  if (pid == 0 || pid == static_cast<long>(::getpid()) || Running(pid)) return false;
  std::error_code ec;
  return std::filesystem::remove_all(entry, ec) > 0;  // a folder: an animation's (cli/animation.cpp)
}

bool WriteAll(std::FILE* f, const std::string& s) { return std::fwrite(s.data(), 1, s.size(), f) == s.size(); }

}  // namespace

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

std::string OverwrittenInput(const std::string& output, const std::vector<std::string>& inputs) {
  for (const std::string& in : inputs)
    if (!in.empty() && SameFile(output, in)) return in;
  return "";
}

std::string TempPathFor(const std::string& target) {
  return target + ".tmp." + HostName() + "." + std::to_string(::getpid());
}

int RemoveStaleTemps(const std::string& target) {
  const std::filesystem::path t(target);
  const std::filesystem::path dir = t.has_parent_path() ? t.parent_path() : std::filesystem::path(".");
  const std::string prefix = t.filename().string(), host = HostName();
  std::error_code ec;
  int removed = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().filename().string().starts_with(prefix + ".tmp.")) removed += RemoveIfStale(e.path(), prefix, host);
  return removed;
}

int RemoveStaleTempsIn(const std::string& dir) {
  const std::string host = HostName();
  std::error_code ec;
  int removed = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) removed += RemoveIfStale(e.path(), "", host);
  return removed;
}

std::string NotRegularFile(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return "";  // absent (or a dangling link: written through)
  switch (st.st_mode & S_IFMT) {
    case S_IFREG: return "";
    case S_IFIFO: return "a FIFO (named pipe)";
    case S_IFCHR: return "a character device";
    case S_IFBLK: return "a block device";
    case S_IFDIR: return "a directory";
    case S_IFSOCK: return "a socket";
    default: return "not a regular file";
  }
}

std::string ReplacedFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_symlink(std::filesystem::symlink_status(path, ec))) return path;
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(path, ec);
  return ec ? path : resolved.string();
}

void SyncParentDir(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string dir = p.has_parent_path() ? p.parent_path().string() : ".";
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);  // best effort: some file systems refuse fsync on a folder
  ::close(fd);
}

AtomicFile::~AtomicFile() { Abandon(); }

void AtomicFile::Abandon() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
}

bool AtomicFile::Open(const std::string& target, std::string* error) {
  Abandon();
  if (std::string what = NotRegularFile(target); !what.empty()) {
    *error = "'" + target + "' is " + what + ", not a regular file; kanesim replaces only regular files " +
             "(renaming over it would destroy it): choose another path";
    return false;
  }
  target_ = ReplacedFile(target);
  // A read-only file stays read-only: the rename would replace it where open(2) would not.
  if (::access(target_.c_str(), F_OK) == 0 && ::access(target_.c_str(), W_OK) != 0) {
    *error = "cannot write '" + target + "': " + std::strerror(errno);
    return false;
  }
  const std::string temp = TempPathFor(target_);
  int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);  // a new file: the umask applies
  if (fd < 0) {
    *error = "cannot write '" + temp + "': " + std::strerror(errno);
    return false;
  }
  struct stat st;
  if (::stat(target_.c_str(), &st) == 0) ::fchmod(fd, st.st_mode & 07777);  // a replaced file keeps its permissions
  temp_ = temp;
  file_ = ::fdopen(fd, "w");
  if (!file_) {
    *error = "cannot write '" + temp + "': " + std::strerror(errno);
    ::close(fd);
    Abandon();
    return false;
  }
  return true;
}

bool AtomicFile::Commit(std::string* error) {
  if (!file_) {
    *error = "cannot write '" + target_ + "': not open";
    return false;
  }
  // A full disk shows at the latest here: in fflush, in fsync (delayed allocation) or in
  // close (NFS); any of them keeps the old target.
  errno = 0;
  bool ok = std::fflush(file_) == 0 && !std::ferror(file_) && ::fsync(::fileno(file_)) == 0;
  int err = ok ? 0 : errno;
  if (std::fclose(file_) != 0 && ok) ok = false, err = errno;
  file_ = nullptr;
  if (ok && ::rename(temp_.c_str(), target_.c_str()) != 0) ok = false, err = errno;
  if (err == 0) err = EIO;
  if (!ok) {
    *error = "cannot write '" + target_ + "': " + std::strerror(err) + "; the previous file, if any, is unchanged";
    Abandon();
    return false;
  }
  temp_.clear();
  SyncParentDir(target_);
  return true;
}

bool WriteFileAtomic(const std::string& path, const std::string& contents, std::string* error) {
  AtomicFile f;
  if (!f.Open(path, error)) return false;
  if (!WriteAll(f.file(), contents)) {
    *error = "cannot write '" + path + "': " + std::strerror(errno) + "; the previous file, if any, is unchanged";
    return false;
  }
  return f.Commit(error);
}

FileLock::~FileLock() {
  if (!remove_.empty()) ::unlink(remove_.c_str());  // still locked: nobody holds this name meanwhile
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the lock
}

bool FileLock::Acquire(const std::string& path, const std::string& what, std::string* error, bool remove_at_end) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
      *error = "cannot open '" + path + "': " + std::strerror(errno);
      return false;
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      ::close(fd);
      *error = err == EWOULDBLOCK ? "another kanesim process is writing " + what +
                                        "; wait for it to finish or choose another output"
                                  : "cannot lock '" + path + "': " + std::strerror(err);
      return false;
    }
    // A lock file removed by its previous holder after we opened it: ours is an orphan
    // that a third process would not see. Start over with the name's current file.
    struct stat held, named;
    if (remove_at_end && (::fstat(fd, &held) != 0 || ::stat(path.c_str(), &named) != 0 ||
                          held.st_dev != named.st_dev || held.st_ino != named.st_ino)) {
      ::close(fd);
      continue;
    }
    fd_ = fd;
    if (remove_at_end) remove_ = path;
    return true;
  }
  *error = "cannot lock '" + path + "': it keeps being replaced";
  return false;
}

}  // namespace kanesim::batch
