// Small CSV helpers shared by the sweep summary and the golden files (RFC 4180 quoting:
// a field with a comma, quote or line break is written in double quotes, quotes doubled).
#pragma once

#include <string>
#include <vector>

#include "runtime/sim/csv.h"

namespace kanesim::batch {

inline std::string QuoteCsv(const std::string& field) { return sim::QuoteCsvField(field); }
// Splits one line (no line breaks inside fields) into unquoted fields.
std::vector<std::string> SplitCsvLine(const std::string& line);

// FNV-1a, 64 bits, as 16 hex digits: a change detector for provenance, not a
// cryptographic hash.
std::string Fnv1a64Hex(const std::string& bytes);

}  // namespace kanesim::batch
