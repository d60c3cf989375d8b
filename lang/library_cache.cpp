#include "lang/library_cache.h"

#include <mutex>

#include "lang/diagnostics.h"
#include "lang/parser.h"
#include "lang/source.h"

namespace kanesim::lang {

namespace {

std::shared_ptr<const ParsedLibrary> ParseLibrary(const std::vector<std::pair<std::string, std::string>>& files) {
  auto lib = std::make_shared<ParsedLibrary>();
  lib->files = files;
  SourceManager sources;
  sources.Add("<model>", "");  // file 0: the slot of the model being loaded
  Diagnostics diags(&sources);
  for (const auto& [name, text] : files) {
    int f = sources.Add(name, text);
    lib->defs.push_back(lang::Parse(f, sources, diags));
  }
  if (diags.HasErrors()) return nullptr;
  return lib;
}

}  // namespace

std::shared_ptr<const ParsedLibrary> SharedParsedLibrary(const std::vector<std::pair<std::string, std::string>>& files) {
  static std::mutex mutex;
  static std::shared_ptr<const ParsedLibrary> cached;
  std::lock_guard<std::mutex> lock(mutex);
  if (cached && cached->files == files) return cached;
  auto lib = ParseLibrary(files);
  if (lib) cached = lib;
  return lib;
}

}  // namespace kanesim::lang
