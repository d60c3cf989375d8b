// Units of the CSV's columns (cli/signal_units.h).
#include "cli/signal_units.h"

#include <cstdlib>

#include "lang/lang.h"

namespace kanesim::cli {

namespace {

// "name[3]" -> 2 (0-based), "name" -> 0.
int Index(const std::string& field) {
  const size_t b = field.find('[');
  return b == std::string::npos ? 0 : std::atoi(field.c_str() + b + 1) - 1;
}

std::string JointSignalUnit(const flat::Joint& j, const std::string& field) {
  const int k = Index(field);
  const std::string base = field.substr(0, field.find('['));
  if (base == "reaction_force") return "N";
  if (base == "reaction_torque") return "N.m";
  const bool quaternion = j.rotation == flat::RotationCoords::Quaternion;
  const std::string c = lang::JointCoordinateUnit(flat::JointTypeName(j.type), quaternion, k, false);
  if (base == "q") return c;
  const std::string speed = lang::JointCoordinateUnit(flat::JointTypeName(j.type), quaternion, k, true);
  if (base == "u") return speed;
  if (base == "a") return speed.empty() ? "" : speed + "2";
  if (base == "drive") return speed == "m/s" ? "N" : speed == "rad/s" ? "N.m" : "";
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
