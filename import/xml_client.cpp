// ReadUrdf for the kanesim command: forwards to the URDF reader module, opened with dlopen on
// the first URDF file a process reads (import/xml_module.h).
#include <string>

#include "import/xml_module.h"
#include "util/dynamic_module.h"

namespace kanesim::import {

#ifdef KANESIM_IMPORT_XML_MODULE_PATH
static constexpr const char* kBuildPath = KANESIM_IMPORT_XML_MODULE_PATH;
#else
static constexpr const char* kBuildPath = nullptr;
#endif

bool ReadUrdf(std::string_view text, Robot* robot, Diags& diags) {
  static const auto loaded = dynamic_module::LoadTable<xml::ModuleApi>(  // once per process, thread-safe
      {"libkanesim_import_xml.so", "KANESIM_IMPORT_XML_MODULE", kBuildPath, xml::kEntryPoint, "the URDF reader library",
       false},
      xml::kAbiVersion);
  if (!loaded.api) {
    diags.Error(DiagCode::UrdfReaderMissing, 0, "", loaded.error,
                "reinstall kanesim, or set KANESIM_IMPORT_XML_MODULE to the library's path");
    return false;
  }
  return loaded.api->read_urdf(text, robot, diags);
}

}  // namespace kanesim::import
