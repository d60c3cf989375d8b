#include "sim/input_table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "sim/csv.h"

namespace kanesim::sim {
namespace {

// One field of a CSV line and the column (1-based) where it starts.
struct Field {
  std::string text;
  int col = 1;
};

// Splits a line at commas; a field may be double-quoted (a header "f[1,2]"), "" for a quote.
std::vector<Field> SplitCsv(std::string_view line) {
  std::vector<Field> out;
  size_t i = 0;
  for (;;) {
    Field f;
    f.col = static_cast<int>(i) + 1;
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i < line.size() && line[i] == '"') {
      for (++i; i < line.size(); ++i) {
        if (line[i] == '"' && i + 1 < line.size() && line[i + 1] == '"') f.text += '"', ++i;
        else if (line[i] == '"') { ++i; break; }
        else f.text += line[i];
      }
      while (i < line.size() && line[i] != ',') ++i;
    } else {
      size_t j = line.find(',', i);
      if (j == std::string_view::npos) j = line.size();
      std::string_view t = line.substr(i, j - i);
      while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.remove_suffix(1);
      f.text = std::string(t);
      i = j;
    }
    out.push_back(std::move(f));
    if (i >= line.size()) break;
    ++i;  // the comma
  }
  return out;
}

// A finite decimal number as the model files write them (3, -0.5, 1e-3); false otherwise.
bool ParseValue(const std::string& s, double* v) {
  const char* b = s.data();
  const char* e = b + s.size();
  if (b != e && *b == '+') ++b;
  if (b == e || !(std::isdigit(static_cast<unsigned char>(*b)) || *b == '-' || *b == '.')) return false;
  auto [p, ec] = std::from_chars(b, e, *v, std::chars_format::general);
  return ec == std::errc() && p == e && std::isfinite(*v);
}

std::string At(const std::string& path, long line, int col) {
  return path + ":" + std::to_string(line) + ":" + std::to_string(col) + ": ";
}

}  // namespace

bool InputTable::Read(const std::string& path, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot read the input table";
    return false;
  }
  File file;
  file.path = path;
  bool hold_default = false;
  std::vector<int> inputs;  // per data column (after time): input index
  std::vector<char> hold;   // ... and its interpolation
  std::string line;
  long lineno = 0;
  bool header = false;
  const int file_index = static_cast<int>(files_.size());
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (!header && line[0] == '#') {  // "# interpolation = hold|linear"; other comments ignored
      std::string s = line.substr(1);
      s.erase(std::remove_if(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t'; }), s.end());
      if (s.rfind("interpolation=", 0) == 0) {
        const std::string mode = s.substr(14);
        if (mode != "hold" && mode != "linear") {
          *error = At(path, lineno, 1) + "interpolation '" + mode + "' is not 'linear' or 'hold'";
          return false;
        }
        hold_default = mode == "hold";
      }
      continue;
    }
    std::vector<Field> fields = SplitCsv(line);
    if (!header) {
      header = true;
      if (fields[0].text != "time") {
        *error = At(path, lineno, fields[0].col) + "the first column must be 'time' (found '" + fields[0].text + "')";
        return false;
      }
      for (size_t c = 1; c < fields.size(); ++c) {
        std::string name = fields[c].text;
        bool h = hold_default;
        if (const size_t colon = name.rfind(':'); colon != std::string::npos) {
          const std::string mode = name.substr(colon + 1);
          if (mode != "hold" && mode != "linear") {
            *error = At(path, lineno, fields[c].col) + "'" + mode + "' after ':' is not 'linear' or 'hold'";
            return false;
          }
          h = mode == "hold";
          name.resize(colon);
        }
        const auto it = std::find(names_.begin(), names_.end(), name);
        if (it == names_.end()) {
          std::string known;
          for (const std::string& n : names_) known += (known.empty() ? "" : ", ") + n;
          *error = At(path, lineno, fields[c].col) + "'" + name + "' is not an input of the model" +
                   (known.empty() ? " (it has none)" : " (its inputs: " + known + ")");
          return false;
        }
        const int k = static_cast<int>(it - names_.begin());
        if (column_of_[static_cast<size_t>(k)].file >= 0 || std::find(inputs.begin(), inputs.end(), k) != inputs.end()) {
          const int other = column_of_[static_cast<size_t>(k)].file;
          *error = At(path, lineno, fields[c].col) + "input '" + name + "' is given twice" +
                   (other >= 0 ? " (also in " + files_[static_cast<size_t>(other)].path + ")" : "");
          return false;
        }
        inputs.push_back(k);
        hold.push_back(h ? 1 : 0);
      }
      for (size_t c = 0; c < inputs.size(); ++c) {
        Column& col = column_of_[static_cast<size_t>(inputs[c])];
        col.file = file_index;
        col.hold = hold[c] != 0;
        col.values.clear();
      }
      continue;
    }
    if (fields.size() != inputs.size() + 1) {
      *error = At(path, lineno, 1) + "the row has " + std::to_string(fields.size()) + " fields, the header " +
               std::to_string(inputs.size() + 1);
      return false;
    }
    for (size_t c = 0; c < fields.size(); ++c) {
      double v = 0.0;
      if (!ParseValue(fields[c].text, &v)) {
        *error = At(path, lineno, fields[c].col) + "'" + fields[c].text + "' is not a finite number";
        return false;
      }
      if (c == 0) {
        if (!file.times.empty() && !(v > file.times.back())) {
          *error = At(path, lineno, fields[c].col) + "time " + FormatShortest(v) + " does not increase (the row before is at " +
                   FormatShortest(file.times.back()) + ")";
          return false;
        }
        file.times.push_back(v);
      } else {
        column_of_[static_cast<size_t>(inputs[c - 1])].values.push_back(v);
      }
    }
  }
  if (!header || file.times.empty()) {
    *error = path + ": the input table has " + (header ? "no rows" : "no header (time,u,...)");
    for (int k : inputs) column_of_[static_cast<size_t>(k)].file = -1;
    return false;
  }
  files_.push_back(std::move(file));
  return true;
}

std::vector<std::string> InputTable::Missing() const {
  std::vector<std::string> out;
  for (size_t k = 0; k < names_.size(); ++k)
    if (column_of_[k].file < 0) out.push_back(names_[k]);
  return out;
}

std::vector<std::string> InputTable::Files() const {
  std::vector<std::string> out;
  for (const File& f : files_) out.push_back(f.path);
  return out;
}

std::string InputTable::CheckSpan(double start, double stop) const {
  for (const File& f : files_)
    if (start < f.times.front() || stop > f.times.back())
      return "the input table " + f.path + " covers " + FormatShortest(f.times.front()) + " to " +
             FormatShortest(f.times.back()) + ", not the run's " + FormatShortest(start) + " to " + FormatShortest(stop) +
             " (inputs are not extrapolated)";
  return "";
}

int InputTable::Values(double t, double* u, double* du_dt, std::string* error) const {
  for (size_t k = 0; k < names_.size(); ++k) {
    const Column& c = column_of_[k];
    if (c.file < 0) {  // never read from (the caller checked Missing)
      u[k] = du_dt[k] = 0.0;
      continue;
    }
    const std::vector<double>& ts = files_[static_cast<size_t>(c.file)].times;
    if (!(t >= ts.front() && t <= ts.back())) {
      *error = "input '" + names_[k] + "' at time " + FormatShortest(t) + ": outside its table " +
               files_[static_cast<size_t>(c.file)].path + " (" + FormatShortest(ts.front()) + " to " +
               FormatShortest(ts.back()) + "; inputs are not extrapolated)";
      return -1;
    }
    // Row i with ts[i] <= t < ts[i + 1] (the last row at its own time).
    size_t i = static_cast<size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
    if (c.hold || ts.size() == 1) {
      u[k] = c.values[i];
      du_dt[k] = 0.0;
      continue;
    }
    if (i + 1 == ts.size()) --i;  // at the end: the last segment
    const double slope = (c.values[i + 1] - c.values[i]) / (ts[i + 1] - ts[i]);
    u[k] = t == ts[i + 1] ? c.values[i + 1] : c.values[i] + (t - ts[i]) * slope;
    du_dt[k] = slope;
  }
  return 0;
}

}  // namespace kanesim::sim
