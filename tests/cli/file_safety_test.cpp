// Items 13 and 14 of issue 24: outputs are never inputs (compared as files: the same
// path, another spelling, a symbolic or a hard link), two processes never write one
// output at once (a lock: the second is refused, exit 1), and temporaries a killed
// process left are ours by name and removed by the next run.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <vector>

#include "tests/support/cli_util.h"
#include "tests/support/dead_pid.h"
#include "tests/support/sanitizer_cases.h"

namespace kanesim::clitest {
namespace {

const std::string kSpring = kSrc + "/examples/spring_mass.mech";

// Names by which `dir/model.mech` can be written: the path, another spelling, a symbolic
// link and a hard link to it.
std::vector<std::string> Aliases(const std::string& dir, const std::string& file) {
  std::filesystem::remove(dir + "/sym");
  std::filesystem::remove(dir + "/hard");
  std::filesystem::create_symlink(dir + "/" + file, dir + "/sym");
  std::filesystem::create_hard_link(dir + "/" + file, dir + "/hard");
  return {file, "./" + file, "../" + std::filesystem::path(dir).filename().string() + "/" + file, "sym", "hard"};
}

TEST(FileSafety, RunNeverWritesOverItsModel) {
  std::string d = Work("safety_run");
  const std::string model = Slurp(kSpring);
  Write(d + "/model.mech", model);
  for (const std::string& out : Aliases(d, "model.mech")) {
    Result r = Kanesim("run model.mech --stop-time 0.1 -o " + out, d);
    EXPECT_EQ(r.rc, 1) << out << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "is the model")) << out << "\n" << r.err;
    EXPECT_EQ(Slurp(d + "/model.mech"), model) << out << ": the model was overwritten";
  }
}

TEST(FileSafety, SweepNeverWritesOverItsInputs) {
  std::string d = Work("safety_sweep");
  const std::string model = Slurp(kSpring);
  std::filesystem::create_directories(d + "/out/trajectories");
  // The model where the summary goes, and a list file where a trajectory goes.
  Write(d + "/out/summary.csv", model);
  Result r = Kanesim("sweep out/summary.csv --grid k=10,20 --no-progress -o out", d);
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "would overwrite its input")) << r.err;
  EXPECT_EQ(Slurp(d + "/out/summary.csv"), model);
  Write(d + "/m.mech", model);
  Write(d + "/out/trajectories/scenario_0.csv", "k\n10\n20\n");
  Result t = Kanesim("sweep m.mech --list out/trajectories/scenario_0.csv --trajectories --no-progress -o out", d);
  EXPECT_EQ(t.rc, 1) << t.err;
  EXPECT_EQ(Slurp(d + "/out/trajectories/scenario_0.csv"), "k\n10\n20\n");
  // sweep merge -o onto one of its inputs.
  std::filesystem::remove_all(d + "/out");
  ASSERT_EQ(Kanesim("sweep m.mech --grid k=10,20 --shard 1/2 --no-progress -o out", d).rc, 0);
  ASSERT_EQ(Kanesim("sweep m.mech --grid k=10,20 --shard 2/2 --no-progress -o out", d).rc, 0);
  const std::string shard = Slurp(d + "/out/summary.shard-1-of-2.csv");
  Result m = Kanesim("sweep merge out -o out/summary.shard-1-of-2.csv", d);
  EXPECT_EQ(m.rc, 1) << m.err;
  EXPECT_EQ(Slurp(d + "/out/summary.shard-1-of-2.csv"), shard);
}

TEST(FileSafety, GoldenUpdateNeverWritesOverItsSpecOrModel) {
  std::string d = Work("safety_golden");
  const std::string model = Slurp(kSpring);
  Write(d + "/model.mech", model);
  for (std::string golden : {"model.mech", "./model.mech", "g.toml", "sym", "hard"}) {
    Aliases(d, "model.mech");
    const std::string spec = "model = \"model.mech\"\ngolden = \"" + golden + "\"\n[run]\nstop_time = 0.1\n";
    Write(d + "/g.toml", spec);
    Result r = Kanesim("test --update g.toml", d);
    EXPECT_EQ(r.rc, 1) << golden << "\n" << r.out;
    EXPECT_EQ(Slurp(d + "/model.mech"), model) << golden;
    EXPECT_EQ(Slurp(d + "/g.toml"), spec) << golden;
  }
}

// A process holding the lock stands for a second kanesim writing the same output.
class HeldLock {
 public:
  explicit HeldLock(const std::string& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT, 0644)) {
    EXPECT_GE(fd_, 0);
    EXPECT_EQ(::flock(fd_, LOCK_EX | LOCK_NB), 0);
  }
  ~HeldLock() { ::close(fd_); }

 private:
  int fd_;
};

TEST(FileSafety, ASecondWriterOfTheSameOutputIsRefused) {
  std::string d = Work("safety_lock");
  {
    std::filesystem::create_directories(d + "/out");
    HeldLock lock(d + "/out/.summary.csv.lock");
    Result r = Kanesim("sweep " + kSpring + " --grid k=10,20 --metric final:slider.q --no-progress -o out", d);
    EXPECT_EQ(r.rc, 1) << r.err;
    EXPECT_TRUE(Has(r.err, "another kanesim process is writing")) << r.err;
    // Another shard of the same sweep has its own summary and lock: it may run.
    Result shard = Kanesim("sweep " + kSpring + " --grid k=10,20 --shard 1/2 --no-progress -o out", d);
    EXPECT_EQ(shard.rc, 0) << shard.err;
  }
  {
    Write(d + "/run.csv", "");
    HeldLock lock(d + "/.run.csv.lock");  // beside the output, which is replaced by a rename (issue 38)
    Result r = Kanesim("run " + kSpring + " --stop-time 0.1 -o run.csv", d);
    EXPECT_EQ(r.rc, 1) << r.err;
    EXPECT_TRUE(Has(r.err, "another kanesim process is writing")) << r.err;
  }
  // Released (the holder ended): both run.
  EXPECT_EQ(Kanesim("sweep " + kSpring + " --grid k=10,20 --metric final:slider.q --no-progress -o out", d).rc, 0);
  EXPECT_EQ(Kanesim("run " + kSpring + " --stop-time 0.1 -o run.csv", d).rc, 0);
  EXPECT_EQ(Kanesim("run " + kSpring + " --stop-time 0.1 -o /dev/null", d).rc, 0);  // not locked: shared by all
}

// Two different sweeps started together into one folder (each two seconds or more, so
// they overlap): one runs, the other is refused, and the summary holds every row of the one
// that ran (without the lock both exited 0 and the summary held one sweep's rows only).
TEST(FileSafety, TwoConcurrentSweepsDoNotLoseRows) {
  std::string d = Work("safety_concurrent");
  const std::string common = " sweep " + kSrc + "/examples/chain.mech --metric final:j[2].q --stop-time 8 "
                             "--no-progress -j1 -o out";
  // Under the sanitizers (runs ~30x slower: still several seconds each) 20 and 10 scenarios.
  const std::string last = test::kUnderSanitizers ? "0.145" : "0.345";
  const std::string a_args = common + " --grid q0=0.05:0.005:" + last, b_args = common + " --grid q0=0.1:0.005:" + last;
  Write(d + "/both.sh", "cd '" + d + "'\n('" + Bin() + "'" + a_args + " 2>a.err; echo $? > a.rc) &\n('" + Bin() +
                           "'" + b_args + " 2>b.err; echo $? > b.rc) &\nwait\n");
  ASSERT_EQ(std::system(("bash '" + d + "/both.sh'").c_str()), 0);
  const int a = std::stoi(Slurp(d + "/a.rc")), b = std::stoi(Slurp(d + "/b.rc"));
  ASSERT_TRUE((a == 0 && b == 1) || (a == 1 && b == 0)) << "exit codes " << a << " " << b;
  EXPECT_TRUE(Has(Slurp(d + (a == 1 ? "/a.err" : "/b.err")), "another kanesim process is writing"));
  EXPECT_EQ(CsvRows(d + "/out/summary.csv"), test::kUnderSanitizers ? (a == 0 ? 20 : 10) : (a == 0 ? 60 : 50));
}

std::string Host() {
  char buf[256] = {};
  ::gethostname(buf, sizeof buf - 1);
  std::string h(buf);
  for (char& c : h)
    if (c == '/' || c == '.') c = '_';
  return h;
}

TEST(FileSafety, StaleTemporariesAreRemovedLiveOnesKept) {
  std::string d = Work("safety_temps");
  Write(d + "/g.toml", "model = \"" + kSpring + "\"\n[run]\nstop_time = 0.1\n");
  const std::string dead = std::to_string(test::DeadPid()), live = std::to_string(::getpid());
  const std::vector<std::string> stale = {"g.csv.tmp." + dead, "g.csv.tmp." + Host() + "." + dead};
  const std::vector<std::string> kept = {"g.csv.tmp." + live, "g.csv.tmp.otherhost." + dead, "g.csv.tmpfile"};
  for (const auto& f : stale) Write(d + "/" + f, "x");
  for (const auto& f : kept) Write(d + "/" + f, "x");
  Result r = Kanesim("test --update g.toml", d);
  ASSERT_EQ(r.rc, 0) << r.out;
  for (const auto& f : stale) EXPECT_FALSE(std::filesystem::exists(d + "/" + f)) << f;
  for (const auto& f : kept) EXPECT_TRUE(std::filesystem::exists(d + "/" + f)) << f;
  // A sweep's summary and trajectory temporaries.
  std::filesystem::create_directories(d + "/out/trajectories");
  const std::vector<std::string> sweep_stale = {"out/summary.csv.tmp." + Host() + "." + dead,
                                                "out/trajectories/scenario_1.csv.tmp." + Host() + "." + dead};
  for (const auto& f : sweep_stale) Write(d + "/" + f, "x");
  ASSERT_EQ(Kanesim("sweep " + kSpring + " --grid k=10,20 --trajectories --no-progress -o out", d).rc, 0);
  for (const auto& f : sweep_stale) EXPECT_FALSE(std::filesystem::exists(d + "/" + f)) << f;
}

}  // namespace
}  // namespace kanesim::clitest
