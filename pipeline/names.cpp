// Option names to the engine's enums (pipeline.h "The one place option names meet the
// enums"): one table per option, read both ways.
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pipeline/pipeline.h"

namespace kanesim::pipeline {

namespace {

template <typename T>
struct Named {
  const char* name;
  T value;
};

constexpr std::array<Named<rt::SolverPath>, 4> kSolvers{{{"auto", rt::SolverPath::Auto},
                                                        {"dense", rt::SolverPath::Dense},
                                                        {"sparse", rt::SolverPath::Sparse},
                                                        {"recursive", rt::SolverPath::Recursive}}};

// nullopt: the compiler's choice. "cvode" is CVODE with Adams and fixed-point iteration.
const std::array<Named<std::optional<sim::Method>>, 6> kIntegrators{{{"auto", std::nullopt},
                                                                    {"ida", sim::Method::IDA},
                                                                    {"cvode", sim::Method::CvodeAdams},
                                                                    {"cvode-bdf", sim::Method::CvodeBdf},
                                                                    {"arkode", sim::Method::ArkodeErk},
                                                                    {"dop853", sim::Method::Dop853}}};

constexpr std::array<Named<rt::IndeterminateReactions>, 2> kReactions{
    {{"nan", rt::IndeterminateReactions::NaN}, {"min-norm", rt::IndeterminateReactions::MinNorm}}};

constexpr std::array<Named<sim::IdaLinearSolver>, 4> kLinearSolvers{{{"auto", sim::IdaLinearSolver::Auto},
                                                                    {"dense", sim::IdaLinearSolver::Dense},
                                                                    {"klu", sim::IdaLinearSolver::Klu},
                                                                    {"krylov", sim::IdaLinearSolver::Krylov}}};

constexpr std::array<Named<sim::EnergyCheck>, 3> kEnergyChecks{
    {{"on", sim::EnergyCheck::kOn}, {"off", sim::EnergyCheck::kOff}, {"report", sim::EnergyCheck::kReport}}};

template <typename Table, typename T>
bool Find(const Table& table, std::string_view name, T* out) {
  for (const auto& row : table) {
    if (name == row.name) {
      *out = row.value;
      return true;
    }
  }
  return false;
}

template <typename Table>
std::vector<std::string> Names(const Table& table) {
  std::vector<std::string> out;
  for (const auto& row : table) out.emplace_back(row.name);
  return out;
}

}  // namespace

bool SolverFromName(std::string_view name, rt::SolverPath* out) { return Find(kSolvers, name, out); }
bool IntegratorFromName(std::string_view name, std::optional<sim::Method>* out) {
  return Find(kIntegrators, name, out);
}
bool ReactionsFromName(std::string_view name, rt::IndeterminateReactions* out) { return Find(kReactions, name, out); }
bool LinearSolverFromName(std::string_view name, sim::IdaLinearSolver* out) {
  return Find(kLinearSolvers, name, out);
}
bool EnergyCheckFromName(std::string_view name, sim::EnergyCheck* out) { return Find(kEnergyChecks, name, out); }

const std::vector<std::string>& SolverNames() {
  static const std::vector<std::string> names = Names(kSolvers);
  return names;
}
const std::vector<std::string>& IntegratorNames() {
  static const std::vector<std::string> names = Names(kIntegrators);
  return names;
}
const std::vector<std::string>& ReactionsNames() {
  static const std::vector<std::string> names = Names(kReactions);
  return names;
}
const std::vector<std::string>& LinearSolverNames() {
  static const std::vector<std::string> names = Names(kLinearSolvers);
  return names;
}
const std::vector<std::string>& EnergyCheckNames() {
  static const std::vector<std::string> names = Names(kEnergyChecks);
  return names;
}

std::string IntegratorName(const std::optional<sim::Method>& integrator) {
  for (const auto& row : kIntegrators)
    if (row.value == integrator) return row.name;
  return "auto";
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out.append(out.empty() ? "" : ", ").append(n);
  return out;
}

rt::CompileOptions CompileOptionsFor(const RunSpec& spec) {
  rt::CompileOptions o;
  o.solver = spec.solver;
  o.indeterminate = spec.reactions;
  if (spec.integrator) {
    switch (*spec.integrator) {
      case sim::Method::IDA: o.integrator = rt::IntegratorKind::IDA; break;
      case sim::Method::CvodeAdams:
      case sim::Method::CvodeBdf: o.integrator = rt::IntegratorKind::CVODE; break;
      case sim::Method::ArkodeErk: o.integrator = rt::IntegratorKind::ARKODE; break;
      case sim::Method::Dop853: o.integrator = rt::IntegratorKind::DOP853; break;
    }
  }
  return o;
}

const char* SolverName(rt::SolverPath s) {
  switch (s) {
    case rt::SolverPath::Auto: return "auto";
    case rt::SolverPath::Dense: return "dense";
    case rt::SolverPath::Sparse: return "sparse";
    case rt::SolverPath::Recursive: return "recursive";
  }
  return "?";
}

const char* IntegratorName(rt::IntegratorKind k) {
  switch (k) {
    case rt::IntegratorKind::Auto: return "auto";
    case rt::IntegratorKind::IDA: return "IDA";
    case rt::IntegratorKind::CVODE: return "CVODE";
    case rt::IntegratorKind::ARKODE: return "ARKODE";
    case rt::IntegratorKind::DOP853: return "DOP853";
  }
  return "?";
}

}  // namespace kanesim::pipeline
