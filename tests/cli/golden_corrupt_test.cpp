// Item 11 of issue 24: a golden test must not pass against a stored output that cannot
// guard anything, and must say which of three things happened:
//   - the stored file is corrupt (cut off, header only, non-finite or non-numeric values,
//     times out of order, rows or checksum unlike its recording): ERROR, exit 1, with
//     "corrupt" and no advice to --update (which would overwrite the evidence);
//   - it is intact but covers other instants than the run (one row of an older
//     recording cut at a row boundary, without the row count): FAIL, exit 3;
//   - the spec's own settings are impossible (times, tolerances): ERROR, exit 1.
#include <gtest/gtest.h>

#include <functional>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

const std::string kSpec =
    "model = \"" + kSrc + "/examples/spring_mass.mech\"\n[run]\nstop_time = 1\ninterval = 0.05\n"
    "[tolerance]\ndefault = { abs = 1e-8, rel = 1e-7 }\n";

// Lines of a recorded golden: provenance, header, rows.
struct Golden {
  std::vector<std::string> head, rows;  // head: '#' lines and the header
  std::string Text() const {
    std::string s;
    for (const auto& l : head) s += l + "\n";
    for (const auto& l : rows) s += l + "\n";
    return s;
  }
};

Golden Parse(const std::string& text) {
  Golden g;
  size_t pos = 0;
  bool header = false;
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (!header) {
      g.head.push_back(line);
      header = line.rfind("time", 0) == 0;
    } else {
      g.rows.push_back(line);
    }
  }
  return g;
}

std::string Record(const std::string& d) {
  Write(d + "/g.toml", kSpec);
  Result r = Kanesim("test --update g.toml", d);
  EXPECT_EQ(r.rc, 0) << r.out << r.err;
  return Slurp(d + "/g.csv");
}

// Corruptions of a recorded golden, each named.
std::vector<std::pair<std::string, std::function<std::string(const Golden&)>>> Corruptions() {
  std::vector<std::pair<std::string, std::function<std::string(const Golden&)>>> c;
  for (std::string bad : {"inf", "-inf", "nan", "1e400", "0x10", "", "1.0.0"})
    c.push_back({"value " + bad, [bad](const Golden& g) {
                   Golden h = g;
                   std::string& row = h.rows[7];
                   row = row.substr(0, row.rfind(',') + 1) + bad;
                   return h.Text();
                 }});
  c.push_back({"header only", [](const Golden& g) {
                 Golden h = g;
                 h.rows.clear();
                 return h.Text();
               }});
  for (size_t keep : {1, 2, 10, 20})
    c.push_back({"cut after row " + std::to_string(keep), [keep](const Golden& g) {
                   Golden h = g;
                   h.rows.resize(keep);
                   return h.Text();
                 }});
  c.push_back({"cut inside a number", [](const Golden& g) {
                 std::string t = g.Text();
                 return t.substr(0, t.size() - 5);
               }});
  c.push_back({"a digit changed", [](const Golden& g) {
                 Golden h = g;
                 std::string& row = h.rows[5];
                 char& ch = row[row.size() - 2];
                 ch = ch == '1' ? '2' : '1';
                 return h.Text();
               }});
  c.push_back({"two rows swapped", [](const Golden& g) {
                 Golden h = g;
                 std::swap(h.rows[3], h.rows[4]);
                 return h.Text();
               }});
  c.push_back({"a row duplicated", [](const Golden& g) {
                 Golden h = g;
                 h.rows.insert(h.rows.begin() + 3, h.rows[3]);
                 return h.Text();
               }});
  return c;
}

TEST(GoldenCorrupt, EveryCorruptionIsAnErrorThatSaysCorrupt) {
  std::string d = Work("golden_corrupt");
  const Golden recorded = Parse(Record(d));
  ASSERT_EQ(recorded.rows.size(), 21u);
  for (const auto& [name, corrupt] : Corruptions()) {
    const std::string text = corrupt(recorded);
    Write(d + "/g.csv", text);
    Result r = Kanesim("test g.toml", d);
    EXPECT_EQ(r.rc, 1) << name << "\n" << r.out;
    EXPECT_TRUE(Has(r.out, "ERROR") && Has(r.out, "corrupt")) << name << "\n" << r.out;
    EXPECT_FALSE(Has(r.out, "--update")) << name << ": steers to overwriting the evidence\n" << r.out;
    EXPECT_EQ(Slurp(d + "/g.csv"), text) << name << ": the stored file was changed";
  }
}

// An older recording (no `rows` and `data` lines) cut at a row boundary is intact as a
// file, but covers less than the run: a failure, never a pass.
TEST(GoldenCorrupt, OlderRecordingCutAtARowBoundaryFails) {
  std::string d = Work("golden_old");
  Golden g = Parse(Record(d));
  std::vector<std::string> head;
  for (const auto& l : g.head)
    if (l.rfind("# rows", 0) != 0 && l.rfind("# data", 0) != 0) head.push_back(l);
  g.head = head;
  for (size_t keep : {1, 2, 20}) {
    Golden h = g;
    h.rows.resize(keep);
    Write(d + "/g.csv", h.Text());
    Result r = Kanesim("test g.toml", d);
    EXPECT_EQ(r.rc, 3) << keep << "\n" << r.out;
    EXPECT_TRUE(Has(r.out, "the golden holds " + std::to_string(keep) + " instant")) << r.out;
  }
  Write(d + "/g.csv", g.Text());  // whole: still passes
  EXPECT_EQ(Kanesim("test g.toml", d).rc, 0);
}

// The spec's own mistakes are errors (exit 1), never regressions (exit 3), and a
// tolerance that cannot fail (inf, nan) is refused.
TEST(GoldenCorrupt, ImpossibleSpecSettingsAreErrors) {
  std::string d = Work("golden_spec");
  Record(d);
  const std::vector<std::string> bad_run = {"stop_time = -1", "stop_time = inf", "stop_time = nan", "stop_time = 1e19",
                                            "interval = 0", "interval = -0.1", "interval = 1e-19", "interval = inf",
                                            "rtol = 0", "rtol = -1e-6", "atol = nan", "start_time = 2"};
  for (const std::string& line : bad_run) {
    std::string spec = kSpec;
    const std::string key = line.substr(0, line.find(' '));
    size_t at = spec.find(key + " =");
    spec = at == std::string::npos ? spec.insert(spec.find("[run]\n") + 6, line + "\n")
                                   : spec.replace(at, spec.find('\n', at) - at, line);
    Write(d + "/b.toml", spec);
    std::filesystem::copy_file(d + "/g.csv", d + "/b.csv", std::filesystem::copy_options::overwrite_existing);
    Result r = Kanesim("test b.toml", d);
    EXPECT_EQ(r.rc, 1) << line << "\n" << r.out << r.err;
    EXPECT_TRUE(Has(r.out, "ERROR")) << line << "\n" << r.out;
  }
  for (std::string tol : {"abs = inf", "rel = nan", "abs = -1", "abs = 0, rel = 0"}) {
    std::string spec = kSpec;
    spec.replace(spec.find("abs = 1e-8, rel = 1e-7"), 22, tol);
    Write(d + "/b.toml", spec);
    Result r = Kanesim("test b.toml", d);
    EXPECT_EQ(r.rc, 1) << tol << "\n" << r.out;
  }
}

// [run] energy_check: "on" is the default (the recorded golden still passes with it
// written out), "off"/"report" are other settings (FAIL until --update), anything else is
// an ERROR naming the values.
TEST(GoldenCorrupt, EnergyCheckSetting) {
  std::string d = Work("golden_energy_check");
  Record(d);
  auto with = [&](const std::string& line) {
    std::string spec = kSpec;
    spec.insert(spec.find("[run]\n") + 6, line + "\n");
    Write(d + "/g.toml", spec);
    return Kanesim("test g.toml", d);
  };
  Result on = with("energy_check = \"on\"");
  EXPECT_EQ(on.rc, 0) << on.out << on.err;
  Result off = with("energy_check = \"off\"");
  EXPECT_EQ(off.rc, 3) << off.out << off.err;
  EXPECT_TRUE(Has(off.out, "run settings changed")) << off.out;
  Result bad = with("energy_check = \"sometimes\"");
  EXPECT_EQ(bad.rc, 1) << bad.out << bad.err;
  EXPECT_TRUE(Has(bad.out, "energy_check 'sometimes'") && Has(bad.out, "on, off, report")) << bad.out;
}

// A missing golden is the one case that advises --update.
TEST(GoldenCorrupt, MissingGoldenAdvisesUpdate) {
  std::string d = Work("golden_missing");
  Write(d + "/g.toml", kSpec);
  Result r = Kanesim("test g.toml", d);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.out, "no stored output") && Has(r.out, "--update")) << r.out;
}

}  // namespace
}  // namespace kanesim::clitest
