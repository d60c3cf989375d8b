#include <algorithm>
#include <set>
#include <sstream>

#include "fmi/dependencies.h"
#include "fmi/fmi.h"
#include "lang/lang.h"

#ifndef KANESIM_VERSION
#define KANESIM_VERSION "unknown"
#endif

namespace kanesim::fmi {
namespace {

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string Number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// causality, variability, initial of each kind (FMI 2.0.4, table in section 2.2.7).
struct Attributes {
  const char *causality, *variability, *initial;
  bool has_start;
};
Attributes AttributesOf(VarKind kind) {
  switch (kind) {
    case VarKind::State: return {"local", "continuous", "exact", true};
    case VarKind::Derivative: return {"local", "continuous", "calculated", false};
    case VarKind::Input: return {"input", "continuous", "", true};  // an input has no initial
    case VarKind::Output: return {"output", "continuous", "calculated", false};
    case VarKind::Parameter: return {"parameter", "fixed", "exact", true};
    case VarKind::CalculatedParameter: return {"calculatedParameter", "fixed", "calculated", false};
    case VarKind::Fixed: return {"local", "constant", "exact", true};
    case VarKind::Indicator: return {"local", "continuous", "calculated", false};
  }
  return {"local", "continuous", "calculated", false};
}
// A state's start computed from parameters: "calculated", without start (FMI 2.0.4 section
// 2.2.7, FMI 3.0 section 2.4.7.4); an initial unknown.
Attributes AttributesOf(const Variable& v) {
  if (v.kind == VarKind::State && v.start_calculated) return {"local", "continuous", "calculated", false};
  return AttributesOf(v.kind);
}

std::string TypeElement(const Variable& v, const Attributes& a, const std::vector<Variable>& vars) {
  const char* tag = v.type == VarType::Integer ? "Integer" : v.type == VarType::Boolean ? "Boolean" : "Real";
  std::string e = std::string("<") + tag;
  if (a.has_start) {
    e += " start=\"";
    e += v.type == VarType::Boolean ? (v.start != 0 ? "true" : "false")
         : v.type == VarType::Integer ? std::to_string(long(v.start))
                                      : Number(v.start);
    e += "\"";
  }
  if (!v.unit.empty()) e += " unit=\"" + Escape(v.unit) + "\"";
  if (v.kind == VarKind::Derivative)
    for (size_t k = 0; k < vars.size(); ++k)
      if (vars[k].kind == VarKind::State && vars[k].index == v.index) e += " derivative=\"" + std::to_string(k + 1) + "\"";
  return e + "/>";
}

// ` dependencies="..."` (FMI 2: 1-based indices, FMI 3: value references; ListedKnowns)
// with ` dependenciesKind="..."` where some known enters with a constant factor (without it
// every one is "dependent", the standard's default), or nothing where the list names every
// known (ListOmitted): a large model's description stays small.
using Structure = StructureLists;
std::string DependencyAttributes(const Structure& s, size_t v, bool initial) {
  if (ListOmitted(s, v, initial)) return "";
  const std::vector<ListedKnown> k = ListedKnowns(s, v, initial);
  const bool structured = std::any_of(k.begin(), k.end(), [](const ListedKnown& e) { return e.constant; });
  const size_t base = s.version == 2 ? 1 : 0;
  std::string deps, kinds;
  for (const ListedKnown& e : k) {
    deps += (deps.empty() ? "" : " ") + std::to_string(e.vr + base);
    kinds += (kinds.empty() ? "" : " ") + std::string(e.constant ? "constant" : "dependent");
  }
  return " dependencies=\"" + deps + "\"" + (structured ? " dependenciesKind=\"" + kinds + "\"" : "");
}

// The unknowns of one section, in variable order: those of `kinds`; the initial ones
// (InitialUnknown) when `initial`.
bool InSection(const Variable& v, std::initializer_list<VarKind> kinds, bool initial) {
  return initial ? InitialUnknown(v) : std::find(kinds.begin(), kinds.end(), v.kind) != kinds.end();
}

void Unknowns(std::ostringstream& x, const char* tag, const Structure& s, std::initializer_list<VarKind> kinds,
              bool initial) {
  std::string body;
  for (size_t k = 0; k < s.vars.size(); ++k)
    if (InSection(s.vars[k], kinds, initial))
      body += "      <Unknown index=\"" + std::to_string(k + 1) + "\"" + DependencyAttributes(s, k, initial) + "/>\n";
  if (!body.empty()) x << "    <" << tag << ">\n" << body << "    </" << tag << ">\n";
}

void UnknownsV3(std::ostringstream& x, const char* tag, const Structure& s, std::initializer_list<VarKind> kinds,
                bool initial, bool with_dependencies = true) {
  for (size_t k = 0; k < s.vars.size(); ++k)
    if (InSection(s.vars[k], kinds, initial))
      x << "    <" << tag << " valueReference=\"" << k << "\""
        << (with_dependencies ? DependencyAttributes(s, k, initial) : "") << "/>\n";
}

// One unit of UnitDefinitions: its SI base-unit exponents and factor as the unit check reads
// the string (lang/units.h); without BaseUnit when it has none FMI can write (a half exponent).
std::string UnitElement(const std::string& name) {
  std::string e = "    <Unit name=\"" + Escape(name) + "\"";
  lang::Unit u;
  std::string error;
  if (!lang::ParseUnit(name, &u, &error)) return e + "/>\n";
  static constexpr const char* kAttr[lang::Unit::kBase] = {"m", "kg", "s", "A", "K", "mol", "cd", "rad"};
  std::string base;
  for (int i = 0; i < lang::Unit::kBase; ++i) {
    const int t = u.twice[size_t(i)];
    if (t % 2) return e + "/>\n";
    if (t) base += std::string(" ") + kAttr[i] + "=\"" + std::to_string(t / 2) + "\"";
  }
  if (u.scale != 1) base += " factor=\"" + Number(u.scale) + "\"";
  return e + ">\n      <BaseUnit" + base + "/>\n    </Unit>\n";
}

// UnitDefinitions (every unit a variable has) and DefaultExperiment, the same in FMI 2 and 3.
void UnitsAndExperiment(std::ostringstream& x, const std::vector<Variable>& vars, const flat::Experiment& e) {
  std::set<std::string> units;
  for (const Variable& v : vars)
    if (!v.unit.empty()) units.insert(v.unit);
  if (!units.empty()) {
    x << "  <UnitDefinitions>\n";
    for (const std::string& u : units) x << UnitElement(u);
    x << "  </UnitDefinitions>\n";
  }
  const double interval = e.interval > 0 ? e.interval : (e.stop_time - e.start_time) / sim::kDefaultIntervals;
  x << "  <DefaultExperiment startTime=\"" << Number(e.start_time) << "\" stopTime=\"" << Number(e.stop_time)
    << "\" tolerance=\"" << Number(e.tolerance) << "\" stepSize=\"" << Number(interval) << "\"/>\n";
}

// One variable of FMI 3.0 (section 2.4.7): the type is the element.
std::string VariableV3(const Variable& v, size_t vr, const std::vector<Variable>& vars) {
  const Attributes a = AttributesOf(v);
  const char* tag = v.type == VarType::Integer ? "Int32" : v.type == VarType::Boolean ? "Boolean" : "Float64";
  std::string e = std::string("    <") + tag + " name=\"" + Escape(v.name) + "\" valueReference=\"" +
                  std::to_string(vr) + "\" causality=\"" + a.causality + "\" variability=\"" + a.variability + "\"";
  if (*a.initial) e += std::string(" initial=\"") + a.initial + "\"";
  if (!v.description.empty()) e += " description=\"" + Escape(v.description) + "\"";
  if (a.has_start)
    e += " start=\"" +
         (v.type == VarType::Boolean ? std::string(v.start != 0 ? "true" : "false")
          : v.type == VarType::Integer ? std::to_string(long(v.start))
                                       : Number(v.start)) +
         "\"";
  if (!v.unit.empty()) e += " unit=\"" + Escape(v.unit) + "\"";
  if (v.kind == VarKind::Derivative)
    for (size_t k = 0; k < vars.size(); ++k)
      if (vars[k].kind == VarKind::State && vars[k].index == v.index) e += " derivative=\"" + std::to_string(k) + "\"";
  return e + "/>\n";
}

}  // namespace

std::string ModelDescription(const pipeline::Model& model, const ExportOptions& options, const std::string& guid) {
  const flat::Mechanism& mech = *model.mech;
  const std::vector<Variable> vars = ListVariables(model);
  const std::string id = Identifier(mech.model_name);
  const std::string caps =
      " canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" canNotUseMemoryManagementFunctions=\"true\""
      " providesDirectionalDerivative=\"true\"";
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"" << Escape(mech.model_name) << "\" guid=\"" << guid
    << "\" description=\"" << Escape(mech.description) << "\" generationTool=\"kanesim " << KANESIM_VERSION
    << "\" variableNamingConvention=\"flat\" numberOfEventIndicators=\""
    << std::count_if(vars.begin(), vars.end(), [](const Variable& v) { return v.kind == VarKind::Indicator; }) << "\">\n";
  if (options.model_exchange) x << "  <ModelExchange modelIdentifier=\"" << id << "\"" << caps << "/>\n";
  if (options.co_simulation)
    x << "  <CoSimulation modelIdentifier=\"" << id << "\" canHandleVariableCommunicationStepSize=\"true\"" << caps
      << "/>\n";
  UnitsAndExperiment(x, vars, mech.experiment);
  x << "  <ModelVariables>\n";
  for (size_t k = 0; k < vars.size(); ++k) {
    const Variable& v = vars[k];
    const Attributes a = AttributesOf(v);
    x << "    <!-- index " << k + 1 << " -->\n    <ScalarVariable name=\"" << Escape(v.name) << "\" valueReference=\"" << k
      << "\" causality=\"" << a.causality << "\" variability=\"" << a.variability << "\"";
    if (*a.initial) x << " initial=\"" << a.initial << "\"";
    if (!v.description.empty()) x << " description=\"" << Escape(v.description) << "\"";
    x << ">\n      " << TypeElement(v, a, vars) << "\n    </ScalarVariable>\n";
  }
  x << "  </ModelVariables>\n  <ModelStructure>\n";
  const Structure s{vars, ModelDependencies(*model.program, vars), 2};
  Unknowns(x, "Outputs", s, {VarKind::Output}, false);
  Unknowns(x, "Derivatives", s, {VarKind::Derivative}, false);
  Unknowns(x, "InitialUnknowns", s, {}, true);
  x << "  </ModelStructure>\n</fmiModelDescription>\n";
  return x.str();
}

// FMI 3.0: the same variables (value reference = order), then the independent variable
// `time`, which FMI 3 requires to be listed.
std::string ModelDescription3(const pipeline::Model& model, const ExportOptions& options, const std::string& token) {
  const flat::Mechanism& mech = *model.mech;
  const std::vector<Variable> vars = ListVariables(model);
  const std::string id = Identifier(mech.model_name);
  const std::string caps =
      " canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" providesDirectionalDerivatives=\"true\""
      " providesAdjointDerivatives=\"true\""
      " providesPerElementDependencies=\"true\"";  // fmi3GetVariableDependencies: every variable is a scalar
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"" << Escape(mech.model_name) << "\" instantiationToken=\""
    << token << "\" description=\"" << Escape(mech.description) << "\" generationTool=\"kanesim " << KANESIM_VERSION
    << "\" variableNamingConvention=\"flat\">\n";
  if (options.model_exchange) x << "  <ModelExchange modelIdentifier=\"" << id << "\"" << caps << "/>\n";
  if (options.co_simulation)
    x << "  <CoSimulation modelIdentifier=\"" << id << "\" canHandleVariableCommunicationStepSize=\"true\""
      << " hasEventMode=\"false\"" << caps << "/>\n";
  UnitsAndExperiment(x, vars, mech.experiment);
  x << "  <ModelVariables>\n";
  for (size_t k = 0; k < vars.size(); ++k) x << VariableV3(vars[k], k, vars);
  x << "    <Float64 name=\"time\" valueReference=\"" << vars.size()
    << "\" causality=\"independent\" variability=\"continuous\"/>\n";
  x << "  </ModelVariables>\n  <ModelStructure>\n";
  const Structure s{vars, ModelDependencies(*model.program, vars), 3};
  UnknownsV3(x, "Output", s, {VarKind::Output}, false);
  UnknownsV3(x, "ContinuousStateDerivative", s, {VarKind::Derivative}, false);
  UnknownsV3(x, "InitialUnknown", s, {}, true);
  UnknownsV3(x, "EventIndicator", s, {VarKind::Indicator}, false, false);
  x << "  </ModelStructure>\n</fmiModelDescription>\n";
  return x.str();
}

}  // namespace kanesim::fmi
