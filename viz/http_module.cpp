#include "viz/http_module.h"

#include "util/dynamic_module.h"

namespace kanesim::viz::http {

#ifdef KANESIM_VIZ_HTTP_MODULE_PATH
static constexpr const char* kBuildPath = KANESIM_VIZ_HTTP_MODULE_PATH;
#else
static constexpr const char* kBuildPath = nullptr;
#endif

const ModuleApi* Module(std::string* error) {
  static const auto loaded = dynamic_module::LoadTable<ModuleApi>(  // once per process, thread-safe
      {"libkanesim_viz_http.so", "KANESIM_VIZ_HTTP_MODULE", kBuildPath, kEntryPoint, "the viewer's HTTP server library", false}, kAbiVersion);
  if (!loaded.api && error) *error = loaded.error;
  return loaded.api;
}

}  // namespace kanesim::viz::http
