// What the FMU's C functions of every FMI version share.
#pragma once

#include <string>

namespace kanesim::fmi {

// The folder of a resource location the master gives ("file:///tmp/x/resources",
// "file:/tmp/x/resources", percent-encoded), or why it is not a local file URI.
std::string ResourceDirectory(const std::string& uri, std::string* dir);

}  // namespace kanesim::fmi
