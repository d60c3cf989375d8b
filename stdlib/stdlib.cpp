#include "stdlib/stdlib.h"

namespace kanesim::stdlib {

const std::vector<std::pair<std::string, std::string>>& Files() {
  static const std::vector<std::pair<std::string, std::string>> files = [] {
    std::vector<std::pair<std::string, std::string>> out;
    for (const EmbeddedFile* f = kEmbeddedFiles; f->name != nullptr; ++f)
      out.emplace_back(std::string("<stdlib>/") + f->name, std::string(f->contents, f->size));
    return out;
  }();
  return files;
}

const char* SourceDir() { return KANESIM_STDLIB_SOURCE_DIR; }

}  // namespace kanesim::stdlib
