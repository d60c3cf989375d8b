// A parsed file's AST as bytes and back, spans included, so that the standard library can be
// parsed when kanesim is built and only read when it runs (lang/library_cache.h).
//
// The bytes are this build's own (written by the tool lang/tools/library_image.cpp from the
// same sources, read by the same binary): no versioning beyond a magic number, and no
// attempt to read another build's. A reader that meets anything unexpected returns null,
// and the caller parses the text instead.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include "lang/ast.h"

namespace kanesim::lang::ast {

// The deepest expression an image holds: the reader recurses, one frame per level. The
// standard library's deepest is a handful of levels.
inline constexpr int kMaxImageExprDepth = 256;

// Appends `def` to *out; false (nothing usable written) if an expression is deeper than
// kMaxImageExprDepth.
bool WriteDefinition(const StoredDefinition& def, std::string* out);

// Reads one definition written by WriteDefinition at bytes[*pos...], moving *pos past it;
// null if the bytes are not one.
std::shared_ptr<StoredDefinition> ReadDefinition(std::string_view bytes, std::size_t* pos);

}  // namespace kanesim::lang::ast
