// The layer fmi/ (kanesim_fmi): a model as a Functional Mock-up Unit (FMI 2.0 and 3.0; docs/fmi.md).
// `kanesim export` calls ExportFmu; the FMU's own library (kanesim_fmu, built from this
// folder's fmi2_api.cpp and instance.cpp) loads the model text the FMU carries and runs it.
#pragma once

#include <string>
#include <vector>

#include "fmi/variables.h"  // the variables an FMU shows, and their value references
#include "pipeline/pipeline.h"

namespace kanesim::fmi {

struct ExportOptions {
  int version = 2;                // FMI 2.0 or 3.0
  bool model_exchange = true;     // the interfaces in the FMU
  bool co_simulation = true;
  std::string output;             // the .fmu file
  std::string model;              // the class exported ("" = the last model of the file)
  std::vector<std::string> sets;  // --set values, fixed into the FMU
  std::string integrator;         // Co-Simulation's integrator ("" = the compiler's choice)
  // The folder holding the FMU's library (kanesim_fmu.so) and the shared libraries it
  // needs besides the system's; "" = found beside the kanesim executable (FmuBinariesDir).
  std::string binaries_dir;
};

// The modelDescription.xml of `model` (loaded and compiled with the options' sets), FMI 2.0
// and 3.0 (`token`: the instantiationToken).
std::string ModelDescription(const pipeline::Model& model, const ExportOptions& options, const std::string& guid);
std::string ModelDescription3(const pipeline::Model& model, const ExportOptions& options, const std::string& token);

// Writes the FMU: modelDescription.xml, binaries/<platform>/<id>.so with the libraries it
// needs, resources/model.mech (`model_text`, the main file) and resources/settings.txt.
// "" or why not.
std::string ExportFmu(const pipeline::Model& model, const std::string& model_text, const ExportOptions& options);

// Where the FMU's library is: $KANESIM_FMU_DIR, <exe>/../<libdir>/kanesim/fmu (installed), or
// the build tree's folder; "" and *error when none holds kanesim_fmu.so.
std::string FmuBinariesDir(std::string* error);

}  // namespace kanesim::fmi
