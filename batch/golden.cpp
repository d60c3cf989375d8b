#include "batch/golden.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <toml++/toml.h>

#include "batch/toml_util.h"

#include "batch/csv_util.h"
#include "flat/number.h"
#include "sim/csv.h"
#include "sim/signal_select.h"

namespace kanesim::batch {
namespace {

std::string Resolve(const std::string& base_file, const std::string& rel) { return ResolveRelative(base_file, rel); }
std::string Where(const std::string& path, const toml::node& n) { return TomlWhere(path, n); }

bool ReadTolerance(const std::string& path, const std::string& pattern, const toml::node& n, Tolerance* out,
                   std::string* error) {
  const toml::table* t = n.as_table();
  if (!t) {
    *error = Where(path, n) + "tolerance for '" + pattern + "' must be { abs = A, rel = R }";
    return false;
  }
  for (const auto& [k, v] : *t) {
    if (k.str() != "abs" && k.str() != "rel") {
      *error = Where(path, v) + "unknown tolerance key '" + std::string(k.str()) + "' (abs, rel)";
      return false;
    }
  }
  out->pattern = pattern;
  for (auto [key, field] : {std::pair{"abs", &out->abs}, {"rel", &out->rel}}) {
    const toml::node* v = t->get(key);
    if (!v) continue;
    auto d = v->value<double>();
    if (!d || !std::isfinite(*d) || *d < 0) {
      *error = Where(path, *v) + "tolerance " + key + " for '" + pattern + "' must be a finite number >= 0";
      return false;
    }
    *field = *d;
  }
  if (out->abs == 0 && out->rel == 0) {
    *error = Where(path, n) + "tolerance for '" + pattern + "' must have abs or rel > 0";
    return false;
  }
  return true;
}

// A stored number: the language's syntax (what %.17g writes for a finite value); a
// stored output holds finite values only.
double Num(const std::string& s, bool* ok) {
  double v = 0.0;
  std::string unused;
  *ok = flat::ParseNumber(s, &v, &unused);
  return v;
}

const Tolerance& ToleranceFor(const GoldenSpec& spec, const std::string& name) {
  const Tolerance* t = &spec.default_tol;
  for (const Tolerance& x : spec.tolerances)
    if (sim::GlobMatch(x.pattern, name)) t = &x;
  return *t;
}

}  // namespace

int Trajectory::Column(const std::string& name) const {
  auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

bool ReadGoldenSpec(const std::string& path, GoldenSpec* out, std::string* error) {
  std::string text;
  return ReadTextFile(path, kMaxSpecBytes, &text, error) && ReadGoldenSpecText(path, text, out, error);
}

bool ReadGoldenSpecText(const std::string& path, const std::string& text, GoldenSpec* out, std::string* error) {
  toml::table root;
  if (!ParseTomlText(path, text, &root, error)) return false;
  *out = GoldenSpec{};
  out->spec_path = path;
  out->name = std::filesystem::path(path).stem().string();
  if (!OnlyKnownKeys(path, root,
                     {"model", "model_name", "golden", "set", "run", "signals", "tolerance", "invariant", "input_files"},
                     error))
    return false;
  std::string model, golden = out->name + ".csv";
  auto string = [&](const char* key, std::string* field) { return OptionalTomlString(path, root, key, field, error); };
  if (!string("model", &model) || !string("golden", &golden) || !string("model_name", &out->model_name))
    return false;
  if (model.empty()) {
    *error = path + ": the spec needs model = \"path/to/file.mech\"";
    return false;
  }
  out->model = Resolve(path, model);
  out->golden_path = Resolve(path, golden);
  if (const toml::node* set = root.get("set")) {
    if (!ReadSetTable(path, *set, &out->sets, error)) return false;
  }
  std::vector<std::string> input_files;  // the model's input tables (--input-file)
  if (!OptionalTomlStrings(path, root, "input_files", "file names", &input_files, error)) return false;
  for (const std::string& f : input_files) out->input_files.push_back(Resolve(path, f));
  if (const toml::table* run = root["run"].as_table()) {
    for (const auto& [k, v] : *run) {
      std::string key(k.str());
      if (key == "integrator" || key == "solver" || key == "energy_check") {
        auto s = v.value<std::string>();
        if (!s) {
          *error = Where(path, v) + key + " must be a string";
          return false;
        }
        (key == "integrator" ? out->integrator : key == "solver" ? out->solver : out->energy_check) = *s;
        continue;
      }
      double* field = key == "start_time" ? &out->start_time
                      : key == "stop_time" ? &out->stop_time
                      : key == "interval"  ? &out->interval
                      : key == "rtol"      ? &out->rtol
                      : key == "atol"      ? &out->atol
                                           : nullptr;
      auto d = v.value<double>();
      if (!field || !d || !std::isfinite(*d)) {
        *error = Where(path, v) + "run." + key +
                 (field ? " must be a finite number" : ": unknown (start_time, stop_time, interval, rtol, atol, integrator, "
                                                       "solver, energy_check)");
        return false;
      }
      if (field != &out->start_time && field != &out->stop_time && !(*d > 0.0)) {
        *error = Where(path, v) + "run." + key + " must be positive";
        return false;
      }
      *field = *d;
    }
    if (out->stop_time < out->start_time) {  // false when either is not given (NaN)
      *error = path + ": run.stop_time (" + sim::FormatNumber(out->stop_time) + ") is before run.start_time (" +
               sim::FormatNumber(out->start_time) + ")";
      return false;
    }
  } else if (root.get("run")) {
    *error = Where(path, *root.get("run")) + "run must be a table ([run])";
    return false;
  }
  if (!OptionalTomlStrings(path, root, "signals", "names or globs", &out->signals, error)) return false;
  for (const char* key : {"tolerance", "invariant"}) {
    const toml::node* n = root.get(key);
    if (n && !(key == std::string("tolerance") ? n->is_table() : n->is_array_of_tables())) {
      *error = Where(path, *n) + key + (key == std::string("tolerance") ? " must be a table ([tolerance])"
                                                                          : " must be an array of tables ([[invariant]])");
      return false;
    }
  }
  if (const toml::table* tol = root["tolerance"].as_table()) {
    for (const auto& [k, v] : *tol) {
      Tolerance t;
      if (!ReadTolerance(path, std::string(k.str()), v, &t, error)) return false;
      if (k.str() == "default")
        out->default_tol = Tolerance{"*", t.abs, t.rel};
      else
        out->tolerances.push_back(t);
    }
  }
  if (const toml::array* inv = root["invariant"].as_array()) {
    for (const toml::node& n : *inv) {
      const toml::table* t = n.as_table();
      auto kind = t ? (*t)["kind"].value<std::string>() : std::nullopt;
      auto tolv = t ? (*t)["tol"].value<double>() : std::nullopt;
      if (!kind || !tolv || !(*tolv > 0) || !std::isfinite(*tolv)) {
        *error = Where(path, n) + "an [[invariant]] needs kind = \"...\" and a finite tol > 0";
        return false;
      }
      for (const auto& [k, v] : *t) {
        const std::string key(k.str());
        if (key != "kind" && key != "tol" && key != "from" && key != "to") {
          *error = Where(path, v) + "unknown invariant key '" + key + "' (kind, tol, from, to)";
          return false;
        }
        if ((key == "from" || key == "to") && !(v.value<double>() && std::isfinite(*v.value<double>()))) {
          *error = Where(path, v) + "invariant " + key + " must be a finite number (a time)";
          return false;
        }
      }
      if (*kind != "energy_balance" && *kind != "constraint_residual" && *kind != "constraint_work") {
        *error = Where(path, n) + "unknown invariant '" + *kind +
                 "' (energy_balance, constraint_residual, constraint_work)";
        return false;
      }
      Invariant iv{*kind, *tolv, (*t)["from"].value_or(kUnset), (*t)["to"].value_or(kUnset)};
      if (iv.to < iv.from) {
        *error = Where(path, n) + "the invariant's window is empty (to < from)";
        return false;
      }
      out->invariants.push_back(iv);
    }
  }
  return true;
}

std::string SettingsText(const GoldenSpec& s) {
  std::string t = "model_name=" + s.model_name + ";";
  for (const std::string& x : s.sets) t += "set " + x + ";";
  for (double v : {s.start_time, s.stop_time, s.interval, s.rtol, s.atol}) t += sim::FormatNumber(v) + ";";
  t += s.integrator + ";" + s.solver + ";";
  // Only when not the default, so that the settings lines recorded before the key existed stay valid.
  if (s.energy_check != "on") t += "energy_check=" + s.energy_check + ";";
  for (const std::string& x : s.signals) t += x + ";";
  // The input tables by content (absent before the key existed: older settings lines stay valid).
  for (const std::string& f : s.input_files) {
    std::string text, why;
    const std::string hash = ReadTextFile(f, kMaxDataBytes, &text, &why) ? "fnv1a64:" + Fnv1a64Hex(text) : "unreadable";
    t += "input_file=" + std::filesystem::path(f).filename().string() + " " + hash + ";";
  }
  return t;
}

bool ReadTrajectoryCsv(const std::string& path, Trajectory* out, std::string* error) {
  std::string text;
  return ReadTextFile(path, kMaxDataBytes, &text, error) && ReadTrajectoryCsvText(path, text, out, error);
}

bool ReadTrajectoryCsvText(const std::string& path, const std::string& text, Trajectory* out, std::string* error) {
  *out = Trajectory{};
  auto fail = [&](int line_no, const std::string& why) {
    *error = path + (line_no > 0 ? ":" + std::to_string(line_no) : std::string()) + ": " + why;
    return false;
  };
  if (!text.empty() && text.back() != '\n') return fail(0, "the last line is cut off (no line break at the end)");
  bool header = false;
  int line_no = 0;
  size_t data_begin = std::string::npos;
  for (size_t pos = 0; pos < text.size();) {
    const size_t nl = text.find('\n', pos);
    std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (line[0] == '#') {
      size_t eq = line.find('=');
      if (eq != std::string::npos) {
        auto trim = [](std::string s) {
          size_t b = s.find_first_not_of(" #"), e = s.find_last_not_of(' ');
          return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
        };
        out->provenance[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
      }
      continue;
    }
    std::vector<std::string> f = SplitCsvLine(line);
    if (!header) {
      if (f.empty() || f[0] != "time") return fail(line_no, "the header must start with 'time'");
      out->names.assign(f.begin() + 1, f.end());
      header = true;
      data_begin = pos;
      continue;
    }
    if (f.size() != out->names.size() + 1)
      return fail(line_no, std::to_string(f.size()) + " fields, expected " + std::to_string(out->names.size() + 1));
    std::vector<double> row(out->names.size());
    bool ok = true;
    double t = Num(f[0], &ok);
    for (size_t j = 0; ok && j < row.size(); ++j) row[j] = Num(f[j + 1], &ok);
    if (!ok) return fail(line_no, "a field is not a finite number");
    // An event's time stands twice (its left and right limits, docs/events.md).
    if (!out->t.empty() && !(t >= out->t.back())) return fail(line_no, "the times do not increase");
    out->t.push_back(t);
    out->rows.push_back(std::move(row));
  }
  if (!header) return fail(0, "no header");
  if (out->t.empty()) return fail(0, "no rows (a run writes at least the start instant)");
  // What the recording said about itself (goldens recorded since these lines exist).
  auto rows = out->provenance.find("rows");
  if (rows != out->provenance.end() && rows->second != std::to_string(out->t.size()))
    return fail(0, std::to_string(out->t.size()) + " rows, but it was recorded with " + rows->second +
                       " (truncated?)");
  auto data = out->provenance.find("data");
  if (data != out->provenance.end() && data->second != "fnv1a64:" + Fnv1a64Hex(text.substr(data_begin)))
    return fail(0, "its rows do not match the checksum recorded with them (edited or damaged?)");
  return true;
}

std::string FormatTrajectoryCsv(const Trajectory& tr) {
  std::string rows;
  for (size_t k = 0; k < tr.t.size(); ++k) {
    rows.append(sim::FormatNumber(tr.t[k]));
    for (double v : tr.rows[k]) rows.append(",").append(sim::FormatNumber(v));
    rows.append("\n");
  }
  std::map<std::string, std::string> provenance = tr.provenance;
  provenance["rows"] = std::to_string(tr.t.size());
  provenance["data"] = "fnv1a64:" + Fnv1a64Hex(rows);
  std::string s;
  for (const auto& [k, v] : provenance) s.append("# ").append(k).append(" = ").append(v).append("\n");
  s.append("time");
  for (const std::string& n : tr.names) s.append(",").append(QuoteCsv(n));
  s.append("\n");
  return s + rows;
}

std::string CompareGrids(const Trajectory& golden, const Trajectory& run) {
  if (golden.t.size() == run.t.size() && !run.t.empty() && golden.t.front() == run.t.front() &&
      golden.t.back() == run.t.back())
    return "";
  auto span = [](const Trajectory& t) {
    return std::to_string(t.t.size()) + " instant" + (t.t.size() == 1 ? "" : "s") +
           (t.t.empty() ? std::string() : " over [" + sim::FormatNumber(t.t.front()) + ", " +
                                               sim::FormatNumber(t.t.back()) + "]");
  };
  return "the golden holds " + span(golden) + ", the run " + span(run) +
         " (the model's experiment or the output grid changed, or the golden is incomplete)";
}

double Interpolate(const Trajectory& tr, int j, double t) {
  const auto c = static_cast<size_t>(j);
  if (tr.t.empty()) return std::nan("");
  if (t <= tr.t.front()) return tr.rows.front()[c];
  if (t >= tr.t.back()) return tr.rows.back()[c];
  size_t hi = static_cast<size_t>(std::upper_bound(tr.t.begin(), tr.t.end(), t) - tr.t.begin());
  size_t lo = hi - 1;
  const double t0 = tr.t[lo], t1 = tr.t[hi];
  if (t == t0 || t1 == t0) return tr.rows[lo][c];
  const double w = (t - t0) / (t1 - t0);
  return (1.0 - w) * tr.rows[lo][c] + w * tr.rows[hi][c];
}

namespace {

// The run's row for golden row k when k is one of an event's two rows (its time twice: the
// left limit, then the right): the same side of the run's event nearest in time between the
// golden's neighbouring instants, so an event a round-off apart is compared across the same
// jump; -1 for other rows, or when the run has no event there (then it is interpolated).
long EventRow(const Trajectory& golden, size_t k, const Trajectory& run) {
  const std::vector<double>& t = golden.t;
  const bool right = k > 0 && t[k - 1] == t[k];
  if (!right && !(k + 1 < t.size() && t[k + 1] == t[k])) return -1;
  const size_t left_row = right ? k - 1 : k;
  const double lo = left_row > 0 ? t[left_row - 1] : -INFINITY;
  const double hi = left_row + 2 < t.size() ? t[left_row + 2] : INFINITY;
  long best = -1;
  for (size_t i = static_cast<size_t>(std::upper_bound(run.t.begin(), run.t.end(), lo) - run.t.begin());
       i + 1 < run.t.size() && run.t[i] < hi; ++i)
    if (run.t[i + 1] == run.t[i] &&
        (best < 0 || std::abs(run.t[i] - t[k]) < std::abs(run.t[static_cast<size_t>(best)] - t[k])))
      best = static_cast<long>(i);
  return best < 0 ? -1 : best + (right ? 1 : 0);
}

}  // namespace

CompareResult Compare(const GoldenSpec& spec, const Trajectory& golden, const Trajectory& actual) {
  CompareResult r;
  for (const std::string& n : actual.names)
    if (golden.Column(n) < 0) r.problems.push_back("signal '" + n + "' is new (not in the golden)");
  if (!golden.t.empty() && !actual.t.empty()) {
    // A run that ends early cannot be compared past its end (a 1e-9 relative slack for
    // the printed stop time).
    const double slack = 1e-9 * std::max(1.0, std::abs(golden.t.back()));
    if (actual.t.back() < golden.t.back() - slack || actual.t.front() > golden.t.front() + slack)
      r.problems.push_back("the run covers [" + sim::FormatNumber(actual.t.front()) + ", " +
                           sim::FormatNumber(actual.t.back()) + "], the golden [" +
                           sim::FormatNumber(golden.t.front()) + ", " + sim::FormatNumber(golden.t.back()) + "]");
  }
  if (actual.t.empty()) r.problems.push_back("the run produced no rows");
  for (size_t g = 0; g < golden.names.size(); ++g) {
    const std::string& name = golden.names[g];
    int a = actual.Column(name);
    if (a < 0) {
      r.problems.push_back("signal '" + name + "' is missing from the run");
      continue;
    }
    if (actual.t.empty()) continue;
    const Tolerance& tol = ToleranceFor(spec, name);
    SignalDeviation d;
    d.signal = name;
    for (size_t k = 0; k < golden.t.size(); ++k) {
      const double t = golden.t[k];
      const double gv = golden.rows[k][g];
      const long e = EventRow(golden, k, actual);
      const double av = e >= 0 ? actual.rows[static_cast<size_t>(e)][static_cast<size_t>(a)] : Interpolate(actual, a, t);
      const double dev = std::abs(av - gv);
      const double allowed = tol.abs + tol.rel * std::abs(gv);
      const double ratio = std::isnan(dev) ? std::numeric_limits<double>::infinity() : dev / allowed;
      if (ratio > d.worst_ratio || (k == 0 && std::isnan(dev))) {
        d.worst_ratio = ratio;
        d.max_dev = dev;
        d.t_max = t;
        d.tol_at_max = allowed;
      }
      if (ratio > 1.0 && std::isnan(d.first_exceed)) d.first_exceed = t;
    }
    r.signals.push_back(d);
  }
  r.pass = r.problems.empty();
  for (const SignalDeviation& d : r.signals) r.pass = r.pass && !d.failed();
  return r;
}

std::vector<std::string> InvariantSignals(const Invariant& inv, const std::vector<std::string>& available) {
  std::vector<std::string> want;
  if (inv.kind == "energy_balance") want = {"kinetic_energy", "potential_energy"};
  else if (inv.kind == "constraint_work") want = {"constraint_power", "kinetic_energy"};
  std::vector<std::string> out;
  if (inv.kind == "constraint_residual") {
    for (const std::string& n : available)
      if (sim::GlobMatch("*constraint_residual*", n)) out.push_back(n);
    return out;
  }
  for (const std::string& w : want)
    if (std::find(available.begin(), available.end(), w) == available.end()) return {};
  return want;
}

InvariantResult CheckInvariant(const Invariant& inv, const Trajectory& run, const std::vector<std::string>& available) {
  InvariantResult r;
  std::vector<std::string> need = InvariantSignals(inv, available);
  if (need.empty()) {
    r.status = InvariantResult::Status::kSkipped;
    r.text = inv.kind + ": skipped (the runtime provides no " +
             (inv.kind == "energy_balance" ? std::string("energy signals")
              : inv.kind == "constraint_work" ? std::string("constraint_power signal")
                                              : std::string("constraint_residual signals")) +
             " for this model yet)";
    return r;
  }
  auto in_window = [&](double t) {
    return (std::isnan(inv.from) || t >= inv.from) && (std::isnan(inv.to) || t <= inv.to);
  };
  if (std::none_of(run.t.begin(), run.t.end(), in_window)) {
    r.status = InvariantResult::Status::kFail;
    r.text = inv.kind + ": no output instant in its window [" + sim::FormatNumber(inv.from) + ", " +
             sim::FormatNumber(inv.to) + "], so nothing was checked";
    return r;
  }
  char buf[256];
  if (inv.kind == "energy_balance") {
    // max_t |E(t) - E(t0)| <= tol * scale, E = KE + PE, scale = max(max_t KE, |E(t0)|):
    // the energy drift relative to the energy that moves.
    const int ke = run.Column("kinetic_energy"), pe = run.Column("potential_energy");
    double e0 = std::nan(""), scale = 0.0, worst = 0.0, t_worst = 0.0;
    for (size_t k = 0; k < run.t.size(); ++k) {
      if (!in_window(run.t[k])) continue;
      const double e = run.rows[k][static_cast<size_t>(ke)] + run.rows[k][static_cast<size_t>(pe)];
      if (std::isnan(e0)) e0 = e;
      scale = std::max({scale, std::abs(run.rows[k][static_cast<size_t>(ke)]), std::abs(e0)});
      if (std::abs(e - e0) > worst || std::isnan(e)) worst = std::abs(e - e0), t_worst = run.t[k];
    }
    const double rel = scale > 0 ? worst / scale : worst;
    std::snprintf(buf, sizeof buf, "energy_balance: max |E - E0| = %.3g (%.3g of the energy scale %.3g) at t = %.6g, tol %.3g",
                  worst, rel, scale, t_worst, inv.tol);
    r.status = rel <= inv.tol ? InvariantResult::Status::kPass : InvariantResult::Status::kFail;
  } else if (inv.kind == "constraint_residual") {
    double worst = 0.0, t_worst = 0.0;
    std::string which;
    for (const std::string& n : need) {
      const auto c = static_cast<size_t>(run.Column(n));
      for (size_t k = 0; k < run.t.size(); ++k)
        if (in_window(run.t[k]) && !(std::abs(run.rows[k][c]) <= worst))
          worst = std::abs(run.rows[k][c]), t_worst = run.t[k], which = n;
    }
    std::snprintf(buf, sizeof buf, "constraint_residual: max |%s| = %.3g at t = %.6g, tol %.3g", which.c_str(), worst,
                  t_worst, inv.tol);
    r.status = worst <= inv.tol ? InvariantResult::Status::kPass : InvariantResult::Status::kFail;
  } else {
    // Work of the constraint forces, trapezoid over constraint_power, relative to the
    // largest kinetic energy: ideal constraints do no work.
    const auto p = static_cast<size_t>(run.Column("constraint_power"));
    const auto ke = static_cast<size_t>(run.Column("kinetic_energy"));
    double work = 0.0, worst = 0.0, scale = 0.0;
    for (size_t k = 0; k < run.t.size(); ++k) {
      if (!in_window(run.t[k])) continue;
      scale = std::max(scale, std::abs(run.rows[k][ke]));
      if (k > 0 && in_window(run.t[k - 1])) work += 0.5 * (run.t[k] - run.t[k - 1]) * (run.rows[k][p] + run.rows[k - 1][p]);
      worst = std::max(worst, std::abs(work));
    }
    const double rel = scale > 0 ? worst / scale : worst;
    std::snprintf(buf, sizeof buf, "constraint_work: max |W| = %.3g (%.3g of max kinetic energy), tol %.3g", worst, rel,
                  inv.tol);
    r.status = rel <= inv.tol ? InvariantResult::Status::kPass : InvariantResult::Status::kFail;
  }
  r.text = buf;
  return r;
}

}  // namespace kanesim::batch
