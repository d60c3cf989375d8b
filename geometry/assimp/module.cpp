// The module's entry point: the table of its functions (geometry/assimp_module.h).
#include "geometry/assimp/module.h"

namespace {

const kanesim::geometry::assimp_io::ModuleApi kApi{
    kanesim::geometry::assimp_io::kAbiVersion,
    &kanesim::geometry::assimp_io::ImportMesh,
    &kanesim::geometry::assimp_io::ExportScene,
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const kanesim::geometry::assimp_io::ModuleApi*
kanesim_geometry_assimp_api() {
  return &kApi;
}
