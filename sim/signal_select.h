// `--output PATTERN`: globs over the dotted signal names of rt::AvailableSignals.
//
// Pattern language (deliberately small, no character classes, so that the brackets of
// array names are literal: `j[*].q` matches `j[1].q`, `j[12].q`):
//   *   any run of characters, possibly empty, including dots and brackets
//   ?   exactly one character
//   any other character matches itself (case-sensitive)
// and one alias: der(X) for X a joint speed `j.u` / `j.u[k]` or a body velocity `b.v[k]`,
// `b.w[k]` selects its derivative, `j.a`, `b.a[k]`, `b.alpha[k]` (the name written).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace kanesim::sim {

bool GlobMatch(std::string_view pattern, std::string_view name);

// The names of `available` matched by at least one pattern, in the order of `available`,
// each once. A pattern that matches nothing is a usage error: returns false and says
// which, with close names ("did you mean ...").
bool SelectSignals(const std::vector<std::string>& available, const std::vector<std::string>& patterns,
                   std::vector<std::string>* selected, std::string* error);

// `pattern` with the der() alias resolved into *canonical (the pattern itself when it is
// not one); false with a message for der() of anything else.
bool DerivativeAlias(const std::string& pattern, std::string* canonical, std::string* error);

// Up to `max_count` names of `available` closest to `pattern` (edit distance, wildcards
// ignored), closest first; only reasonably close ones.
std::vector<std::string> CloseNames(const std::vector<std::string>& available, std::string_view pattern,
                                    size_t max_count);

}  // namespace kanesim::sim
