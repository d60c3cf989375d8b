#include "flat/number.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace kanesim::flat {
namespace {

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

size_t Digits(std::string_view s, size_t i) {
  while (i < s.size() && IsDigit(s[i])) ++i;
  return i;
}

std::string Quoted(std::string_view text) {
  constexpr size_t kShown = 40;  // a number is never longer; keep messages short
  std::string s(text.substr(0, kShown));
  if (text.size() > kShown) s += "...";
  return "'" + s + "'";
}

}  // namespace

size_t NumberPrefix(std::string_view s) {
  size_t i = 0;
  if (i < s.size() && IsDigit(s[i])) {
    i = Digits(s, i);
    if (i < s.size() && s[i] == '.') i = Digits(s, i + 1);
  } else if (i + 1 < s.size() && s[i] == '.' && IsDigit(s[i + 1])) {
    i = Digits(s, i + 1);
  } else {
    return 0;
  }
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    size_t j = i + 1;
    if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
    if (j >= s.size() || !IsDigit(s[j])) return i;  // "1e" or "1e+": not an exponent
    i = Digits(s, j);
  }
  return i;
}

bool ParseNumber(std::string_view text, double* value, std::string* error) {
  size_t start = (!text.empty() && (text[0] == '+' || text[0] == '-')) ? 1 : 0;
  const size_t len = NumberPrefix(text.substr(start));
  if (len == 0 || start + len != text.size()) {
    *error = Quoted(text) + " is not a number (numbers look like " + kNumberExamples + ")";
    return false;
  }
  const std::string s(text);
  errno = 0;
  const double v = std::strtod(s.c_str(), nullptr);
  if (errno == ERANGE || !std::isfinite(v)) {
    *error = Quoted(text) + (std::abs(v) > 1.0 ? " is out of range (beyond 1.8e308)"
                                                : " is too small (it underflows below 2.2e-308)");
    return false;
  }
  *value = v;
  return true;
}

bool ParseInteger(std::string_view text, long long lo, long long hi, long long* value, std::string* error) {
  size_t start = (!text.empty() && (text[0] == '+' || text[0] == '-')) ? 1 : 0;
  if (start == text.size() || Digits(text, start) != text.size()) {
    *error = Quoted(text) + " is not an integer";
    return false;
  }
  const std::string s(text);
  errno = 0;
  const long long v = std::strtoll(s.c_str(), nullptr, 10);
  if (errno == ERANGE || v < lo || v > hi) {
    *error = Quoted(text) + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    return false;
  }
  *value = v;
  return true;
}

}  // namespace kanesim::flat
