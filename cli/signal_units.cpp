// Units of the CSV's columns (cli/signal_units.h).
#include "cli/signal_units.h"

#include <cstdlib>

namespace kanesim::cli {

namespace {

// "name[3]" -> 2 (0-based), "name" -> 0.
int Index(const std::string& field) {
  const size_t b = field.find('[');
  return b == std::string::npos ? 0 : std::atoi(field.c_str() + b + 1) - 1;
}

// Coordinate k of joint j: its q is an angle ("rad"), a length ("m") or a quaternion
// component ("1").
const char* CoordinateKind(const flat::Joint& j, int k, bool speed) {
  using T = flat::JointType;
  const bool quaternion = j.rotation == flat::RotationCoords::Quaternion;
  switch (j.type) {
    case T::Revolute:
    case T::Universal: return "rad";
    case T::Prismatic: return "m";
    case T::Cylindrical: return k == 0 ? "m" : "rad";
    case T::Planar: return k < 2 ? "m" : "rad";
    case T::Spherical: return speed || !quaternion ? "rad" : "1";
    case T::Free: return k < 3 ? "m" : speed || !quaternion ? "rad" : "1";
    case T::Weld: return "";
  }
  return "";
}

std::string JointSignalUnit(const flat::Joint& j, const std::string& field) {
  const int k = Index(field);
  const std::string base = field.substr(0, field.find('['));
  if (base == "reaction_force") return "N";
  if (base == "reaction_torque") return "N.m";
  const bool speed = base != "q";
  const std::string c = CoordinateKind(j, k, speed);
  if (c.empty() || c == "1") return base == "q" ? c : "";
  if (base == "q") return c;
  if (base == "u") return c + "/s";
  if (base == "a") return c + "/s2";
  if (base == "drive") return c == "m" ? "N" : "N.m";
  return "";
}

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

std::string SignalUnit(const flat::Mechanism& m, const std::string& name) {
  if (name == "time") return "s";
  if (name == "kinetic_energy" || name == "potential_energy") return "J";
  if (name == "constraint_power") return "W";
  for (const auto& o : m.outputs)
    if (o.name == name) return o.unit;
  for (const auto& j : m.joints)
    if (name.size() > j.name.size() + 1 && name.compare(0, j.name.size(), j.name) == 0 && name[j.name.size()] == '.')
      if (std::string u = JointSignalUnit(j, name.substr(j.name.size() + 1)); !u.empty()) return u;
  const size_t dot = name.rfind('.');
  if (dot == std::string::npos) return "";
  const std::string field = name.substr(dot + 1, name.find('[', dot) - dot - 1);
  if (field == "r" || field == "point") return "m";
  if (field == "v") return "m/s";
  if (field == "w") return "rad/s";
  if (field == "a") return "m/s2";
  if (field == "alpha") return "rad/s2";
  if (field == "R") return "1";
  if (EndsWith(field, "_force")) return "N";
  return "";
}

bool UnitsInHeader::Begin(const std::vector<std::string>& names) {
  std::vector<std::string> with_units = names;
  for (std::string& n : with_units)
    if (std::string u = SignalUnit(m_, n); !u.empty()) n += " [" + u + "]";
  return inner_.Begin(with_units);
}

}  // namespace kanesim::cli
