// The viewer page's own files (viz/page/), embedded at build time by cmake/embed_files.cmake.
#pragma once

#include <cstddef>
#include <string_view>

namespace kanesim::viz {

struct PageFile {
  const char* name;  // file name in viz/page/, e.g. "viewer.js"
  const char* data;  // contents (not NUL-terminated in general)
  size_t size;       // bytes
};

// All files, ended by an entry whose name is null (generated page_files.cpp).
extern const PageFile kPageFiles[];

// The contents of one file; throws std::logic_error when it was not embedded (a build bug).
std::string_view PageFileText(std::string_view name);

}  // namespace kanesim::viz
