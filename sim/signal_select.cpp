#include "sim/signal_select.h"

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace kanesim::sim {

// Iterative glob with one backtrack point (the last `*`): linear in practice, no
// recursion, exact for patterns made of `*`, `?` and literals.
bool GlobMatch(std::string_view pattern, std::string_view name) {
  size_t p = 0, n = 0;
  size_t star = std::string_view::npos, star_n = 0;
  while (n < name.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || (pattern[p] != '*' && pattern[p] == name[n]))) {
      ++p;
      ++n;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      star_n = n;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      n = ++star_n;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

static size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::vector<std::string> CloseNames(const std::vector<std::string>& available, std::string_view pattern,
                                    size_t max_count) {
  std::string literal;
  for (char c : pattern)
    if (c != '*' && c != '?') literal += c;
  // Close: within a third of the length (at least 2 edits), or sharing the prefix up to
  // the first dot (same joint or body).
  size_t limit = std::max<size_t>(2, literal.size() / 3);
  std::string_view head = std::string_view(literal).substr(0, literal.find('.'));
  std::vector<std::pair<size_t, std::string>> scored;
  for (const std::string& name : available) {
    size_t d = EditDistance(literal, name);
    bool same_head = !head.empty() && head.size() < literal.size() && name.compare(0, head.size(), head) == 0 &&
                     name.size() > head.size() && name[head.size()] == '.';
    if (d <= limit || same_head) scored.emplace_back(d, name);
  }
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<std::string> out;
  for (size_t i = 0; i < scored.size() && i < max_count; ++i) out.push_back(scored[i].second);
  return out;
}

bool DerivativeAlias(const std::string& pattern, std::string* canonical, std::string* error) {
  *canonical = pattern;
  if (pattern.rfind("der(", 0) != 0) return true;
  const std::string inner = pattern.size() > 5 && pattern.back() == ')' ? pattern.substr(4, pattern.size() - 5) : "";
  const size_t dot = inner.rfind('.');
  const size_t bracket = inner.find('[', dot == std::string::npos ? 0 : dot);
  const std::string field = dot == std::string::npos ? "" : inner.substr(dot + 1, bracket == std::string::npos ? std::string::npos : bracket - dot - 1);
  const std::string index = bracket == std::string::npos ? "" : inner.substr(bracket);
  const char* to = field == "u" || field == "v" ? "a" : field == "w" ? "alpha" : nullptr;
  if (!to) {
    *error = "'" + pattern + "': der() selects the derivative of a joint's speed (der(j.u)) or of a body's "
             "velocity (der(b.v[k]), der(b.w[k]))";
    return false;
  }
  *canonical = inner.substr(0, dot + 1) + to + index;
  return true;
}

bool SelectSignals(const std::vector<std::string>& available, const std::vector<std::string>& given,
                   std::vector<std::string>* selected, std::string* error) {
  selected->clear();
  std::vector<std::string> patterns(given.size());
  for (size_t i = 0; i < given.size(); ++i)
    if (!DerivativeAlias(given[i], &patterns[i], error)) return false;
  for (const std::string& pattern : patterns) {
    bool any = std::any_of(available.begin(), available.end(),
                           [&](const std::string& name) { return GlobMatch(pattern, name); });
    if (any) continue;
    *error = "no output signal matches '" + pattern + "'";
    std::vector<std::string> close = CloseNames(available, pattern, 5);
    if (!close.empty()) {
      *error += "; did you mean ";
      for (size_t i = 0; i < close.size(); ++i) *error += (i ? ", '" : "'") + close[i] + "'";
      *error += "?";
    } else if (!available.empty()) {
      *error += "; available signals include ";
      for (size_t i = 0; i < available.size() && i < 6; ++i) *error += (i ? ", '" : "'") + available[i] + "'";
      if (available.size() > 6) *error += ", ...";
    }
    return false;
  }
  for (const std::string& name : available) {
    bool match = std::any_of(patterns.begin(), patterns.end(),
                             [&](const std::string& pattern) { return GlobMatch(pattern, name); });
    if (match) selected->push_back(name);
  }
  return true;
}

}  // namespace kanesim::sim
