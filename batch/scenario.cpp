#include "batch/scenario.h"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <random>
#include <set>
#include <sstream>

#include "batch/csv_util.h"
#include "flat/number.h"

namespace kanesim::batch {
namespace {

constexpr size_t kMaxValues = 1000000;

std::string Trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// The language's number syntax (flat/number.h), spaces around it allowed.
bool ParseNumber(const std::string& text, double* out) {
  std::string unused;
  return flat::ParseNumber(Trim(text), out, &unused);
}

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    size_t at = s.find(sep, start);
    parts.push_back(s.substr(start, at == std::string::npos ? std::string::npos : at - start));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return parts;
}

bool SplitNameValue(const std::string& text, std::string* name, std::string* value, std::string* error) {
  size_t eq = text.find('=');
  if (eq == std::string::npos || Trim(text.substr(0, eq)).empty()) {
    *error = "expected name=values, got '" + text + "'";
    return false;
  }
  *name = Trim(text.substr(0, eq));
  *value = text.substr(eq + 1);
  return true;
}

// A number as FormatBlocks writes it (%.17g, subnormals included: std::from_chars, not the
// language's syntax, which refuses them).
bool ParseExact(const std::string& text, double* out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *out);
  return ec == std::errc() && end == text.data() + text.size() && std::isfinite(*out);
}

// Uniform on [0, 1) from the top 53 bits of one 64-bit draw.
double Unit(std::mt19937_64& gen) { return static_cast<double>(gen() >> 11) * 0x1.0p-53; }

// Uniform integer in [0, n) without modulo bias.
std::uint64_t Below(std::mt19937_64& gen, std::uint64_t n) {
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
  std::uint64_t x;
  do x = gen();
  while (x >= limit);
  return x % n;
}

}  // namespace

bool ParseValues(const std::string& text, std::vector<double>* out, std::string* error) {
  out->clear();
  std::string t = Trim(text);
  if (t.find(':') != std::string::npos) {
    std::vector<std::string> p = Split(t, ':');
    double a = 0, step = 0, b = 0;
    if (p.size() != 3 || !ParseNumber(p[0], &a) || !ParseNumber(p[1], &step) || !ParseNumber(p[2], &b)) {
      *error = "a range is start:step:stop with three numbers, got '" + t + "'";
      return false;
    }
    if (step == 0.0 || (b - a) / step < 0.0) {
      *error = "the step of '" + t + "' does not lead from " + p[0] + " to " + p[2];
      return false;
    }
    double count = std::floor((b - a) / step + 1e-9) + 1.0;
    if (count > static_cast<double>(kMaxValues)) {
      *error = "'" + t + "' has more than a million values";
      return false;
    }
    for (long i = 0; i < static_cast<long>(count); ++i) out->push_back(a + static_cast<double>(i) * step);
    return true;
  }
  for (const std::string& item : Split(t, ',')) {
    double v = 0;
    if (!ParseNumber(item, &v)) {
      *error = "'" + Trim(item) + "' is not a number (in '" + t + "')";
      return false;
    }
    out->push_back(v);
  }
  return true;
}

bool ParseGrid(const std::string& text, Block* out, std::string* error) {
  std::string name, values;
  if (!SplitNameValue(text, &name, &values, error)) return false;
  std::vector<double> v;
  if (!ParseValues(values, &v, error)) return false;
  *out = Block{};
  out->names = {name};
  for (double x : v) out->rows.push_back({x});
  return true;
}

bool ParseDistribution(const std::string& text, Distribution::Kind kind, Distribution* out, std::string* error) {
  std::string name, values;
  if (!SplitNameValue(text, &name, &values, error)) return false;
  std::vector<std::string> p = Split(Trim(values), values.find(':') != std::string::npos ? ':' : ',');
  double a = 0, b = 0;
  if (p.size() != 2 || !ParseNumber(p[0], &a) || !ParseNumber(p[1], &b)) {
    *error = kind == Distribution::Kind::Uniform ? "--uniform needs name=low:high, got '" + text + "'"
                                                 : "--normal needs name=mean,sd, got '" + text + "'";
    return false;
  }
  if (kind == Distribution::Kind::Uniform && !(b > a)) {
    *error = "the uniform range of '" + name + "' is empty (" + p[0] + " to " + p[1] + ")";
    return false;
  }
  if (kind == Distribution::Kind::Normal && !(b >= 0.0)) {
    *error = "the standard deviation of '" + name + "' is negative";
    return false;
  }
  *out = Distribution{name, kind, a, b};
  return true;
}

double InverseNormalCdf(double p) {
  // Acklam (2003), "An algorithm for computing the inverse normal cumulative
  // distribution function": rational approximations in a central and two tail regions.
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  if (p <= 0.0) return -std::numeric_limits<double>::infinity();
  if (p >= 1.0) return std::numeric_limits<double>::infinity();
  constexpr double kLow = 0.02425;
  double x;
  if (p < kLow) {
    double q = std::sqrt(-2 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else if (p <= 1 - kLow) {
    double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  } else {
    double q = std::sqrt(-2 * std::log(1 - p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  // One Halley step on Phi(x) - p = 0, Phi(x) = erfc(-x / sqrt 2) / 2.
  double e = 0.5 * std::erfc(-x / std::numbers::sqrt2) - p;
  double u = e * std::sqrt(2 * std::numbers::pi) * std::exp(x * x / 2);
  return x - u / (1 + x * u / 2);
}

Block SampleBlock(const SampleSpec& spec) {
  Block out;
  const size_t n = static_cast<size_t>(std::max(spec.n, 0));
  for (const Distribution& d : spec.dists) out.names.push_back(d.name);
  out.rows.assign(n, std::vector<double>(spec.dists.size(), 0.0));
  std::mt19937_64 gen(spec.seed);
  for (size_t j = 0; j < spec.dists.size(); ++j) {
    const Distribution& d = spec.dists[j];
    std::vector<double> u(n);
    if (spec.latin_hypercube) {
      // Stratum k = [k/n, (k+1)/n); a random permutation assigns strata to rows
      // (Fisher-Yates), a uniform draw places the point inside its stratum.
      std::vector<size_t> perm(n);
      for (size_t i = 0; i < n; ++i) perm[i] = i;
      for (size_t i = n; i > 1; --i) std::swap(perm[i - 1], perm[Below(gen, i)]);
      for (size_t i = 0; i < n; ++i) u[i] = (static_cast<double>(perm[i]) + Unit(gen)) / static_cast<double>(n);
    } else {
      for (size_t i = 0; i < n; ++i) u[i] = Unit(gen);
    }
    for (size_t i = 0; i < n; ++i) {
      double x;
      if (d.kind == Distribution::Kind::Uniform) {
        x = d.a + (d.b - d.a) * u[i];
      } else if (spec.latin_hypercube) {
        x = d.a + d.b * InverseNormalCdf(std::clamp(u[i], 1e-300, 1.0 - 0x1.0p-53));
      } else {
        // Box-Muller, one normal per pair of uniforms (the cosine branch).
        double u1 = 1.0 - u[i];  // (0, 1]
        double u2 = Unit(gen);
        x = d.a + d.b * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
      }
      out.rows[i][j] = x;
    }
  }
  return out;
}

bool ReadListCsv(const std::string& path, Block* out, std::string* error) {
  std::string text;
  return ReadTextFile(path, kMaxDataBytes, &text, error) && ReadListCsvText(path, text, out, error);
}

bool ReadListCsvText(const std::string& path, const std::string& text, Block* out, std::string* error) {
  std::istringstream in(text);
  *out = Block{};
  std::string line;
  int line_no = 0;
  std::vector<int> column_kind;  // 0..: parameter column index; -1 stop_time, -2 rtol, -3 atol
  bool have_header = false, any_run = false;
  while (std::getline(in, line)) {
    ++line_no;
    std::string t = Trim(line);
    if (t.empty() || t[0] == '#') continue;
    std::vector<std::string> fields = SplitCsvLine(t);
    if (!have_header) {
      have_header = true;
      for (std::string f : fields) {
        f = Trim(f);
        if (f == "stop_time") column_kind.push_back(-1), any_run = true;
        else if (f == "rtol") column_kind.push_back(-2), any_run = true;
        else if (f == "atol") column_kind.push_back(-3), any_run = true;
        else if (f.empty()) {
          *error = path + ":" + std::to_string(line_no) + ": empty column name in the header";
          return false;
        } else {
          column_kind.push_back(static_cast<int>(out->names.size()));
          out->names.push_back(f);
        }
      }
      continue;
    }
    if (fields.size() != column_kind.size()) {
      *error = path + ":" + std::to_string(line_no) + ": " + std::to_string(fields.size()) + " fields, the header has " +
               std::to_string(column_kind.size());
      return false;
    }
    std::vector<double> row(out->names.size(), kUnset);
    RunOverride run;
    for (size_t c = 0; c < fields.size(); ++c) {
      double v = kUnset;
      if (!Trim(fields[c]).empty() && !ParseNumber(fields[c], &v)) {
        *error = path + ":" + std::to_string(line_no) + ": '" + Trim(fields[c]) + "' is not a number";
        return false;
      }
      int k = column_kind[c];
      if (k >= 0) row[static_cast<size_t>(k)] = v;
      else if (k == -1) run.stop_time = v;
      else if (k == -2) run.rtol = v;
      else run.atol = v;
    }
    if (out->rows.size() >= static_cast<size_t>(kMaxScenarios)) {
      *error = path + ":" + std::to_string(line_no) + ": more than " + std::to_string(kMaxScenarios) + " scenarios";
      return false;
    }
    out->rows.push_back(std::move(row));
    out->run.push_back(run);
  }
  if (!have_header) {
    *error = "'" + path + "' has no header row";
    return false;
  }
  if (!any_run) out->run.clear();
  return true;
}

bool CombineBlocks(const std::vector<Block>& blocks, std::vector<std::string>* names, std::vector<Scenario>* out,
                   std::string* error) {
  names->clear();
  out->clear();
  std::set<std::string> seen;
  double total = 1.0;
  for (const Block& b : blocks) {
    for (const std::string& n : b.names) {
      if (!seen.insert(n).second) {
        *error = "parameter '" + n + "' is given by two scenario sources";
        return false;
      }
      names->push_back(n);
    }
    total *= static_cast<double>(b.rows.size());
  }
  if (blocks.empty()) total = 0.0;
  if (!(total <= static_cast<double>(kMaxScenarios))) {  // compared as a double: never an overflowed count
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", total);
    *error = std::string("the sweep has ") + buf + " scenarios (more than " + std::to_string(kMaxScenarios) + ")";
    return false;
  }
  const size_t count = static_cast<size_t>(total);
  out->reserve(count);
  for (size_t id = 0; id < count; ++id) {
    Scenario s;
    s.id = static_cast<int>(id);
    // Mixed-radix digits of id, the last block varying fastest.
    std::vector<size_t> digit(blocks.size());
    size_t rest = id;
    for (size_t b = blocks.size(); b-- > 0;) {
      digit[b] = rest % blocks[b].rows.size();
      rest /= blocks[b].rows.size();
    }
    for (size_t b = 0; b < blocks.size(); ++b) {
      const std::vector<double>& row = blocks[b].rows[digit[b]];
      s.values.insert(s.values.end(), row.begin(), row.end());
      if (!blocks[b].run.empty()) {
        const RunOverride& r = blocks[b].run[digit[b]];
        if (!std::isnan(r.stop_time)) s.run.stop_time = r.stop_time;
        if (!std::isnan(r.rtol)) s.run.rtol = r.rtol;
        if (!std::isnan(r.atol)) s.run.atol = r.atol;
      }
    }
    out->push_back(std::move(s));
  }
  return true;
}

std::string FormatBlocks(const std::vector<Block>& blocks) {
  auto num = [](double v) { return std::isnan(v) ? std::string() : sim::FormatNumber(v); };
  std::string out = "# kanesim sweep: the scenario sources of the summary beside this file (sweep merge reads it)\n";
  for (const Block& b : blocks) {
    const bool run = !b.run.empty();
    out += "block " + std::to_string(b.names.size()) + " " + std::to_string(b.rows.size()) + (run ? " 1\n" : " 0\n");
    for (size_t j = 0; j < b.names.size(); ++j) out.append(j ? "," : "").append(QuoteCsv(b.names[j]));
    out += "\n";
    for (size_t i = 0; i < b.rows.size(); ++i) {
      for (size_t j = 0; j < b.rows[i].size(); ++j) out.append(j ? "," : "").append(num(b.rows[i][j]));
      if (run)
        for (double v : {b.run[i].stop_time, b.run[i].rtol, b.run[i].atol}) out.append(",").append(num(v));
      out += "\n";
    }
  }
  return out;
}

bool ParseBlocks(const std::string& text, std::vector<Block>* out, std::string* error) {
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& why) {
    *error = "line " + std::to_string(line_no) + ": " + why;
    return false;
  };
  out->clear();
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    size_t ncols = 0, nrows = 0;
    int run = 0, used = 0;
    if (std::sscanf(line.c_str(), "block %zu %zu %d%n", &ncols, &nrows, &run, &used) != 3 ||
        used != static_cast<int>(line.size()) || nrows > static_cast<size_t>(kMaxScenarios) || ncols > kMaxValues)
      return fail("expected 'block NCOLS NROWS RUN'");
    Block b;
    if (!std::getline(in, line)) return fail("the block has no names");
    ++line_no;
    b.names = SplitCsvLine(line);
    if (b.names.size() != ncols) return fail("expected " + std::to_string(ncols) + " names");
    const size_t fields = ncols + (run ? 3 : 0);
    for (size_t i = 0; i < nrows; ++i) {
      if (!std::getline(in, line)) return fail("the block ends early");
      ++line_no;
      std::vector<std::string> f = SplitCsvLine(line);
      if (f.size() != fields) return fail("expected " + std::to_string(fields) + " fields");
      std::vector<double> v(fields, kUnset);
      for (size_t j = 0; j < fields; ++j)
        if (!f[j].empty() && !ParseExact(f[j], &v[j])) return fail("'" + f[j] + "' is not a number");
      b.rows.emplace_back(v.begin(), v.begin() + static_cast<long>(ncols));
      if (run) b.run.push_back(RunOverride{v[ncols], v[ncols + 1], v[ncols + 2]});
    }
    out->push_back(std::move(b));
  }
  return true;
}

std::string ScenarioDefinitionsDigest(const std::vector<std::string>& names, const std::vector<Scenario>& scenarios) {
  std::string defs;
  for (size_t j = 0; j < names.size(); ++j) defs.append(j ? "; " : "").append(names[j]);
  defs += "\n";
  for (const Scenario& sc : scenarios) {
    for (double v : sc.values) defs.append(sim::FormatNumber(v)).append(",");
    for (double v : {sc.run.stop_time, sc.run.rtol, sc.run.atol}) defs.append(sim::FormatNumber(v)).append(",");
    defs.append("\n");
  }
  return std::to_string(scenarios.size()) + " fnv1a64:" + Fnv1a64Hex(defs);
}

}  // namespace kanesim::batch
