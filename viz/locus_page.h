// The root locus of `kanesim linearize --sweep` as one offline HTML page (page/locus.html,
// page/locus.js): the eigenvalues in the complex plane coloured by the parameter, and their
// real parts against the parameter, drawn by Debian's dygraphs read at run time and inlined.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "viz/page.h"

namespace kanesim::viz {

struct LocusData {
  std::string title;      // the page's heading
  std::string parameter;  // the swept parameter's name
  std::vector<double> values;
  std::vector<std::vector<std::complex<double>>> eigenvalues;  // one row per value, same length
};

// The page's HTML; libraries as ReadLibraries gives them (only dygraphs' are used).
std::string RenderLocusPage(const LocusData& data, const std::vector<LibraryFile>& libraries);

// Writes the page to `path` (through path.part, renamed). On failure (a missing library,
// named with its Debian package, or an unwritable file) returns false and sets *error.
bool WriteLocusHtml(const LocusData& data, const std::string& path, const std::string& js_root, std::string* error);

}  // namespace kanesim::viz
