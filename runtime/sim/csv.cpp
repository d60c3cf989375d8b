#include "runtime/sim/csv.h"

#include <charconv>
#include <cstdio>
#include <string>
#include <vector>

namespace kanesim::sim {

static void AppendNumber(std::string* line, double x) {
  char buf[32];
  int len = std::snprintf(buf, sizeof buf, "%.17g", x);
  line->append(buf, static_cast<size_t>(len));
}

std::string FormatNumber(double x) {
  std::string s;
  AppendNumber(&s, x);
  return s;
}

std::string FormatShortest(double x) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  return ec == std::errc() ? std::string(buf, end) : FormatNumber(x);
}

std::string QuoteCsvField(const std::string& field) {
  if (field.find_first_of(",\"\n\r") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  out += '"';
  return out;
}

bool CsvWriter::Begin(const std::vector<std::string>& names) {
  line_ = "time";
  for (const std::string& name : names) {
    line_ += ',';
    line_ += QuoteCsvField(name);
  }
  line_ += '\n';
  return Flush();
}

bool CsvWriter::Row(double t, const double* values, size_t count) {
  line_.clear();
  AppendNumber(&line_, t);
  for (size_t i = 0; i < count; ++i) {
    line_ += ',';
    AppendNumber(&line_, values[i]);
  }
  line_ += '\n';
  return Flush();
}

bool CsvWriter::End() { return std::fflush(out_) == 0 && !std::ferror(out_); }

bool CsvWriter::Flush() {
  if (std::fwrite(line_.data(), 1, line_.size(), out_) != line_.size()) return false;
  return std::fflush(out_) == 0;
}

}  // namespace kanesim::sim
