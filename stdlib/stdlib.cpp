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

extern const unsigned char kImage[];  // stdlib_image.cpp, written at build time
extern const std::size_t kImageSize;

std::string_view Image() { return {reinterpret_cast<const char*>(kImage), kImageSize}; }

const char* SourceDir() { return KANESIM_STDLIB_SOURCE_DIR; }

}  // namespace kanesim::stdlib
