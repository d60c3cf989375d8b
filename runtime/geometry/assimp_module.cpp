#include "runtime/geometry/assimp_module.h"

#include "runtime/util/dynamic_module.h"

namespace kanesim::geometry::assimp_io {
namespace {

struct Loaded {
  const ModuleApi* api = nullptr;
  std::string error;
};

Loaded LoadOnce() {
  dynamic_module::Spec spec;
  spec.file_name = "libkanesim_geometry_assimp.so";
  spec.env_variable = "KANESIM_GEOMETRY_MODULE";
#ifdef KANESIM_GEOMETRY_MODULE_PATH
  spec.build_path = KANESIM_GEOMETRY_MODULE_PATH;
#else
  spec.build_path = nullptr;
#endif
  spec.entry_point = kEntryPoint;
  spec.what = "the mesh support library";
  spec.global_symbols = false;
  Loaded out;
  dynamic_module::Open(
      spec,
      [&out](void* entry) {
        const ModuleApi* api = reinterpret_cast<EntryFunction>(entry)();
        if (!api || api->abi_version != kAbiVersion) return false;
        out.api = api;
        return true;
      },
      &out.error);
  return out;
}

}  // namespace

const ModuleApi* Module(std::string* error) {
  static const Loaded loaded = LoadOnce();  // thread-safe initialisation
  if (!loaded.api && error) *error = loaded.error;
  return loaded.api;
}

}  // namespace kanesim::geometry::assimp_io
