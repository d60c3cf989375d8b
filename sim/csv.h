// Signal rows and the CSV writer (DESIGN.md "Output"): a header `time,<names...>`, then
// one row per output instant, numbers with 17 significant digits so that they
// round-trip. The header and the first row are flushed at once, later rows at least every
// 50 ms and at the end, so a numerical failure keeps every row before it on disk. A process
// killed from outside leaves whole rows plus at most one last row cut short (SIGKILL may
// end a write(2) between two pages).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace kanesim::sim {

// Receives the selected signals at each output instant.
class SignalSink {
 public:
  virtual ~SignalSink() = default;
  virtual bool Begin(const std::vector<std::string>& names) = 0;  // false: cannot write
  virtual bool Row(double t, const double* values, size_t count) = 0;
  virtual bool End() { return true; }
};

// %.17g: enough digits that strtod gives back the same double.
std::string FormatNumber(double x);
// The shortest text that reads back as x (0.1, not 0.10000000000000001): for messages.
std::string FormatShortest(double x);
// A CSV field as RFC 4180 wants it: quoted when it holds a comma, quote or line break
// (signal names such as `rod.body.R[1,2]`), inner quotes doubled, line breaks blanked.
std::string QuoteCsvField(const std::string& field);

class CsvWriter final : public SignalSink {
 public:
  explicit CsvWriter(std::FILE* out) : out_(out) {}  // not owned
  bool Begin(const std::vector<std::string>& names) override;
  bool Row(double t, const double* values, size_t count) override;
  bool End() override;

 private:
  static constexpr std::chrono::milliseconds kFlushInterval{50};
  static constexpr size_t kMaxPending = 1 << 20;  // bytes of rows held at most
  bool Flush();  // the rows held, in one write, flushed
  std::FILE* out_;
  std::string rows_;  // rows not yet written (whole rows only)
  long rows_written_ = 0;
  std::chrono::steady_clock::time_point last_flush_;
};

// Keeps every row in memory (tests, sweeps).
class MemorySink final : public SignalSink {
 public:
  bool Begin(const std::vector<std::string>& signal_names) override {
    names = signal_names;
    return true;
  }
  bool Row(double t, const double* values, size_t count) override {
    times.push_back(t);
    rows.emplace_back(values, values + count);
    return true;
  }
  std::vector<std::string> names;
  std::vector<double> times;
  std::vector<std::vector<double>> rows;
};

}  // namespace kanesim::sim
