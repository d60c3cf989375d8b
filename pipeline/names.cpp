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

// "auto": the compiler's choice. "cvode" is CVODE with Adams and fixed-point iteration.
constexpr std::array<Named<rt::Integrator>, 6> kIntegrators{{{"auto", rt::Integrator::Auto},
                                                            {"ida", rt::Integrator::IDA},
                                                            {"cvode", rt::Integrator::CvodeAdams},
                                                            {"cvode-bdf", rt::Integrator::CvodeBdf},
                                                            {"arkode", rt::Integrator::ArkodeErk},
                                                            {"dop853", rt::Integrator::Dop853}}};

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
bool IntegratorFromName(std::string_view name, rt::Integrator* out) {
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

std::string IntegratorOptionName(rt::Integrator integrator) {
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
  o.integrator = spec.integrator;
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

const char* IntegratorName(rt::Integrator k) {
  switch (k) {
    case rt::Integrator::Auto: return "auto";
    case rt::Integrator::IDA: return "IDA";
    case rt::Integrator::CvodeAdams:
    case rt::Integrator::CvodeBdf: return "CVODE";  // Adams or BDF: the run's --stats says which
    case rt::Integrator::ArkodeErk: return "ARKODE";
    case rt::Integrator::Dop853: return "DOP853";
  }
  return "?";
}

}  // namespace kanesim::pipeline
