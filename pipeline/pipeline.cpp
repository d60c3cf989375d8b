// The pipeline's stages (pipeline.h): load (parse, elaborate, compile) and run (resolve,
// integrate, output).
#include "pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "lang/diagnostics.h"
#include "lang/set_argument.h"
#include "lang/text.h"
#include "runtime/program/program.h"
#include "sim/signal_select.h"
#include "stdlib/stdlib.h"
#include "compiler/compiler.h"

namespace kanesim::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The bytes of a file; false when it cannot be read.
bool ReadWholeFile(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return !in.bad();
}

// Stages 1-2. False with the diagnostics appended to *text when a stage fails; warnings
// are appended also on success.
bool ParseAndElaborate(const Source& source, const LoadOptions& options, Model* m, std::string* text) {
  lang::Diagnostics diags(&m->source.sources);
  lang::ElaborateOptions eo;
  eo.model = options.model;
  eo.data_files = options.data_files;
  eo.leave_to_exit = options.leave_to_exit;
  for (const std::string& s : options.sets) {
    lang::ParamOverride o;
    if (!lang::ParseSetArgument(s, &o)) {
      *text += "kanesim: error[E210]: --set needs name=value, got '" + lang::ClipMessage(s) + "'\n";
      return false;
    }
    eo.overrides.push_back(std::move(o));
  }
  // 0. Import: a URDF becomes .mech text, named PATH.mech (its mesh names are relative to
  // the URDF's folder, which that name shares).
  if (import::IsUrdfPath(source.path)) {
    std::string urdf = source.text;
    std::error_code ec;
    if (const std::uintmax_t size = std::filesystem::file_size(source.path, ec);
        !source.from_text && !ec && size > import::kMaxUrdfBytes) {
      *text += import::TooLargeMessage(source.path, size);  // not read into memory
      return false;
    }
    if (!source.from_text && !ReadWholeFile(source.path, &urdf)) {
      *text += "kanesim: error: cannot read '" + lang::ClipMessage(source.path) + "'\n";
      return false;
    }
    import::Options io = options.urdf;
    io.notes = false;
    io.mesh_base_dir = std::filesystem::path(source.path).parent_path().string();
    if (io.mesh_base_dir.empty()) io.mesh_base_dir = ".";
    import::Result r = import::UrdfToMech(source.path, urdf, io);
    *text += r.diagnostics;
    if (!r.ok) return false;
    return ParseAndElaborate(Source::Text(source.path + ".mech", std::move(r.mech)), options, m, text);
  }
  // 1. Parse the main file; the standard library's classes are read from its image (parsed
  // at build time), each once per process, when elaboration first names them.
  bool ok = source.from_text
                ? lang::LoadProgramFromText(source.path, source.text, stdlib::Files(), &m->source, diags, stdlib::Image())
                : lang::LoadProgram(source.path, stdlib::Files(), &m->source, diags, stdlib::Image());
  // 2. Elaborate into the flat mechanism.
  if (ok) {
    auto mech = std::make_shared<flat::Mechanism>();
    ok = lang::Elaborate(m->source, eo, mech.get(), diags);
    m->mech = std::move(mech);
  }
  *text += diags.RenderAll();
  if (!ok && diags.NumErrors() > 0)
    *text += std::to_string(diags.NumErrors()) + " error" + (diags.NumErrors() == 1 ? "" : "s") + "\n";
  return ok && !diags.HasErrors();
}

// Stage 3. The compiler's errors are capped like the language's (Diagnostics::kMaxErrors):
// a model with thousands of unconnected bodies gives 50 messages and a count.
// The mechanism was elaborated just before: its parameters hold their values.
bool CompileStage(const RunSpec& spec, Model* m, std::string* text) {
  rt::CompileResult r = rt::Compile(m->mech, flat::ElaboratedParamValues(*m->mech), CompileOptionsFor(spec));
  if (r.errors.empty()) {
    m->program = std::move(r.program);
    return true;
  }
  lang::Diagnostics diags(&m->source.sources);
  for (const rt::CompileMessage& e : r.errors) AddCompileMessage(e, lang::Severity::Error, diags);
  *text += diags.RenderAll();
  const size_t shown = static_cast<size_t>(lang::Diagnostics::kMaxErrors) - 1;  // the last slot says "too many"
  if (r.errors.size() > static_cast<size_t>(lang::Diagnostics::kMaxErrors))
    *text += "kanesim: " + std::to_string(r.errors.size() - shown) + " more errors like these are not shown\n";
  return false;
}

// The span of a compiler location in `sm`: one byte at line:col of the file of that name.
lang::Span SpanOf(const lang::SourceManager& sm, const flat::SourceLoc& loc) {
  if (loc.file.empty() || loc.line <= 0) return {};
  for (int f = 0; f < sm.NumFiles(); ++f) {
    if (sm.Name(f) != loc.file) continue;
    const std::int32_t at = sm.Offset(f, loc.line, loc.col);
    return at >= 0 ? lang::Span{f, at, at + 1} : lang::Span{};
  }
  return {};
}

}  // namespace

LoadResult LoadModel(const Source& source, const LoadOptions& options, const RunSpec& spec) {
  LoadResult result;
  auto m = std::make_unique<Model>();
  Clock::time_point t0 = Clock::now();
  if (!ParseAndElaborate(source, options, m.get(), &result.diagnostics)) return result;
  m->load_seconds = Since(t0);
  if (options.compile) {
    Clock::time_point t1 = Clock::now();
    if (!CompileStage(spec, m.get(), &result.diagnostics)) return result;
    m->compile_seconds = Since(t1);
  }
  result.model = std::move(m);
  return result;
}

void AddCompileMessage(const rt::CompileMessage& e, lang::Severity severity, lang::Diagnostics& diags) {
  const lang::SourceManager& sm = diags.Sources();
  lang::Diagnostic& d = severity == lang::Severity::Error ? diags.Error(e.code, SpanOf(sm, e.loc), e.message)
                                                          : diags.Warning(e.code, SpanOf(sm, e.loc), e.message);
  for (const auto& [loc, msg] : e.notes) d.notes.push_back({SpanOf(sm, loc), msg});
  d.hint = e.hint;
}

std::string RenderCompileMessage(const Model& model, const rt::CompileMessage& e, lang::Severity severity) {
  lang::Diagnostics diags(&model.source.sources);
  AddCompileMessage(e, severity, diags);
  return diags.RenderAll();
}

void AddUnconnectedInputs(const flat::Mechanism& mech, const std::vector<std::string>& missing, lang::Diagnostics& diags) {
  for (const std::string& name : missing)
    for (const flat::Input& in : mech.inputs) {
      if (in.name != name) continue;
      diags.Error(flat::DiagCode::UnconnectedInput, SpanOf(diags.Sources(), in.loc),
                  "input '" + name + "' is not connected: nothing gives its value")
          .hint = "give it a column of an --input-file table, or a constant with --set " + name.substr(0, name.find('[')) +
                  "=...";
      break;
    }
}

std::string RenderUnconnectedInputs(const Model& model, const std::vector<std::string>& missing) {
  if (missing.empty()) return "";
  lang::Diagnostics diags(&model.source.sources);
  AddUnconnectedInputs(*model.mech, missing, diags);
  return diags.RenderAll();
}

namespace {
// A start value as a --sensitivity name: "j.q.start" / "j.u.start" (a joint with one coordinate
// or speed) or "j.q[k].start" (k from 1), of a joint whose coordinates are states.
struct StartValue {
  int joint = -1;  // flat joint index
  bool speed = false;
  int k = 0;       // from 0
  int state = -1;  // its index in y = [q_free; u_free] (-1: prescribed)
};

// True when `name` has a start value's form; then *why is "" (and *out filled) or why not.
bool ParseStartValue(const Model& model, const std::string& name, StartValue* out, std::string* why) {
  const std::string tail = ".start";
  if (name.size() <= tail.size() || name.compare(name.size() - tail.size(), tail.size(), tail) != 0) return false;
  std::string var = name.substr(0, name.size() - tail.size());
  int k = -1;
  if (!var.empty() && var.back() == ']') {
    const size_t open = var.rfind('[');
    if (open == std::string::npos) return false;
    const std::string digits = var.substr(open + 1, var.size() - open - 2);
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 6) return false;
    k = std::stoi(digits) - 1;
    var.resize(open);
  }
  if (var.size() < 3 || var[var.size() - 2] != '.' || (var.back() != 'q' && var.back() != 'u')) return false;
  out->speed = var.back() == 'u';
  const std::string joint = var.substr(0, var.size() - 2);
  const flat::Mechanism& mech = *model.mech;
  const rt::Program& program = *model.program;
  out->joint = mech.FindJoint(joint);
  *why = "";
  const int tree = out->joint < 0 ? -1 : program.joint_of_flat[static_cast<size_t>(out->joint)];
  if (tree < 0) {
    *why = "--sensitivity " + name + ": " +
           (out->joint < 0 ? "no joint '" + joint + "'" : "joint '" + joint + "' has no coordinates of its own (a cut joint or a weld)");
    return true;
  }
  const rt::TreeJoint& tj = program.joints[static_cast<size_t>(tree)];
  const int n = out->speed ? tj.nu : tj.nq;
  const std::string has = "--sensitivity " + name + ": joint '" + joint + "' has " + std::to_string(n) +
                          (out->speed ? " speed" : " coordinate") + (n == 1 ? "" : "s");
  if (k < 0 && n != 1) {
    *why = has + "; name one: " + var + "[1].start";
    return true;
  }
  out->k = k < 0 ? 0 : k;
  if (out->k >= n) {
    *why = has;
    return true;
  }
  if (!out->speed && (tj.type == flat::JointType::Spherical || tj.type == flat::JointType::Free) &&
      tj.rotation == flat::RotationCoords::Quaternion && out->k >= (tj.type == flat::JointType::Free ? 3 : 0)) {
    *why = "--sensitivity " + name + ": a quaternion's start is normalized, so its entries have no derivative of their own";
    return true;
  }
  const int full = (out->speed ? tj.u0 : tj.q0) + out->k;
  const std::vector<int>& free = out->speed ? program.u_free : program.q_free;
  for (size_t i = 0; i < free.size(); ++i)
    if (free[i] == full) out->state = static_cast<int>(i) + (out->speed ? program.nq : 0);
  return true;
}

// Why `name` cannot be a --sensitivity parameter ("" when it can).
std::string CheckSensitivityParam(const Model& model, const std::string& name) {
  StartValue sv;
  std::string why;
  if (ParseStartValue(model, name, &sv, &why)) return why;
  const flat::Mechanism& mech = *model.mech;
  const int i = mech.FindParam(name);
  if (i < 0) return "--sensitivity " + name + ": no parameter of that name (`kanesim check --emit flat` lists them)";
  const flat::Param& p = mech.params[static_cast<size_t>(i)];
  if (p.type != flat::ParamType::Real) return "--sensitivity " + name + ": not a Real parameter";
  if (p.structural) return "--sensitivity " + name + ": a structural parameter (it shapes the model, no derivative)";
  if (p.is_constant) return "--sensitivity " + name + ": a constant";
  return "";
}

// The model with a start value moved by d: its expression plus d, compiled again (so that a
// closed loop is assembled from it as from a start written in the file).
rt::CompileResult ShiftStart(const Model& model, const StartValue& sv, double d) {
  flat::Mechanism mech = *model.mech;
  flat::Joint& j = mech.joints[static_cast<size_t>(sv.joint)];
  std::vector<flat::ExprId>& starts = sv.speed ? j.u_start : j.q_start;
  if (starts.size() <= static_cast<size_t>(sv.k)) starts.resize(static_cast<size_t>(sv.k) + 1, flat::kNoExpr);
  flat::ExprId& e = starts[static_cast<size_t>(sv.k)];
  const flat::ExprId shift = mech.exprs.Constant(d);
  e = e == flat::kNoExpr ? shift : mech.exprs.Binary(flat::Op::Add, e, shift);
  return rt::Compile(std::make_shared<const flat::Mechanism>(std::move(mech)), model.program->options);
}
}  // namespace

std::string ResolveRun(const Model& model, const RunSpec& spec, ResolvedRun* out, RunProblem* problem) {
  RunProblem unused;
  RunProblem& why = problem ? *problem : unused;
  why = RunProblem::kNone;
  const flat::Experiment& ex = model.mech->experiment;
  const rt::Program& program = *model.program;

  for (auto [name, value] : {std::pair{"interval", spec.interval}, {"rtol", spec.rtol}, {"atol", spec.atol}}) {
    if (!std::isnan(value) && !(value > 0.0 && std::isfinite(value))) {
      why = RunProblem::kValue;
      return std::string(name) + " must be a positive number, got " + sim::FormatNumber(value);
    }
  }
  sim::SimOptions& so = out->sim;
  so = sim::SimOptions{};
  if (!std::isnan(spec.start_time)) so.start_time = spec.start_time;
  so.stop_time = !std::isnan(spec.stop_time) ? spec.stop_time : ex.stop_time;
  if (!std::isnan(spec.interval)) so.interval = spec.interval;
  else if (ex.has_interval) so.interval = ex.interval;
  so.rtol = !std::isnan(spec.rtol) ? spec.rtol : ex.tolerance;
  so.atol = !std::isnan(spec.atol) ? spec.atol : so.rtol;
  so.integrator = spec.integrator;
  so.ida_linear_solver = spec.linear_solver;
  so.project_steps = spec.project_steps;
  so.energy_check = spec.energy_check;
  so.speeds = spec.speeds.value_or(ex.diagonal_speeds ? sim::Speeds::kDiagonal : sim::Speeds::kJoint);
  so.speed_order = !spec.speed_order.empty() ? spec.speed_order : ex.speed_order;

  if (!spec.outputs.empty()) {
    std::string error;
    if (!sim::SelectSignals(rt::AvailableSignals(program), spec.outputs, &so.signals, &error)) {
      why = RunProblem::kSignals;
      return error;
    }
  }
  out->sensitivity.clear();
  for (const std::string& name : spec.sensitivity) {
    if (std::string bad = CheckSensitivityParam(model, name); !bad.empty()) {
      why = RunProblem::kSensitivity;
      return bad;
    }
    out->sensitivity.push_back(name);
  }
  out->grid = sim::ResolveGrid(program, so);
  if (std::string bad = sim::CheckRun(out->grid, so.rtol, so.atol); !bad.empty()) {
    why = RunProblem::kGrid;
    return bad;
  }
  return "";
}

std::string RunWarnings(const Model& model, double rtol, const std::vector<std::string>& signals) {
  std::string out;
  const rt::Program& program = *model.program;
  if (rt::CompileMessage f = rt::FrictionIndeterminateWarning(program); !f.message.empty())
    out += RenderCompileMessage(model, f, lang::Severity::Warning);
  if (rt::CompileMessage w = rt::StartSpeedsWarning(program); !w.message.empty())
    out += RenderCompileMessage(model, w, lang::Severity::Warning);
  for (const rt::CompileMessage& w : rt::LockedJointWarnings(program))
    out += RenderCompileMessage(model, w, lang::Severity::Warning);
  if (program.options.indeterminate == rt::IndeterminateReactions::NaN) {
    const std::vector<std::string> which = rt::IndeterminateSignals(program, signals);
    if (!which.empty()) out += RenderCompileMessage(model, rt::IndeterminateWarning(program, which), lang::Severity::Warning);
  }
  if (std::string w = sim::ToleranceWarning(rtol); !w.empty()) out += "kanesim: warning: " + w + "\n";
  return out;
}

std::string SensitivityParams(const Model& model, const std::vector<std::string>& names,
                              std::vector<sim::SensitivityParam>* out) {
  const flat::Mechanism& mech = *model.mech;
  out->clear();
  for (const std::string& name : names) {
    if (std::string bad = CheckSensitivityParam(model, name); !bad.empty()) return bad;
    StartValue sv;
    std::string why;
    if (ParseStartValue(model, name, &sv, &why)) {
      // A start value: only the start moves (df/dp = 0); the step is scaled to at least 1
      // (angles, lengths and speeds of order one).
      std::vector<double> y0(static_cast<size_t>(rt::StateSize(*model.program)));
      rt::InitialState(*model.program, y0.data());
      const double x = sv.state >= 0 ? y0[static_cast<size_t>(sv.state)] : 0.0;
      sim::SensitivityParam sp;
      sp.name = name;
      sp.delta = sim::SensitivityStep(std::max(std::fabs(x), 1.0));
      sp.start_value = true;
      // At +/- delta and +/- 2 delta (the second pair for the error estimate).
      for (int step : {1, -1, 2, -2}) {
        rt::CompileResult r = ShiftStart(model, sv, step * sp.delta);
        if (!r.program)
          return "--sensitivity " + name + ": the model does not assemble with that start moved by " +
                 sim::FormatShortest(step * sp.delta) + (r.errors.empty() ? std::string() : " (" + r.errors.front().message + ")");
        (step == 1 ? sp.plus : step == -1 ? sp.minus : step == 2 ? sp.plus2 : sp.minus2) = r.program;
      }
      out->push_back(std::move(sp));
      continue;
    }
    const size_t i = static_cast<size_t>(mech.FindParam(name));
    const double p = flat::EvaluateParams(mech)[i];
    sim::SensitivityParam sp;
    sp.name = name;
    sp.delta = sim::SensitivityStep(p);
    for (int step : {1, -1, 2, -2}) {
      rt::CompileResult r = rt::Rebind(*model.program, flat::EvaluateParams(mech, {{i, p + step * sp.delta}}));
      if (!r.program)
        return "--sensitivity " + name + ": the model does not compile at " + name + " = " +
               sim::FormatShortest(p + step * sp.delta) +
               (r.errors.empty() ? std::string() : " (" + r.errors.front().message + ")");
      (step == 1 ? sp.plus : step == -1 ? sp.minus : step == 2 ? sp.plus2 : sp.minus2) = r.program;
    }
    out->push_back(std::move(sp));
  }
  return "";
}

sim::SimResult Run(const Model& model, const ResolvedRun& run, sim::SignalSink& sink) {
  if (run.sensitivity.empty()) return sim::Simulate(*model.program, run.sim, sink);
  std::vector<sim::SensitivityParam> params;
  if (std::string why = SensitivityParams(model, run.sensitivity, &params); !why.empty()) {
    sim::SimResult bad;
    bad.status = sim::SimResult::Status::kUsageError;
    bad.message = why;
    return bad;
  }
  return sim::SimulateSensitivities(*model.program, params, run.sim, sink);
}

sim::SimResult Run(const Model& model, const RunSpec& spec, sim::SignalSink& sink) {
  ResolvedRun run;
  if (std::string why = ResolveRun(model, spec, &run); !why.empty()) {
    sim::SimResult r;
    r.status = sim::SimResult::Status::kUsageError;
    r.message = why;
    return r;
  }
  return Run(model, run, sink);
}

}  // namespace kanesim::pipeline
