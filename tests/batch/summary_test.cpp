// The summary file: durable appends, torn lines dropped, resume, merge; CSV quoting.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "batch/csv_util.h"
#include "batch/summary.h"

namespace kanesim::batch {
namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Wrong if a message with commas or quotes breaks the row's columns.
TEST(Csv, QuoteRoundTrip) {
  std::string msg = "singular at t = 1, \"joint\" j";
  std::string line = "3," + QuoteCsv(msg) + ",x";
  EXPECT_EQ(SplitCsvLine(line), (std::vector<std::string>{"3", msg, "x"}));
  EXPECT_EQ(QuoteCsv("plain"), "plain");
}

// Wrong if rows finished out of order end up unsorted, or the file is not rewritten.
TEST(SummaryFile, AppendThenFinishSorted) {
  std::string path = ::testing::TempDir() + "/summary_sorted.csv";
  SummaryFile f;
  std::string err;
  ASSERT_TRUE(f.Open(path, "id,a", false, nullptr, &err)) << err;
  ASSERT_TRUE(f.Append(2, "2,z", &err));
  ASSERT_TRUE(f.Append(0, "0,x", &err));
  EXPECT_EQ(Slurp(path), "id,a\n2,z\n0,x\n");  // durable in finishing order meanwhile
  ASSERT_TRUE(f.Finish(&err));
  EXPECT_EQ(Slurp(path), "id,a\n0,x\n2,z\n");
}

// Wrong if resume keeps a torn (interrupted) last line, loses complete ones, or accepts
// a summary from another sweep.
TEST(SummaryFile, ResumeDropsTornLine) {
  std::string path = ::testing::TempDir() + "/summary_resume.csv";
  {
    std::ofstream o(path);
    o << "id,a\n0,x\n1,y\n2,z-half";
  }
  SummaryFile f;
  std::map<int, std::string> done;
  std::string err;
  ASSERT_TRUE(f.Open(path, "id,a", true, &done, &err)) << err;
  EXPECT_EQ(done.size(), 2u);
  EXPECT_EQ(Slurp(path), "id,a\n0,x\n1,y\n");
  ASSERT_TRUE(f.Append(2, "2,z", &err));
  ASSERT_TRUE(f.Finish(&err));
  EXPECT_EQ(Slurp(path), "id,a\n0,x\n1,y\n2,z\n");
  SummaryFile g;
  EXPECT_FALSE(g.Open(path, "id,b", true, &done, &err));
}

// Wrong if merging loses rows, accepts a conflicting duplicate, or objects to a
// duplicate that differs only in wall time.
TEST(MergeSummaries, UnionAndConflicts) {
  std::string d = ::testing::TempDir();
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(d + "/" + name) << text;
    return d + "/" + name;
  };
  std::string a = write("m1.csv", "id,k,wall_time\n0,1,0.5\n2,3,0.1\n");
  std::string b = write("m2.csv", "id,k,wall_time\n1,2,0.2\n2,3,0.9\n");
  std::string c = write("m3.csv", "id,k,wall_time\n1,7,0.2\n");
  std::string e = write("m4.csv", "id,q,wall_time\n5,1,0.2\n");
  SummaryTable t;
  std::string err;
  ASSERT_TRUE(MergeSummaries({a, b}, &t, &err)) << err;
  EXPECT_EQ(FormatSummary(t), "id,k,wall_time\n0,1,0.5\n1,2,0.2\n2,3,0.1\n");
  EXPECT_FALSE(MergeSummaries({b, c}, &t, &err));
  EXPECT_FALSE(MergeSummaries({a, e}, &t, &err));
}

}  // namespace
}  // namespace kanesim::batch
