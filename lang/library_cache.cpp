#include "lang/library_cache.h"

#include <algorithm>
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
  for (const auto& [name, text] : files) sources.Add(name, text);
  // Largest file first: each file's token list, freed after its parse, then leaves a hole
  // that the smaller files' tokens and nodes reuse, so less fresh heap is touched.
  std::vector<int> order(files.size());
  for (size_t i = 0; i < files.size(); ++i) order[i] = static_cast<int>(i);
  auto bytes = [&](int i) { return files[static_cast<size_t>(i)].second.size(); };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return bytes(a) > bytes(b); });
  lib->defs.resize(files.size());
  for (int i : order) lib->defs[static_cast<size_t>(i)] = lang::Parse(i + 1, sources, diags);
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
