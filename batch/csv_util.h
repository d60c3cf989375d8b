// Small CSV helpers shared by the sweep summary and the golden files (RFC 4180 quoting:
// a field with a comma, quote or line break is written in double quotes, quotes doubled).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/csv.h"

namespace kanesim::batch {

inline std::string QuoteCsv(const std::string& field) { return sim::QuoteCsvField(field); }
// Splits one line (no line breaks inside fields) into unquoted fields.
std::vector<std::string> SplitCsvLine(const std::string& line);

// Size limits of the files the batch readers take: a spec (sweep.toml, golden .toml) is
// small like a model; a list of scenarios or a stored output can be long.
inline constexpr std::uintmax_t kMaxSpecBytes = 4u << 20;    // 4 MiB
inline constexpr std::uintmax_t kMaxDataBytes = 1ull << 30;  // 1 GiB

// The whole text of a regular file of at most `max_bytes` (not a directory, a device or
// a pipe, which could block or never end); false with the reason.
bool ReadTextFile(const std::string& path, std::uintmax_t max_bytes, std::string* text, std::string* error);

// FNV-1a, 64 bits, as 16 hex digits: a change detector for provenance, not a
// cryptographic hash.
std::string Fnv1a64Hex(const std::string& bytes);

}  // namespace kanesim::batch
