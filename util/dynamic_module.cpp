#include "util/dynamic_module.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

namespace kanesim::dynamic_module {
namespace {

std::vector<std::string> Candidates(const Spec& spec) {
  if (const char* env = std::getenv(spec.env_variable); env && *env) return {env};
  std::vector<std::string> paths;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    paths.push_back((exe.parent_path() / spec.file_name).string());
#ifdef KANESIM_INSTALLED_MODULE_DIR
    paths.push_back((exe.parent_path() / KANESIM_INSTALLED_MODULE_DIR / spec.file_name).lexically_normal().string());
#endif
  }
  if (spec.build_path) paths.emplace_back(spec.build_path);
  return paths;
}

}  // namespace

bool Open(const Spec& spec, const std::function<bool(void* entry)>& accept, std::string* error) {
  std::string tried;  // "path (why), path (why)": one line, so a diagnostic can quote it
  auto note = [&tried](const std::string& path, const std::string& why) {
    tried += (tried.empty() ? " " : ", ") + path + " (" + why + ")";
  };
  for (const std::string& path : Candidates(spec)) {
    if (!std::filesystem::exists(path)) {
      note(path, "absent");
      continue;
    }
    // RTLD_LOCAL by default: the module's libraries keep their symbols to themselves.
    void* handle = dlopen(path.c_str(), RTLD_NOW | (spec.global_symbols ? RTLD_GLOBAL : RTLD_LOCAL));
    if (!handle) {
      note(path, dlerror());
      continue;
    }
    void* entry = dlsym(handle, spec.entry_point);
    if (!entry || !accept(entry)) {
      note(path, std::string("stale, or not ") + spec.what);
      dlclose(handle);
      continue;
    }
    return true;  // the handle stays open for the life of the process
  }
  if (error) *error = std::string("cannot load ") + spec.what + " " + spec.file_name + "; tried:" + tried;
  return false;
}

}  // namespace kanesim::dynamic_module
