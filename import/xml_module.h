// The boundary between the importer (kanesim_import, static) and the URDF reader module
// libkanesim_import_xml.so (urdf_read.cpp with tinyxml2), which the kanesim command opens
// with dlopen the first time it reads a URDF file. tinyxml2 is a C++ shared library that
// needs libstdc++.so; the command links the C++ runtime statically (docs/benchmarks.md,
// "Process start"), so a start that reads no URDF maps neither.
//
// Which reader a program gets is chosen when it is linked (import/CMakeLists.txt): the
// command takes this module; the Python module, the tests and the fuzzers link the reader
// directly. Both sides are built together by this project's CMake with one compiler and
// standard library, so Robot and Diags cross the boundary as C++ types; kAbiVersion guards
// against a stale module.
#pragma once

#include <string_view>

#include "import/diagnostics.h"
#include "import/urdf_model.h"

namespace kanesim::import::xml {

inline constexpr int kAbiVersion = 2;  // 2: Diags records messages (import/diagnostics.h)

struct ModuleApi {
  int abi_version;
  bool (*read_urdf)(std::string_view text, Robot* robot, Diags& diags);  // ReadUrdf (urdf_model.h)
};

// The entry point the module exports (extern "C" so that dlsym finds it by this name).
inline constexpr const char* kEntryPoint = "kanesim_import_xml_api";

}  // namespace kanesim::import::xml
