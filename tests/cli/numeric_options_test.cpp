// "Clear messages" of issue 24: every numeric option reads exactly the language's number
// syntax (flat/number.h) and says what is wrong with a value (not a number, out
// of range, not positive), tolerances that are legal but almost surely mistakes draw a
// warning, and the TOML readers refuse values of the wrong type or range with file:line.
#include <gtest/gtest.h>

#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

const std::string kSpring = kSrc + "/examples/spring_mass.mech";

const std::vector<std::string> kRealOptions = {"--start-time", "--stop-time", "--interval", "--rtol", "--atol"};

// Not numbers in a model, so not on the command line either.
const std::vector<std::string> kNotNumbers = {"nan", "inf", "-inf", "0x10", "1_000", "1e", "1.5.2", "'1 '", "''",
                                              "1e+", "++1", "0b1", "1f", "infinity"};

TEST(NumericOptions, EveryRealOptionRejectsWhatAModelRejects) {
  std::string d = Work("options_syntax");
  for (std::string cmd : {"run", "sweep"})  // (sweep: the first five values; it parses options the same way)
    for (const std::string& opt : kRealOptions)
      for (const std::string& v : kNotNumbers) {
        if (cmd == "sweep" && &v - kNotNumbers.data() >= 5) break;
        const std::string extra = cmd == "sweep" ? " --grid k=10 --no-progress -o out" : " -o out.csv";
        Result r = Kanesim(cmd + " " + kSpring + " " + opt + " " + v + extra, d);
        EXPECT_EQ(r.rc, 1) << cmd << " " << opt << " " << v << "\n" << r.err;
        EXPECT_TRUE(Has(r.err, opt + ": ") && Has(r.err, "is not a number")) << cmd << " " << opt << " " << v << "\n"
                                                                              << r.err;
        EXPECT_FALSE(Has(r.err, "must not be before")) << r.err;
      }
}

TEST(NumericOptions, OutOfRangeSaysSo) {
  std::string d = Work("options_range");
  for (const std::string& opt : kRealOptions)
    for (std::string v : {"1e400", "-1e400", "1e-400"}) {
      Result r = Kanesim("run " + kSpring + " " + opt + " " + v + " -o out.csv", d);
      EXPECT_EQ(r.rc, 1) << opt << " " << v;
      EXPECT_TRUE(Has(r.err, "out of range") || Has(r.err, "too small")) << opt << " " << v << "\n" << r.err;
    }
  for (std::string v : {"0", "-1e-6"})
    for (std::string opt : {"--interval", "--rtol", "--atol"}) {
      Result r = Kanesim("run " + kSpring + " " + opt + " " + v + " -o out.csv", d);
      EXPECT_EQ(r.rc, 1) << opt << " " << v;
      EXPECT_TRUE(Has(r.err, "positive")) << opt << " " << v << "\n" << r.err;
    }
  Result r = Kanesim("run " + kSpring + " --stop-time -1 -o out.csv", d);
  EXPECT_TRUE(r.rc == 1 && Has(r.err, "is before the start time")) << r.err;
}

// The forms of the language's numbers are all accepted, with the model's meaning.
TEST(NumericOptions, TheLanguagesNumberFormsAreAccepted) {
  std::string d = Work("options_forms");
  for (std::string v : {"0.5", ".5", "5e-1", "5E-1", "0.05e1", "+0.5", "5.e-1"}) {
    Result r = Kanesim("run " + kSpring + " --stop-time " + v + " --interval 0.25 -o out.csv", d);
    ASSERT_EQ(r.rc, 0) << v << "\n" << r.err;
    EXPECT_EQ(CsvRows(d + "/out.csv"), 3) << v;
  }
}

TEST(NumericOptions, IntegerOptionsAreIntegers) {
  std::string d = Work("options_int");
  for (std::string opt : {"--sample 0x10", "--sample 1e3", "--sample 0", "--sample 99999999999999999999",
                          "--seed 1.5", "--seed 0x10", "-j -1", "-j 1e2", "-j 100000", "--shard 1/0",
                          "--shard 99999999999/99999999999", "--shard 2/1", "--shard +1/2x"}) {
    Result r = Kanesim("sweep " + kSpring + " --uniform k=10:20 --sample 2 " + opt + " --no-progress -o out", d);
    EXPECT_EQ(r.rc, 1) << opt << "\n" << r.err;
  }
  Result t = Kanesim("test -j 0x2 " + kSrc + "/tests/golden/spring_mass.toml", d);
  EXPECT_EQ(t.rc, 1) << t.err;
}

// rtol > 0.1 is legal but allows errors larger than the solution: a warning (run, sweep,
// test), and the run still happens.
TEST(NumericOptions, SillyToleranceDrawsAWarning) {
  std::string d = Work("options_warn");
  for (std::string rtol : {"10", "0.5", "1e-16"}) {
    Result r = Kanesim("run " + kSpring + " --rtol " + rtol + " --stop-time 0.1 -o out.csv", d);
    EXPECT_EQ(r.rc, 0) << rtol << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "warning: rtol = ")) << rtol << "\n" << r.err;
    Result s = Kanesim("sweep " + kSpring + " --grid k=10 --rtol " + rtol + " --stop-time 0.1 --no-progress -o out", d);
    EXPECT_TRUE(Has(s.err, "warning: rtol = ")) << rtol << "\n" << s.err;
  }
  Result quiet = Kanesim("run " + kSpring + " --rtol 1e-6 --stop-time 0.1 -o out.csv", d);
  EXPECT_FALSE(Has(quiet.err, "warning")) << quiet.err;
  Write(d + "/g.toml", "model = \"" + kSpring + "\"\n[run]\nstop_time = 0.1\nrtol = 10\n");
  Result g = Kanesim("test --update g.toml", d);
  EXPECT_TRUE(Has(g.out, "warning: rtol = ") || Has(g.err, "warning: rtol = ")) << g.out << g.err;
}

// sweep.toml fields of the wrong type or range: refused with the file and line.
TEST(NumericOptions, SweepTomlValuesAreChecked) {
  std::string d = Work("options_toml");
  const std::string head = "model = \"" + kSpring + "\"\n[grid]\nk = [10, 20]\n";
  const std::vector<std::string> bad = {"stop_time = inf", "stop_time = nan", "rtol = -1", "interval = 0",
                                        "atol = 0.0", "trajectories = \"yes\"", "integrator = 5", "output = 3",
                                        "set = { F0 = [1, 2] }", "set = { F0 = inf }", "start_time = 2\nstop_time = 1",
                                        "metrics = \"final:slider.q\"", "grid = 3"};
  for (const std::string& line : bad) {
    Write(d + "/s.toml", line + "\n" + head);
    Result r = Kanesim("sweep --no-progress s.toml", d);
    EXPECT_EQ(r.rc, 1) << line << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "s.toml:")) << line << "\n" << r.err;
  }
  for (std::string sample : {"n = 4294967301", "n = 0", "n = 1.5", "n = 3\nseed = 1.5", "n = 3\nbogus = 1"}) {
    Write(d + "/s.toml", "model = \"" + kSpring + "\"\n[sample]\n" + sample + "\nuniform = { k = [10, 20] }\n");
    Result r = Kanesim("sweep --no-progress s.toml", d);
    EXPECT_EQ(r.rc, 1) << sample << "\n" << r.err;
  }
  Write(d + "/s.toml", "model = \"" + kSpring + "\"\n[grid]\nk = \"0x10,20\"\n");
  Result hex = Kanesim("sweep --no-progress s.toml", d);
  EXPECT_EQ(hex.rc, 1) << hex.err;
  Result level = Kanesim("sweep " + kSpring + " --grid k=10 --metric cross:slider.q=0x1 --no-progress -o out", d);
  EXPECT_EQ(level.rc, 1) << level.err;
}

}  // namespace
}  // namespace kanesim::clitest
