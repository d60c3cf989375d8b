// Unit strings (lang/units.h): a recursive-descent parser over the grammar there, a table
// of symbols and a table of prefixes.
#include "lang/units.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

namespace kanesim::lang {

namespace {

// One symbol: its scale to the coherent SI unit and its exponents of m, kg, s, A, K, mol,
// cd, rad.
struct Symbol {
  std::string_view name;
  double scale;
  std::array<std::int8_t, Unit::kBase> exp;
};

constexpr double kPi = std::numbers::pi;

// Modelica's SI units (Modelica.Units.SI) and the non-SI ones its models use.
constexpr Symbol kSymbols[] = {
    {"m", 1, {1, 0, 0, 0, 0, 0, 0, 0}},       {"g", 1e-3, {0, 1, 0, 0, 0, 0, 0, 0}},
    {"s", 1, {0, 0, 1, 0, 0, 0, 0, 0}},       {"A", 1, {0, 0, 0, 1, 0, 0, 0, 0}},
    {"K", 1, {0, 0, 0, 0, 1, 0, 0, 0}},       {"mol", 1, {0, 0, 0, 0, 0, 1, 0, 0}},
    {"cd", 1, {0, 0, 0, 0, 0, 0, 1, 0}},      {"rad", 1, {0, 0, 0, 0, 0, 0, 0, 1}},
    {"sr", 1, {0, 0, 0, 0, 0, 0, 0, 2}},      {"deg", kPi / 180, {0, 0, 0, 0, 0, 0, 0, 1}},
    {"rev", 2 * kPi, {0, 0, 0, 0, 0, 0, 0, 1}}, {"Hz", 1, {0, 0, -1, 0, 0, 0, 0, 0}},
    {"N", 1, {1, 1, -2, 0, 0, 0, 0, 0}},      {"Pa", 1, {-1, 1, -2, 0, 0, 0, 0, 0}},
    {"J", 1, {2, 1, -2, 0, 0, 0, 0, 0}},      {"W", 1, {2, 1, -3, 0, 0, 0, 0, 0}},
    {"C", 1, {0, 0, 1, 1, 0, 0, 0, 0}},       {"V", 1, {2, 1, -3, -1, 0, 0, 0, 0}},
    {"F", 1, {-2, -1, 4, 2, 0, 0, 0, 0}},     {"Ohm", 1, {2, 1, -3, -2, 0, 0, 0, 0}},
    {"S", 1, {-2, -1, 3, 2, 0, 0, 0, 0}},     {"Wb", 1, {2, 1, -2, -1, 0, 0, 0, 0}},
    {"T", 1, {0, 1, -2, -1, 0, 0, 0, 0}},     {"H", 1, {2, 1, -2, -2, 0, 0, 0, 0}},
    {"degC", 1, {0, 0, 0, 0, 1, 0, 0, 0}},    {"lm", 1, {0, 0, 0, 0, 0, 0, 1, 2}},
    {"lx", 1, {-2, 0, 0, 0, 0, 0, 1, 2}},     {"Bq", 1, {0, 0, -1, 0, 0, 0, 0, 0}},
    {"Gy", 1, {2, 0, -2, 0, 0, 0, 0, 0}},     {"Sv", 1, {2, 0, -2, 0, 0, 0, 0, 0}},
    {"kat", 1, {0, 0, -1, 0, 0, 1, 0, 0}},    {"min", 60, {0, 0, 1, 0, 0, 0, 0, 0}},
    {"h", 3600, {0, 0, 1, 0, 0, 0, 0, 0}},    {"d", 86400, {0, 0, 1, 0, 0, 0, 0, 0}},
    {"l", 1e-3, {3, 0, 0, 0, 0, 0, 0, 0}},    {"L", 1e-3, {3, 0, 0, 0, 0, 0, 0, 0}},
    {"bar", 1e5, {-1, 1, -2, 0, 0, 0, 0, 0}}, {"t", 1e3, {0, 1, 0, 0, 0, 0, 0, 0}},
};

struct Prefix {
  std::string_view name;
  double scale;
};

// "u" stands for micro as in Modelica; "µ" may be the micro sign (U+00B5) or the Greek mu (U+03BC).
constexpr Prefix kPrefixes[] = {
    {"Y", 1e24}, {"Z", 1e21}, {"E", 1e18}, {"P", 1e15},  {"T", 1e12},       {"G", 1e9},        {"M", 1e6},
    {"k", 1e3},  {"h", 1e2},  {"da", 1e1}, {"d", 1e-1},  {"c", 1e-2},       {"m", 1e-3},       {"u", 1e-6},
    {"\xC2\xB5", 1e-6},       {"\xCE\xBC", 1e-6},        {"n", 1e-9},       {"p", 1e-12},      {"f", 1e-15},
    {"a", 1e-18}, {"z", 1e-21}, {"y", 1e-24},
};

const Symbol* FindSymbol(std::string_view name) {
  for (const Symbol& s : kSymbols)
    if (s.name == name) return &s;
  return nullptr;
}

Unit FromSymbol(const Symbol& s, double prefix) {
  Unit u;
  for (int i = 0; i < Unit::kBase; ++i) u.twice[static_cast<size_t>(i)] = static_cast<std::int16_t>(2 * s.exp[static_cast<size_t>(i)]);
  u.scale = s.scale * prefix;
  return u;
}

// A symbol written whole wins over a prefixed reading ("min" is the minute, "cd" the candela).
bool ResolveOperand(std::string_view word, Unit* out) {
  if (const Symbol* s = FindSymbol(word)) {
    *out = FromSymbol(*s, 1);
    return true;
  }
  for (const Prefix& p : kPrefixes) {
    if (word.size() <= p.name.size() || word.substr(0, p.name.size()) != p.name) continue;
    if (const Symbol* s = FindSymbol(word.substr(p.name.size()))) {
      *out = FromSymbol(*s, p.scale);
      return true;
    }
  }
  return false;
}

class UnitParser {
 public:
  explicit UnitParser(std::string_view t) : t_(t) {}

  bool Parse(Unit* out, std::string* error) {
    if (!Expression(out, 0) || i_ != t_.size()) {
      if (error_.empty()) error_ = "unexpected '" + std::string(1, t_[i_]) + "'";
      *error = error_ + " at character " + std::to_string(i_ + 1);
      return false;
    }
    return true;
  }

 private:
  static constexpr int kMaxDepth = 16;  // parentheses nested deeper are refused, not recursed into

  bool Fail(const char* what) {
    if (error_.empty()) error_ = what;
    return false;
  }
  bool At(char c) const { return i_ < t_.size() && t_[i_] == c; }
  static bool WordByte(unsigned char c) { return std::isalpha(c) || c >= 0x80; }

  // unit_expression := numerator { "/" denominator }
  bool Expression(Unit* out, int depth) {
    if (depth > kMaxDepth) return Fail("parentheses nested too deep");
    if (!Numerator(out, depth)) return false;
    while (At('/')) {
      ++i_;
      Unit d;
      if (At('(')) {
        if (!Group(&d, depth)) return false;
      } else if (!Factor(&d)) {
        return false;
      }
      *out = *out / d;
    }
    return true;
  }

  // numerator := "1" | "(" expression ")" | factor { "." factor }
  bool Numerator(Unit* out, int depth) {
    if (At('1') && (i_ + 1 == t_.size() || t_[i_ + 1] == '/' || t_[i_ + 1] == ')')) {
      ++i_;
      *out = Unit::One();
      return true;
    }
    if (At('(')) return Group(out, depth);
    if (!Factor(out)) return false;
    while (At('.')) {
      ++i_;
      Unit f;
      if (!Factor(&f)) return false;
      *out = *out * f;
    }
    return true;
  }

  bool Group(Unit* out, int depth) {
    ++i_;
    if (!Expression(out, depth + 1)) return false;
    if (!At(')')) return Fail("expected ')'");
    ++i_;
    return true;
  }

  // factor := operand [ ["+" | "-"] digits ]
  bool Factor(Unit* out) {
    size_t b = i_;
    while (i_ < t_.size() && WordByte(static_cast<unsigned char>(t_[i_]))) ++i_;
    if (i_ == b) return Fail("expected a unit symbol");
    if (!ResolveOperand(t_.substr(b, i_ - b), out)) {
      i_ = b;
      return Fail("unknown unit symbol");
    }
    int sign = 1;
    size_t s = i_;
    if (At('+') || At('-')) sign = t_[i_++] == '-' ? -1 : 1;
    size_t digits = i_;
    int e = 0;
    while (i_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[i_])) && e < 1000) e = 10 * e + (t_[i_++] - '0');
    if (i_ == digits) {
      if (i_ != s) return Fail("expected an exponent after the sign");
      return true;
    }
    if (e > 99) return Fail("exponent too large");
    *out = out->Pow(sign * e, 1);
    return true;
  }

  std::string_view t_;
  size_t i_ = 0;
  std::string error_;
};

}  // namespace

Unit Unit::operator*(const Unit& o) const {
  Unit r;
  for (int i = 0; i < kBase; ++i) r.twice[static_cast<size_t>(i)] = static_cast<std::int16_t>(twice[static_cast<size_t>(i)] + o.twice[static_cast<size_t>(i)]);
  r.scale = scale * o.scale;
  return r;
}

Unit Unit::operator/(const Unit& o) const {
  Unit r;
  for (int i = 0; i < kBase; ++i) r.twice[static_cast<size_t>(i)] = static_cast<std::int16_t>(twice[static_cast<size_t>(i)] - o.twice[static_cast<size_t>(i)]);
  r.scale = scale / o.scale;
  return r;
}

Unit Unit::Pow(int num, int den) const {
  Unit r;
  for (int i = 0; i < kBase; ++i) {
    const int t = den == 1 ? twice[static_cast<size_t>(i)] * num : twice[static_cast<size_t>(i)] * num / den;
    r.twice[static_cast<size_t>(i)] = static_cast<std::int16_t>(t);
  }
  r.scale = scale == 1 ? 1 : std::pow(scale, static_cast<double>(num) / den);  // pow(1, x) is 1
  return r;
}

bool Unit::SameDimension(const Unit& o) const {
  for (int i = 0; i < kRad; ++i)
    if (twice[static_cast<size_t>(i)] != o.twice[static_cast<size_t>(i)]) return false;
  return true;
}

bool Unit::Agrees(const Unit& o) const {
  if (!SameDimension(o)) return false;
  if (scale == o.scale && std::isfinite(scale)) return true;  // equal scales, the common case
  return std::abs(scale - o.scale) <= 1e-9 * std::max(std::abs(scale), std::abs(o.scale));
}

bool Unit::Dimensionless() const { return SameDimension(Unit::One()); }

std::string Unit::ToString() const {
  static constexpr const char* kNames[kBase] = {"m", "kg", "s", "A", "K", "mol", "cd", "rad"};
  auto part = [&](bool positive) {
    std::string s;
    for (int i = 0; i < kBase; ++i) {
      const int t = twice[static_cast<size_t>(i)];
      if (t == 0 || (t > 0) != positive) continue;
      const int a = std::abs(t);
      if (!s.empty()) s += ".";
      s += kNames[i];
      if (a % 2) s += std::to_string(a / 2) + ".5";  // a half exponent (after sqrt): "m0.5"
      else if (a != 2) s += std::to_string(a / 2);
    }
    return s;
  };
  std::string num = part(true), den = part(false);
  std::string s = num.empty() ? "1" : num;
  if (!den.empty()) s += "/" + (den.find('.') == std::string::npos ? den : "(" + den + ")");
  if (scale != 1) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g ", scale);
    s = buf + s;
  }
  return s;
}

std::string JointCoordinateUnit(std::string_view kind, bool quaternion, int k, bool speed) {
  std::string q;
  if (kind == "revolute" || kind == "universal") q = "rad";
  else if (kind == "prismatic") q = "m";
  else if (kind == "cylindrical") q = k == 0 ? "m" : "rad";
  else if (kind == "planar") q = k < 2 ? "m" : "rad";
  else if (kind == "spherical") q = speed || !quaternion ? "rad" : "1";
  else if (kind == "free") q = k < 3 ? "m" : speed || !quaternion ? "rad" : "1";
  if (!speed || q.empty()) return q;
  return q + "/s";
}

bool ParseUnit(std::string_view text, Unit* out, std::string* error) {
  if (text.empty()) {
    *error = "empty unit";
    return false;
  }
  return UnitParser(text).Parse(out, error);
}

}  // namespace kanesim::lang
