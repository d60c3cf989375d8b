// The URDF reader module's entry point: the table of its functions (import/xml_module.h).
#include "import/xml_module.h"

namespace {

const kanesim::import::xml::ModuleApi kApi{kanesim::import::xml::kAbiVersion, &kanesim::import::ReadUrdf};

}  // namespace

extern "C" __attribute__((visibility("default"))) const kanesim::import::xml::ModuleApi* kanesim_import_xml_api() {
  return &kApi;
}
