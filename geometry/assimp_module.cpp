#include "geometry/assimp_module.h"

#include "util/dynamic_module.h"

namespace kanesim::geometry::assimp_io {

#ifdef KANESIM_GEOMETRY_MODULE_PATH
static constexpr const char* kBuildPath = KANESIM_GEOMETRY_MODULE_PATH;
#else
static constexpr const char* kBuildPath = nullptr;
#endif

const ModuleApi* Module(std::string* error) {
  static const auto loaded = dynamic_module::LoadTable<ModuleApi>(  // once per process, thread-safe
      {"libkanesim_geometry_assimp.so", "KANESIM_GEOMETRY_MODULE", kBuildPath, kEntryPoint, "the mesh support library", false}, kAbiVersion);
  if (!loaded.api && error) *error = loaded.error;
  return loaded.api;
}

}  // namespace kanesim::geometry::assimp_io
