// CSV output: if these fail, numbers do not round-trip (fewer than 17 digits), the
// header is wrong, or rows sit in a buffer longer than the flush interval.
#include "sim/csv.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace kanesim::sim {
namespace {

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(SimCsv, SeventeenDigitsRoundTrip) {
  std::vector<double> xs = {0.1, 1.0 / 3.0, M_PI, -0.0, 1e-300, 4.9406564584124654e-324,
                            std::numeric_limits<double>::max(), -2.5e17, 123456789.123456789};
  std::mt19937_64 rng(20240611);  // fixed seed
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-300, 300);
  for (int i = 0; i < 10000; ++i) xs.push_back(std::ldexp(uniform(rng), exponent(rng)));
  for (double x : xs) {
    std::string s = FormatNumber(x);
    double back = std::strtod(s.c_str(), nullptr);
    ASSERT_TRUE(SameBits(x, back)) << s;
  }
}

// FormatNumber writes with std::to_chars; the text must stay what printf's "%.17g" gives
// (the CSV files of earlier versions, and the golden files, were written that way), for
// any bit pattern: NaNs, infinities, subnormals included.
TEST(SimCsv, NumbersAreExactlyPrintfSeventeenG) {
  std::mt19937_64 rng(7);
  std::vector<double> xs = {std::nan(""), -std::nan(""), HUGE_VAL, -HUGE_VAL, 0.0, -0.0, 1e16, 1e17};
  for (int i = 0; i < 200000; ++i) {
    uint64_t bits = rng();
    double x;
    std::memcpy(&x, &bits, sizeof x);
    xs.push_back(x);
  }
  char buf[64];
  for (double x : xs) {
    std::snprintf(buf, sizeof buf, "%.17g", x);
    ASSERT_EQ(FormatNumber(x), buf);
  }
}

std::string ReadAll(const char* path) {
  std::FILE* f = std::fopen(path, "r");
  std::string s;
  char buf[256];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  std::fclose(f);
  return s;
}

TEST(SimCsv, HeaderRowsFlushedFirstRowAtOnceLaterRowsWithinTheInterval) {
  char path[] = "/tmp/kanesim_csv_testXXXXXX";
  int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  std::FILE* f = fdopen(fd, "w");
  CsvWriter w(f);
  ASSERT_TRUE(w.Begin({"a.q", "b[2].u"}));
  const double row1[2] = {0.1, -1.0 / 3.0};
  ASSERT_TRUE(w.Row(0.0, row1, 2));
  // Read through another handle before End(): the header and the first row are on disk.
  const std::string first = "time,a.q,b[2].u\n0,0.10000000000000001,-0.33333333333333331\n";
  EXPECT_EQ(ReadAll(path), first);
  const double row2[2] = {2.0, 1e-300};
  ASSERT_TRUE(w.Row(0.5, row2, 2));
  // A row more than the flush interval (50 ms) after the last flush goes out with those
  // before it.
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  const double row3[2] = {-0.0, 4.9e-324};
  ASSERT_TRUE(w.Row(1.0, row3, 2));
  const std::string all3 = first + "0.5,2,1e-300\n1,-0,4.9406564584124654e-324\n";
  EXPECT_EQ(ReadAll(path), all3);
  ASSERT_TRUE(w.Row(1.5, row2, 2));  // right after a flush: buffered until End()
  ASSERT_TRUE(w.End());
  std::fclose(f);
  std::string all = ReadAll(path);
  std::remove(path);
  EXPECT_EQ(all, all3 + "1.5,2,1e-300\n");
}

// Names with commas (matrix entries) or quotes are quoted as RFC 4180 says, so that a
// CSV reader sees one column per signal.
TEST(SimCsv, HeaderNamesWithCommasAreQuoted) {
  char path[] = "/tmp/kanesim_csv_testXXXXXX";
  int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  std::FILE* f = fdopen(fd, "w");
  CsvWriter w(f);
  ASSERT_TRUE(w.Begin({"rod.body.R[1,2]", "a.q", "odd\"name"}));
  ASSERT_TRUE(w.End());
  std::fclose(f);
  std::string all = ReadAll(path);
  std::remove(path);
  EXPECT_EQ(all, "time,\"rod.body.R[1,2]\",a.q,\"odd\"\"name\"\n");
  EXPECT_EQ(QuoteCsvField("plain"), "plain");
}

}  // namespace
}  // namespace kanesim::sim
