// `kanesim linearize FILE`: the linear state-space model about an operating point, its
// eigenvalues and modes (linearize, docs/linearize.md); `--sweep` a root locus.
#include "cli/cmd_linearize.h"

#include <CLI/CLI.hpp>
#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli/common.h"
#include "cli/number_options.h"
#include "batch/file_guard.h"
#include "flat/number.h"
#include "lang/set_argument.h"
#include "linearize/linearize.h"
#include "runtime/program/program.h"
#include "viz/locus_page.h"
#include "viz/viewer.h"

namespace kanesim::cli {

namespace {

struct LinearizeArgs {
  LoadOptions load;
  std::string out_path;
  std::string solver = "auto";
  double at = 0.0;
  CLI::Option* at_opt = nullptr;
  bool equilibrium = false;
  std::vector<std::string> inputs, outputs;
  double step = 1e-3;
  std::string sweep;
  std::string html_path;
  bool frozen = false;
};

// Above this change of A along the motion (relative) the operating point is no equilibrium
// nor steady motion in these coordinates and the eigenvalues are no stability exponents.
constexpr double kUnsteadyLimit = 1e-6;

std::string UnsteadyCause(double unsteady) {
  return fmt::format(
      "the operating point is neither an equilibrium nor a steady motion in these coordinates (A changes by {:.1e} "
      "relative along the motion): the eigenvalues would be those of a frozen instant, not stability exponents",
      unsteady);
}

// The refusal (exit 2) for an unsteady operating point without --frozen.
int FailUnsteady(double t, double unsteady, const std::string& where) {
  std::fflush(stdout);  // rows printed before come first
  fmt::print(stderr, "kanesim linearize: numerical failure at t = {}{}: {}\n", t, where, UnsteadyCause(unsteady));
  fmt::print(stderr,
             "  hint: use --equilibrium, or joints whose coordinates follow the motion's symmetry (joint angles "
             "instead of a spinning quaternion; docs/linearize.md, \"Steady motions\"); --frozen accepts the "
             "eigenvalues of the frozen instant\n");
  return kExitNumerical;
}

// Numbers in JSON: 17 significant digits (round-trip), null for a non-finite value.
std::string Num(double x) { return std::isfinite(x) ? fmt::format("{:.17g}", x) : "null"; }

std::string Str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      o += fmt::format("\\u{:04x}", c);
      continue;
    }
    o += c;
  }
  return o + "\"";
}

std::string Names(const std::vector<std::string>& v) {
  std::string o = "[";
  for (size_t i = 0; i < v.size(); ++i) o += (i ? ", " : "") + Str(v[i]);
  return o + "]";
}

std::string Matrix(const Eigen::MatrixXd& m) {
  std::string o = "[";
  for (int i = 0; i < m.rows(); ++i) {
    o += i ? ",\n    [" : "\n    [";
    for (int j = 0; j < m.cols(); ++j) o += (j ? ", " : "") + Num(m(i, j));
    o += "]";
  }
  return o + (m.rows() ? "\n  ]" : "]");
}

std::string Json(const lin::LinearModel& m, const lin::OperatingPoint& op) {
  std::string o = "{\n";
  o += "  \"states\": " + Names(m.states) + ",\n";
  o += fmt::format("  \"n_coordinates\": {},\n", m.n_coords);
  o += "  \"inputs\": " + Names(m.inputs) + ",\n";
  o += "  \"outputs\": " + Names(m.outputs) + ",\n";
  o += "  \"time\": " + Num(op.t) + ",\n";
  o += "  \"A\": " + Matrix(m.A) + ",\n";
  o += "  \"B\": " + Matrix(m.B) + ",\n";
  o += "  \"C\": " + Matrix(m.C) + ",\n";
  o += "  \"D\": " + Matrix(m.D) + ",\n";
  o += "  \"eigenvalues\": [";
  for (size_t k = 0; k < m.modes.size(); ++k)
    o += (k ? ", " : "") + fmt::format("[{}, {}]", Num(m.modes[k].lambda.real()), Num(m.modes[k].lambda.imag()));
  o += "],\n  \"modes\": [";
  for (size_t k = 0; k < m.modes.size(); ++k) {
    const lin::Mode& md = m.modes[k];
    o += k ? ",\n    {" : "\n    {";
    o += fmt::format("\"eigenvalue\": [{}, {}], \"natural_frequency\": {}, \"frequency_hz\": {}, \"damping_ratio\": {}, ",
                     Num(md.lambda.real()), Num(md.lambda.imag()), Num(md.omega_n), Num(md.freq_hz), Num(md.zeta));
    o += "\"dominant\": [";
    for (size_t i = 0; i < md.dominant.size(); ++i)
      o += (i ? ", " : "") + fmt::format("[{}, {}]", Str(md.dominant[i].first), Num(md.dominant[i].second));
    o += "], \"shape\": [";
    for (int i = 0; i < md.shape.size(); ++i)
      o += (i ? ", " : "") + fmt::format("[{}, {}]", Num(md.shape[i].real()), Num(md.shape[i].imag()));
    o += "]}";
  }
  o += m.modes.empty() ? "],\n" : "\n  ],\n";
  o += "  \"ignorable\": " + Names(m.ignorable) + ",\n";
  o += "  \"held\": " + Names(m.held) + ",\n";
  std::string widened;
  for (const lin::WidenedStep& w : m.widened) widened += (widened.empty() ? "" : ", ") + Str(w.name) + ": " + Num(w.used);
  o += fmt::format("  \"accuracy\": {{\"step\": {}, \"A\": {}, \"BCD\": {}, \"unsteady\": {}, \"widened\": {{{}}}}}\n",
                   Num(m.h), Num(m.error_A), Num(m.error_BCD), Num(m.unsteady), widened);
  return o + "}\n";
}

// Says which columns were differenced with a wider step than --step (linearize.cpp, eq. 8):
// "" when none.
std::string WidenedNote(const lin::LinearModel& m) {
  if (m.widened.empty()) return "";
  std::string cols;
  for (const lin::WidenedStep& w : m.widened) cols += fmt::format("{}{} {:.2g}", cols.empty() ? "" : ", ", w.name, w.used);
  return fmt::format("kanesim linearize: note: --step {:g} is too small for {} of the {} column(s): added to the "
                     "operating point's value it would be lost to rounding; differenced with the smallest step that "
                     "keeps the change instead ({}); the accuracy printed includes the rounding error\n",
                     m.h, m.widened.size(), m.states.size() + m.inputs.size(), cols);
}

// The printed report: states, accuracy, eigenvalues with frequency, damping and the
// dominant coordinates, the ignorable coordinates.
void Print(const lin::LinearModel& m, const lin::OperatingPoint& op) {
  const int nc = m.n_coords, n = static_cast<int>(m.states.size());
  fmt::print("states      {} coordinate(s), {} speed(s) at t = {}\n", nc, n - nc, op.t);
  if (n == 0) {
    fmt::print("  none: constraints and prescribed motions fix every coordinate (0 degrees of freedom); nothing to "
               "linearize\n");
    return;
  }
  for (int i = 0; i < n; ++i) fmt::print("  x{:<3} {}\n", i + 1, m.states[static_cast<size_t>(i)]);
  if (!m.inputs.empty()) fmt::print("inputs      {}\n", fmt::join(m.inputs, ", "));
  if (!m.outputs.empty()) fmt::print("outputs     {}\n", fmt::join(m.outputs, ", "));
  fmt::print("accuracy    A to {:.1e} relative (central differences, Richardson over h = {:g}, h/2, h/4{})", m.error_A,
             m.h, m.widened.empty() ? "" : "; wider where rounding needs it: see the note");
  if (!m.inputs.empty() || !m.outputs.empty()) fmt::print("; B, C, D to {:.1e}", m.error_BCD);
  fmt::print("\n");
  fmt::print("eigenvalues (sorted by modulus)\n");
  fmt::print("  {:>3}  {:>14} {:>14}  {:>11} {:>9}  {}\n", "#", "real [1/s]", "imag [rad/s]", "freq [Hz]", "damping",
             "dominant coordinates");
  for (size_t k = 0; k < m.modes.size(); ++k) {
    const lin::Mode& md = m.modes[k];
    std::string dom;
    for (const auto& [name, w] : md.dominant) dom += (dom.empty() ? "" : ", ") + fmt::format("{} {:.2f}", name, w);
    if (md.omega_n == 0) dom = "(zero: an ignorable or neutral direction)";
    const std::string damping = md.omega_n > 0 ? fmt::format("{:9.4f}", md.zeta) : fmt::format("{:>9}", "-");
    fmt::print("  {:>3}  {:>14.7g} {:>14.7g}  {:>11.5g} {}  {}\n", k + 1, md.lambda.real(), md.lambda.imag(),
               md.freq_hz, damping, dom);
  }
  if (!m.ignorable.empty())
    fmt::print("ignorable   {} (zero eigenvalues: no other state reads them)\n", fmt::join(m.ignorable, ", "));
  if (!m.held.empty())
    fmt::print("held        {} (constraint rows at the operating point: not states)\n", fmt::join(m.held, ", "));
  double rmax = -INFINITY;
  for (const lin::Mode& md : m.modes) rmax = std::max(rmax, md.lambda.real());
  if (!m.modes.empty())
    fmt::print("stability   {} (largest real part {:.3g})\n",
               rmax > 1e-9 ? "unstable" : (rmax < -1e-9 ? "asymptotically stable" : "marginal (no growing mode)"),
               rmax);
}

// The -o file, written as `kanesim run -o` writes its CSV (docs/sweeps.md "Output files of
// every command"): a regular (or new) file through a temporary beside it, flushed and
// renamed over it at the end, under a lock file beside it, so a kill, a crash or a full disk
// leaves the previous file whole; a FIFO or a device (/dev/stdout) is streamed to directly.
class Output {
 public:
  // False (said on stderr) when it cannot be opened. `inputs`: every file the model read.
  bool Open(const std::string& path, const std::vector<std::string>& inputs) {
    path_ = path;
    if (std::string in = batch::OverwrittenInput(path, inputs); !in.empty()) {
      fmt::print(stderr, "kanesim: error: -o '{}' is the model file '{}'; writing there would destroy it\n", path, in);
      return false;
    }
    std::string error;
    if (batch::NotRegularFile(path).empty()) {
      const std::filesystem::path target(batch::ReplacedFile(path));
      const std::string lock_path = (target.parent_path() / ("." + target.filename().string() + ".lock")).string();
      if (!lock_.Acquire(lock_path, "'" + path + "'", &error, /*remove_at_end=*/true) ||
          (batch::RemoveStaleTemps(target.string()), !atomic_.Open(path, &error))) {
        fmt::print(stderr, "kanesim: error: {}\n", error);
        return false;
      }
      file_ = atomic_.file();
    } else if (!(file_ = std::fopen(path.c_str(), "w"))) {
      fmt::print(stderr, "kanesim: error: cannot open '{}' for writing: {}\n", path, std::strerror(errno));
      return false;
    }
    return true;
  }
  std::FILE* file() const { return file_; }
  // Renames the finished file over the target (or closes the stream); false, said, when
  // it could not be written whole (the previous file is then unchanged).
  bool Finish() {
    std::string error;
    const bool ok = atomic_.file() ? atomic_.Commit(&error) : std::fclose(file_) == 0;
    file_ = nullptr;
    if (!ok)
      fmt::print(stderr, "kanesim: error: cannot write '{}'{}\n", path_, error.empty() ? "" : ": " + error);
    return ok;
  }

 private:
  std::string path_;
  batch::FileLock lock_;
  batch::AtomicFile atomic_;  // removes its temporary when not committed
  std::FILE* file_ = nullptr;
};

int Fail(const lin::Status& s) {
  fmt::print(stderr, "kanesim linearize: {}: {}\n", s.code == 1 ? "error" : "numerical failure", s.message);
  if (s.where.line > 0)
    fmt::print(stderr, "{}:{}:{}: note: declared here\n", s.where.file.str(), s.where.line, s.where.col);
  if (!s.hint.empty()) fmt::print(stderr, "  hint: {}\n", s.hint);
  return s.code == 1 ? kExitModelError : kExitNumerical;
}

// The model's inputs (docs/linearize.md "Inputs"): --input-file tables, and --set
// constants, which here keep the input an input (a column of B and D) at that value, where
// `run` makes it a constant of the model.
class ModelInputs final : public rt::InputSource {
 public:
  explicit ModelInputs(const std::vector<std::string>& names)
      : table(names), constant(names.size(), 0.0), is_constant(names.size(), 0) {}
  int Values(double t, double* u, double* du_dt, std::string* error) const override {
    if (const int s = table.Values(t, u, du_dt, error); s != 0) return s;
    for (size_t k = 0; k < constant.size(); ++k)
      if (is_constant[k]) u[k] = constant[k], du_dt[k] = 0.0;
    return 0;
  }
  // The values at time t (the operating point's), "" or why not.
  std::string At(double t, std::vector<double>* u) const {
    std::vector<double> rates(constant.size());
    u->assign(constant.size(), 0.0);
    std::string error;
    return Values(t, u->data(), rates.data(), &error) == 0 ? "" : error;
  }
  sim::InputTable table;
  std::vector<double> constant;
  std::vector<char> is_constant;
};

// The --set values of load->sets that name one of the model's inputs (a scalar, or one
// element: "tau=0.5", "f[2]=1"), removed from load->sets: NAME is such an input when the
// model loaded without that set lists it (`mech`, loaded with every set, has it as a
// constant). False after saying why (a value that is not a number).
bool SplitInputSets(LoadOptions* load, const pipeline::RunSpec& spec, const flat::Mechanism& mech,
                    std::vector<std::pair<std::string, double>>* out) {
  std::vector<std::string> keep;
  for (size_t i = 0; i < load->sets.size(); ++i) {
    lang::ParamOverride set;
    if (!lang::ParseSetArgument(load->sets[i], &set) || mech.FindParam(set.name) >= 0) {
      keep.push_back(load->sets[i]);
      continue;
    }
    pipeline::LoadOptions lo;
    lo.model = load->model;
    lo.compile = false;
    lo.urdf.floating = load->floating;
    lo.urdf.package_paths = load->package_paths;
    for (size_t j = 0; j < load->sets.size(); ++j)
      if (j != i) lo.sets.push_back(load->sets[j]);
    const pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(load->path), lo, spec);
    bool input = false, array = false;
    for (const flat::Input& in : r.model ? r.model->mech->inputs : std::vector<flat::Input>{}) {
      input = input || in.name == set.name;
      array = array || in.name.rfind(set.name + "[", 0) == 0;
    }
    if (array && !input) {
      fmt::print(stderr, "kanesim: error: --set {}: linearize takes an array input's elements one by one ({}[1]=...)\n",
                 set.name, set.name);
      return false;
    }
    if (!input) {
      keep.push_back(load->sets[i]);
      continue;
    }
    double v = 0.0;
    std::string why;
    if (!flat::ParseNumber(set.value, &v, &why)) {
      fmt::print(stderr, "kanesim: error: --set {}: an input's value for linearize is a number: {}\n", set.name, why);
      return false;
    }
    out->emplace_back(set.name, v);
  }
  load->sets = keep;
  return true;
}

// The model's inputs from --input-file and the --set values found by SplitInputSets, each
// input given one way, the tables covering [t0, t1]: false after saying why (E239 for an
// input that nothing gives, at its declaration).
bool GatherInputs(const pipeline::Model& model, const std::vector<std::string>& files,
                  const std::vector<std::pair<std::string, double>>& sets, double t0, double t1, ModelInputs* mi) {
  for (const std::string& f : files) {
    std::string error;
    if (!mi->table.Read(f, &error)) {
      fmt::print(stderr, "kanesim: error: {}\n", error);
      return false;
    }
  }
  const rt::Program& p = *model.program;
  for (const auto& [name, value] : sets)
    for (int k = 0; k < rt::NumInputs(p); ++k)
      if (rt::InputName(p, k) == name) mi->constant[static_cast<size_t>(k)] = value, mi->is_constant[static_cast<size_t>(k)] = 1;
  std::vector<std::string> missing;
  for (const std::string& name : mi->table.Missing()) {
    bool set = false;
    for (const auto& kv : sets) set = set || kv.first == name;
    if (!set) missing.push_back(name);
  }
  if (const std::string e = pipeline::RenderUnconnectedInputs(model, missing); !e.empty()) {
    std::cerr << e;
    return false;
  }
  if (std::string why = mi->table.CheckSpan(t0, t1); !why.empty()) {
    fmt::print(stderr, "kanesim: error: {}\n", why);
    return false;
  }
  return true;
}

// The operating point per the options: start values, the motion at --at, or an
// equilibrium found from the start values (reported); *u: the model's inputs there.
lin::Status OperatingPointFor(const rt::Program& p, const LinearizeArgs& a, const ModelInputs& mi, bool report,
                              lin::OperatingPoint* op, std::vector<double>* u) {
  const rt::InputSource* source = rt::NumInputs(p) > 0 ? &mi : nullptr;
  if (a.equilibrium) {
    lin::EquilibriumResult eq;
    lin::OperatingPoint start = lin::StartPoint(p);
    if (a.at_opt->count() > 0)
      if (lin::Status s = lin::PointAtTime(p, a.at, &start, source); !s.ok()) return s;
    if (std::string why = mi.At(start.t, u); !why.empty()) return {1, why};
    if (lin::Status s = lin::FindEquilibrium(p, start, &eq, *u); !s.ok()) return s;
    *op = eq.point;
    if (report) {
      fmt::print("equilibrium found in {} Newton iteration(s){}, residual {:.2e} (largest acceleration)\n",
                 eq.iterations,
                 eq.relaxation_steps > 0
                     ? fmt::format(" (Newton stalled: {} relaxation steps toward a potential minimum first)",
                                   eq.relaxation_steps)
                     : "",
                 eq.residual);
      if (eq.moved.empty()) fmt::print("  the start values are an equilibrium: nothing moved\n");
      for (const auto& [name, d] : eq.moved) fmt::print("  moved  {:<24} {:+.10g}\n", name, d);
    }
    return {};
  }
  *op = lin::StartPoint(p);
  if (a.at_opt->count() > 0)
    if (lin::Status s = lin::PointAtTime(p, a.at, op, source); !s.ok()) return s;
  if (std::string why = mi.At(op->t, u); !why.empty()) return {1, why};
  return {};
}

// --sweep NAME=A:STEP:B into its parts.
bool ParseSweep(const std::string& text, std::string* name, std::vector<double>* values, std::string* why) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    *why = "--sweep needs NAME=FROM:STEP:TO, e.g. v=0:0.1:10";
    return false;
  }
  *name = text.substr(0, eq);
  std::string rest = text.substr(eq + 1);
  double v[3];
  for (int k = 0; k < 3; ++k) {
    const size_t c = rest.find(':');
    if ((k < 2) == (c == std::string::npos)) {
      *why = "--sweep needs NAME=FROM:STEP:TO, e.g. v=0:0.1:10";
      return false;
    }
    if (!flat::ParseNumber(rest.substr(0, c), &v[k], why)) return false;
    rest = c == std::string::npos ? "" : rest.substr(c + 1);
  }
  if (!(v[1] > 0) || v[2] < v[0]) {
    *why = "--sweep: STEP must be positive and TO not below FROM";
    return false;
  }
  const double count = std::floor((v[2] - v[0]) / v[1] * (1 + 1e-12)) + 1;
  if (count > 100000) {
    *why = "--sweep: more than 100000 values";
    return false;
  }
  for (long i = 0; i < static_cast<long>(count); ++i) values->push_back(v[0] + static_cast<double>(i) * v[1]);
  return true;
}

// Root locus: one row per value, the eigenvalues sorted by modulus (re, im pairs).
int RunSweep(const rt::Program& program, const std::vector<std::string>& inputs, const ModelInputs& mi,
             const LinearizeArgs& a) {
  std::string name, why;
  std::vector<double> values;
  if (!ParseSweep(a.sweep, &name, &values, &why)) {
    fmt::print(stderr, "kanesim: error: {}\n", why);
    return kExitModelError;
  }
  lin::LinearizeOptions o;
  o.step = a.step;
  std::vector<std::vector<std::complex<double>>> rows;
  std::vector<double> unsteady, times;
  std::string widened_note;  // the first value's, said once
  for (double v : values) {
    std::shared_ptr<const rt::Program> p;
    if (lin::Status s = lin::RebindParameter(program, name, v, &p); !s.ok()) return Fail(s);
    lin::OperatingPoint op;
    lin::LinearModel m;
    lin::Status s = OperatingPointFor(*p, a, mi, false, &op, &o.input_values);
    if (s.ok()) s = lin::Linearize(*p, op, o, &m);
    if (s.ok()) lin::ComputeModes(&m);
    if (!s.ok()) {
      s.message = fmt::format("{} = {}: {}", name, v, s.message);
      return Fail(s);
    }
    if (widened_note.empty()) widened_note = WidenedNote(m);
    std::vector<std::complex<double>> ev;
    for (const lin::Mode& md : m.modes) ev.push_back(md.lambda);
    rows.push_back(ev);
    unsteady.push_back(m.unsteady);
    times.push_back(op.t);
    if (m.unsteady > kUnsteadyLimit && !a.frozen) break;  // nothing after it is computed
  }
  fmt::print(stderr, "{}", widened_note);
  const size_t n = rows.empty() ? 0 : rows.front().size();
  std::FILE* out = stdout;
  Output file;
  if (!a.out_path.empty() && a.out_path != "-") {
    if (!file.Open(a.out_path, inputs)) return kExitModelError;
    out = file.file();
  }
  // fwrite, not fmt::print(FILE*), which throws when the disk is full: the failure is
  // said once at the end and the previous file kept.
  bool write_ok = true;
  auto put = [&](const std::string& text) {
    write_ok = std::fwrite(text.data(), 1, text.size(), out) == text.size() && write_ok;
  };
  std::string head = name;
  for (size_t k = 0; k < n; ++k) head += fmt::format(",lambda{}.re,lambda{}.im", k + 1, k + 1);
  put(head + ",max_real\n");
  bool warned = false;
  int code = kExitOk;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (unsteady[r] > kUnsteadyLimit && !a.frozen) {
      // The rows before are kept; this one and the rest are not trustworthy.
      code = FailUnsteady(times[r], unsteady[r], fmt::format(" ({} = {})", name, values[r]));
      rows.resize(r);
      break;
    }
    std::string line = Num(values[r]);
    double rmax = -INFINITY;
    for (const auto& e : rows[r]) {
      line += fmt::format(",{},{}", Num(e.real()), Num(e.imag()));
      rmax = std::max(rmax, e.real());
    }
    put(line + fmt::format(",{}\n", Num(rmax)));
    if (unsteady[r] > kUnsteadyLimit && !warned) {
      std::fflush(out);
      fmt::print(stderr, "kanesim linearize: warning (--frozen): at {} = {}: {}\n", name, values[r],
                 UnsteadyCause(unsteady[r]));
      warned = true;
    }
  }
  if (!write_ok) {
    fmt::print(stderr, "kanesim: error: cannot write '{}': {}{}\n", out == stdout ? "stdout" : a.out_path,
               std::strerror(errno), out == stdout ? "" : " (the previous file, if any, is unchanged)");
    return kExitModelError;  // the temporary is removed
  }
  // The rows before an unsteady point are correct: kept, like run's before a failure.
  if (out != stdout && !file.Finish()) return kExitModelError;
  if (!a.html_path.empty() && !rows.empty()) {  // the rows kept, as in the table
    viz::LocusData data;
    data.title = fmt::format("Root locus of {}: {} = {}", std::filesystem::path(a.load.path).filename().string(),
                             name, a.sweep.substr(a.sweep.find('=') + 1));
    data.parameter = name;
    data.values.assign(values.begin(), values.begin() + static_cast<long>(rows.size()));
    data.eigenvalues = rows;
    std::string error;
    if (!viz::WriteLocusHtml(data, a.html_path, viz::kDebianJavaScriptRoot, &error)) {
      fmt::print(stderr, "kanesim: error: {}\n", error);
      return code == kExitOk ? kExitModelError : code;
    }
  }
  return code;
}

int RunLinearize(const LinearizeArgs& a) {
  // An output is never an input: refused before any work.
  if (!a.out_path.empty() && a.out_path != "-") {
    if (std::string in = batch::OverwrittenInput(a.out_path, {a.load.path}); !in.empty()) {
      fmt::print(stderr, "kanesim: error: -o '{}' is the model '{}'; writing there would destroy it\n", a.out_path,
                 in);
      return kExitModelError;
    }
  }
  if (!a.html_path.empty()) {
    if (std::string in = batch::OverwrittenInput(a.html_path, {a.load.path}); !in.empty()) {
      fmt::print(stderr, "kanesim: error: --html '{}' is the model '{}'; writing there would destroy it\n",
                 a.html_path, in);
      return kExitModelError;
    }
  }
  pipeline::RunSpec spec;
  if (a.solver == "dense") spec.solver = rt::SolverPath::Dense;
  if (a.solver == "sparse") spec.solver = rt::SolverPath::Sparse;
  if (a.solver == "recursive") spec.solver = rt::SolverPath::Recursive;
  std::unique_ptr<pipeline::Model> model = LoadAndCompile(a.load, spec);
  if (!model) return kExitModelError;
  // --set of a model input: loaded again with the input kept (its warnings said once above).
  LoadOptions load = a.load;
  std::vector<std::pair<std::string, double>> input_sets;
  if (!SplitInputSets(&load, spec, *model->mech, &input_sets)) return kExitModelError;
  if (!input_sets.empty()) {
    pipeline::LoadOptions lo;
    lo.model = load.model;
    lo.sets = load.sets;
    lo.urdf.floating = load.floating;
    lo.urdf.package_paths = load.package_paths;
    pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(load.path), lo, spec);
    if (!r.model) {
      std::cerr << r.diagnostics;
      return kExitModelError;
    }
    model = std::move(r.model);
  }
  const rt::Program& program = *model->program;
  std::vector<std::string> input_names;
  for (int k = 0; k < rt::NumInputs(program); ++k) input_names.push_back(rt::InputName(program, k));
  ModelInputs mi(input_names);
  const double t0 = rt::StartTime(program);
  if (!GatherInputs(*model, a.load.input_files, input_sets, t0, a.at_opt->count() > 0 ? std::max(t0, a.at) : t0, &mi))
    return kExitModelError;
  // Now that every file the model read is known: none of them (nor an input table) is an output.
  std::vector<std::string> read_files = model->mech->source_files;
  read_files.insert(read_files.end(), a.load.input_files.begin(), a.load.input_files.end());
  for (const std::string& out : {a.out_path, a.html_path}) {
    if (out.empty() || out == "-") continue;
    if (std::string in = batch::OverwrittenInput(out, read_files); !in.empty()) {
      fmt::print(stderr, "kanesim: error: {} '{}' is the model file '{}'; writing there would destroy it\n",
                 out == a.out_path ? "-o" : "--html", out, in);
      return kExitModelError;
    }
  }
  if (!(a.step > 0) || a.step > 0.1) {
    fmt::print(stderr, "kanesim: error: --step must be in (0, 0.1]\n");
    return kExitModelError;
  }
  if (!a.html_path.empty() && a.sweep.empty()) {
    fmt::print(stderr, "kanesim: error: --html writes the root locus of --sweep; add --sweep NAME=FROM:STEP:TO\n");
    return kExitModelError;
  }
  if (!a.sweep.empty()) return RunSweep(program, read_files, mi, a);

  lin::OperatingPoint op;
  lin::LinearizeOptions o;
  if (lin::Status s = OperatingPointFor(program, a, mi, true, &op, &o.input_values); !s.ok()) return Fail(s);
  o.step = a.step;
  o.inputs = a.inputs;
  o.outputs = a.outputs;
  lin::LinearModel m;
  if (lin::Status s = lin::Linearize(program, op, o, &m); !s.ok()) return Fail(s);
  lin::ComputeModes(&m);
  if (m.unsteady > kUnsteadyLimit && !a.frozen) return FailUnsteady(op.t, m.unsteady, "");
  Print(m, op);
  std::fflush(stdout);
  fmt::print(stderr, "{}", WidenedNote(m));
  if (m.unsteady > kUnsteadyLimit)
    fmt::print(stderr, "kanesim linearize: warning (--frozen): {}\n", UnsteadyCause(m.unsteady));
  if (!a.out_path.empty()) {
    Output file;
    if (!file.Open(a.out_path, read_files)) return kExitModelError;
    const std::string text = Json(m, op);
    if (std::fwrite(text.data(), 1, text.size(), file.file()) != text.size()) {
      fmt::print(stderr, "kanesim: error: cannot write '{}': {}\n", a.out_path, std::strerror(errno));
      return kExitModelError;  // the temporary is removed; the previous file stays
    }
    if (!file.Finish()) return kExitModelError;
  }
  return kExitOk;
}

}  // namespace

void AddLinearizeCommand(CLI::App& app, int* exit_code, bool options) {
  auto a = std::make_shared<LinearizeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "linearize", "Linear state-space model (A, B, C, D) about an operating point: eigenvalues, modes, root locus");
  if (!options) return;  // only its name and description (main.cpp)
  cmd->add_option("file", a->load.path, "The .mech file")->required();
  cmd->add_option("-o,--out", a->out_path, "Write the model as JSON (with --sweep: the table as CSV)");
  cmd->add_option("--model", a->load.model, "Model to linearize (default: the last one in the file)");
  AddUrdfOptions(*cmd, &a->load.floating, &a->load.stops, &a->load.package_paths);
  cmd->add_option("--set", a->load.sets, "Set a parameter, name=value (repeatable)")->allow_extra_args(false);
  a->at_opt = AddNumberOption(cmd, "--at", &a->at, "Linearize about the motion at time T (default: the start values)");
  cmd->add_flag("--equilibrium", a->equilibrium,
                "Find a static equilibrium from the start values (or from --at) and linearize about it");
  cmd->add_option("--input", a->inputs,
                  "An input besides the model's own: JOINT.tau, JOINT.tau[k] or a real parameter (repeatable)")
      ->allow_extra_args(false);
  AddInputFileOption(*cmd, &a->load.input_files);
  cmd->add_option("--output", a->outputs, "An output signal, by its exact name (repeatable)")->allow_extra_args(false);
  AddNumberOption(cmd, "--step", &a->step,
                  "Base difference step h (default 1e-3; speeds scale it by their size; a step too small to survive "
                  "rounding is widened, with a note)");
  cmd->add_option("--sweep", a->sweep, "Root locus: NAME=FROM:STEP:TO, one row of eigenvalues per value");
  cmd->add_option("--html", a->html_path,
                  "With --sweep: also write the root locus as an offline HTML page (eigenvalues in the complex plane "
                  "coloured by the parameter; real parts against it)");
  cmd->add_flag("--frozen", a->frozen,
                "Accept the eigenvalues of a frozen instant at an operating point that is neither an equilibrium nor a "
                "steady motion (a warning, exit 0; without it: exit 2)");
  cmd->add_option("--solver", a->solver, "Solution path")->check(CLI::IsMember({"auto", "dense", "sparse", "recursive"}));
  cmd->callback([a, exit_code] { *exit_code = RunLinearize(*a); });
}

}  // namespace kanesim::cli
