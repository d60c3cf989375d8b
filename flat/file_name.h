// The name of a source file as a flat::SourceLoc keeps it: one pointer into a table of
// file names that lives as long as the process, so that a location costs no string of
// its own (`<stdlib>/Parts.mech` is longer than std::string's inline buffer, and every
// parameter and primitive carries a location). Equal names share one entry, so two
// FileNames are equal when their pointers are. Reads as a const std::string&.
#pragma once

#include <ostream>
#include <string>
#include <string_view>

namespace kanesim::flat {

class FileName {
 public:
  FileName() = default;
  // Looks `name` up in the process's table, adding it the first time (thread-safe).
  FileName(std::string_view name);  // NOLINT(google-explicit-constructor): `loc.file = name`
  FileName(const std::string& name) : FileName(std::string_view(name)) {}  // NOLINT
  FileName(const char* name) : FileName(std::string_view(name)) {}         // NOLINT

  const std::string& str() const { return name_ ? *name_ : Empty(); }
  operator const std::string&() const { return str(); }  // NOLINT
  bool empty() const { return name_ == nullptr; }

  friend bool operator==(const FileName& a, const FileName& b) { return a.name_ == b.name_; }
  friend bool operator==(const FileName& a, const std::string& b) { return a.str() == b; }
  friend bool operator==(const FileName& a, std::string_view b) { return a.str() == b; }
  friend bool operator==(const FileName& a, const char* b) { return a.str() == b; }
  friend std::ostream& operator<<(std::ostream& os, const FileName& f) { return os << f.str(); }

 private:
  static const std::string& Empty();
  const std::string* name_ = nullptr;  // null for "" (no file)
};

}  // namespace kanesim::flat
