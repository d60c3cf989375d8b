#include "fmi/fmu_common.h"

#include <cctype>
#include <cstdlib>

namespace kanesim::fmi {

std::string ResourceDirectory(const std::string& uri, std::string* dir) {
  std::string path;
  if (uri.rfind("file://", 0) == 0) {
    path = uri.substr(7);
    if (path.rfind("localhost/", 0) == 0) path = path.substr(9);
  } else if (uri.rfind("file:", 0) == 0) {
    path = uri.substr(5);
  } else {
    return "the resource location '" + uri + "' is not a file URI";
  }
  if (path.empty() || path[0] != '/') return "the resource location '" + uri + "' is not an absolute file URI";
  dir->clear();
  for (size_t i = 0; i < path.size(); ++i) {
    if (path[i] == '%' && i + 2 < path.size() && std::isxdigit(static_cast<unsigned char>(path[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(path[i + 2]))) {
      *dir += char(std::strtol(path.substr(i + 1, 2).c_str(), nullptr, 16));
      i += 2;
    } else {
      *dir += path[i];
    }
  }
  while (dir->size() > 1 && dir->back() == '/') dir->pop_back();
  return "";
}

}  // namespace kanesim::fmi
