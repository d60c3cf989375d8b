// Access to the standard library's .mech files (embedded at build time).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kanesim::stdlib {

struct EmbeddedFile {
  const char* name;      // "Joints.mech"
  const char* contents;  // not NUL-terminated within size
  std::size_t size;
};
extern const EmbeddedFile kEmbeddedFiles[];  // ends with {nullptr, nullptr, 0}

// The files, as (display path, contents). Display paths look like "<stdlib>/Joints.mech".
// Built on first use and kept for the process (every load reads them).
const std::vector<std::pair<std::string, std::string>>& Files();

// The image of the library's classes parsed at build time (lang::Library's constructor reads
// it; lang/library_cache.h), or empty (a fuzzing build): static, for the life of the process.
std::string_view Image();

// The source directory recorded at build time (for provenance hashes and docs checks).
const char* SourceDir();

}  // namespace kanesim::stdlib
