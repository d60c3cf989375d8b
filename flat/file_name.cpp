// The process's table of file names (flat/file_name.h).
#include "flat/file_name.h"

#include <array>
#include <cstddef>
#include <mutex>
#include <unordered_set>

namespace kanesim::flat {
namespace {

// Node-based, so the address of an entry never changes; entries are never removed (one per
// distinct file name a process has loaded).
struct Table {
  std::mutex mutex;
  std::unordered_set<std::string> names;
};

Table& TheTable() {
  static Table* table = new Table();  // never destroyed: FileNames may outlive static destructors
  return *table;
}

}  // namespace

const std::string& FileName::Empty() {
  static const std::string empty;
  return empty;
}

FileName::FileName(std::string_view name) {
  if (name.empty()) return;
  // The elaborator asks for a few names many times over (the main file and the library's
  // files, alternately): a small per-thread cache of the last entries found spares the lock.
  thread_local std::array<const std::string*, 4> recent{};
  thread_local std::size_t next = 0;
  for (const std::string* r : recent)
    if (r && *r == name) {
      name_ = r;
      return;
    }
  Table& t = TheTable();
  {
    std::lock_guard<std::mutex> lock(t.mutex);
    name_ = &*t.names.emplace(name).first;
  }
  recent[next] = name_;
  next = (next + 1) % recent.size();
}

}  // namespace kanesim::flat
