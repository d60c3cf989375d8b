// Issue 38, data loss: every file kanesim replaces (run -o, --animation, test --update, a
// sweep's summary and records, sweep merge -o) is written through a temporary beside it,
// flushed and renamed over it (batch/file_guard.h AtomicFile), so
//   - a full disk, a file-size limit or a kill leaves the previous file whole (before: run -o
//     truncated it at once, --animation left a torn file);
//   - a FIFO, a device, a directory or a socket named as the target is refused, never
//     replaced by a regular file (before: test --update renamed over a FIFO).
// Full disks are real: a small tmpfs mounted for the test (needs root; skipped otherwise),
// and RLIMIT_FSIZE (`ulimit -f`), which works anywhere.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

const std::string kSpring = kSrc + "/examples/spring_mass.mech";

std::string FileType(const std::string& path) {
  struct stat st;
  if (::lstat(path.c_str(), &st) != 0) return "absent";
  switch (st.st_mode & S_IFMT) {
    case S_IFREG: return "regular";
    case S_IFIFO: return "fifo";
    case S_IFCHR: return "chardev";
    case S_IFDIR: return "directory";
    case S_IFSOCK: return "socket";
    default: return "other";
  }
}

// Temporaries of `target` left in its folder.
std::vector<std::string> Temps(const std::string& target) {
  std::vector<std::string> found;
  const std::filesystem::path t(target);
  for (const auto& e : std::filesystem::directory_iterator(t.parent_path()))
    if (e.path().filename().string().starts_with(t.filename().string() + ".tmp.")) found.push_back(e.path().string());
  return found;
}

// Special files at d/NAME: a FIFO, a socket, a directory and (as root) a character device
// of our own (the null device's numbers; replacing it would not harm /dev/null).
std::vector<std::pair<std::string, std::string>> MakeSpecialFiles(const std::string& d) {
  std::vector<std::pair<std::string, std::string>> made;
  if (::mkfifo((d + "/fifo").c_str(), 0644) == 0) made.emplace_back("fifo", "a FIFO (named pipe)");
  int s = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const std::string sock = d + "/sock";
  if (sock.size() < sizeof addr.sun_path) {
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", sock.c_str());
    if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) made.emplace_back("sock", "a socket");
  }
  ::close(s);
  std::filesystem::create_directory(d + "/dir");
  made.emplace_back("dir", "a directory");
  if (::mknod((d + "/chardev").c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0)
    made.emplace_back("chardev", "a character device");
  return made;
}

// Wrong if test --update (or any writer through the atomic helper) replaces a special file.
TEST(OutputReplace, GoldenUpdateRefusesSpecialFiles) {
  const std::string d = Work("replace_golden_special");
  Write(d + "/m.mech", Slurp(kSpring));
  for (const auto& [name, what] : MakeSpecialFiles(d)) {
    const std::string type = FileType(d + "/" + name);
    Write(d + "/spec.toml", "model = \"m.mech\"\ngolden = \"" + name + "\"\n[run]\nstop_time = 0.1\n");
    Result r = Kanesim("test spec.toml --update", d);
    EXPECT_EQ(r.rc, 1) << name << "\n" << r.out << r.err;
    EXPECT_TRUE(Has(r.out + r.err, "is " + what + ", not a regular file")) << name << "\n" << r.out << r.err;
    EXPECT_EQ(FileType(d + "/" + name), type) << name << " was replaced";
    EXPECT_TRUE(Temps(d + "/" + name).empty()) << name;
  }
}

// The same class through the other writers: a sweep whose summary is a special file, sweep
// merge -o onto one, --animation onto one. (run -o onto a FIFO or a device streams into it,
// as a pipe should: not refused.)
TEST(OutputReplace, EveryWriterRefusesSpecialFiles) {
  const std::string d = Work("replace_special_all");
  ASSERT_EQ(Kanesim("sweep " + kSpring + " --grid k=10,20 --shard 1/2 --no-progress -o shards", d).rc, 0);
  ASSERT_EQ(Kanesim("sweep " + kSpring + " --grid k=10,20 --shard 2/2 --no-progress -o shards", d).rc, 0);
  std::filesystem::create_directories(d + "/sw");
  const auto in_sweep = MakeSpecialFiles(d + "/sw");
  for (const auto& [name, what] : in_sweep) {
    std::filesystem::rename(d + "/sw/" + name, d + "/sw/summary.csv");
    const std::string type = FileType(d + "/sw/summary.csv");
    Result s = Kanesim("sweep " + kSpring + " --grid k=10,20 --no-progress -o sw", d);
    EXPECT_EQ(s.rc, 1) << name << "\n" << s.err;
    EXPECT_TRUE(Has(s.err, "is " + what + ", not a regular file")) << name << "\n" << s.err;
    EXPECT_EQ(FileType(d + "/sw/summary.csv"), type) << name << " was replaced";
    std::filesystem::rename(d + "/sw/summary.csv", d + "/" + name);
    Result m = Kanesim("sweep merge shards -o " + name, d);
    EXPECT_EQ(m.rc, 1) << name << "\n" << m.err;
    EXPECT_TRUE(Has(m.err, "is " + what + ", not a regular file")) << name << "\n" << m.err;
    EXPECT_EQ(FileType(d + "/" + name), type) << name << " was replaced by merge";
    if (name == "fifo") continue;  // the animation exporter would block opening it before the fix
    std::filesystem::rename(d + "/" + name, d + "/" + name + ".glb");  // an animation's name ends in .glb
    Result a = Kanesim("run " + kSpring + " --stop-time 0.1 -o run.csv --animation " + name + ".glb", d);
    EXPECT_EQ(a.rc, 1) << name << "\n" << a.err;
    EXPECT_TRUE(Has(a.err, "is " + what + ", not a regular file")) << name << "\n" << a.err;
    EXPECT_EQ(FileType(d + "/" + name + ".glb"), type) << name << " was replaced by the animation";
  }
}

// A small file system that fills up: mounted for the test, unmounted at the end.
class SmallDisk {
 public:
  explicit SmallDisk(const std::string& dir, const std::string& size) : dir_(dir) {
    std::filesystem::create_directories(dir);
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  bool mounted() const { return mounted_; }

 private:
  std::string dir_;
  bool mounted_ = false;
};

// A full disk: run -o and --animation keep the previous good files, byte for byte, and leave
// no temporary (before: run -o had truncated the CSV, the animation was torn).
TEST(OutputReplace, AFullDiskKeepsThePreviousFiles) {
  // A run killed before its unmount left the small disk mounted: detach it first.
  ::umount2((std::string(KANESIM_WORK_DIR) + "/replace_full_disk/disk").c_str(), MNT_DETACH);
  const std::string d = Work("replace_full_disk");
  SmallDisk disk(d + "/disk", "192k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs (not root?); RLIMIT_FSIZE test below covers it";
  const std::string chain = kSrc + "/examples/chain.mech";
  // Small good outputs first (about 10 kB each), then runs whose outputs cannot fit.
  Result good = Kanesim("run " + chain + " --set N=2 --stop-time 0.5 --interval 0.01 -o disk/out.csv "
                        "--animation disk/out.glb",
                        d);
  ASSERT_EQ(good.rc, 0) << good.err;
  const std::string csv = Slurp(d + "/disk/out.csv"), glb = Slurp(d + "/disk/out.glb");
  ASSERT_GT(csv.size(), 1000u);
  ASSERT_GT(glb.size(), 1000u);
  for (const std::string big : {"-o disk/out.csv", "-o /dev/null --animation disk/out.glb",
                                 "-o disk/out.csv --animation disk/out.glb"}) {
    Result r = Kanesim("run " + chain + " --set N=3 --stop-time 20 --interval 0.001 " + big, d);
    EXPECT_EQ(r.rc, 1) << big << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "No space left on device") || Has(r.err, "cannot write")) << big << "\n" << r.err;
    EXPECT_EQ(Slurp(d + "/disk/out.csv"), csv) << big << ": the previous CSV was not kept";
    EXPECT_EQ(Slurp(d + "/disk/out.glb"), glb) << big << ": the previous animation was not kept";
    EXPECT_TRUE(Temps(d + "/disk/out.csv").empty() && Temps(d + "/disk/out.glb").empty()) << big;
  }
  // The CSV's disk is full, the animation's is not: the failed run (exit 1) leaves the
  // previous animation as it was too (before: the part of the motion computed before the CSV
  // failed replaced it; on the one small disk that happened only when that part fit).
  ASSERT_EQ(Kanesim("run " + chain + " --set N=2 --stop-time 0.5 --interval 0.01 -o /dev/null --animation roomy.glb", d)
                .rc,
            0);
  const std::string roomy = Slurp(d + "/roomy.glb");
  Result r = Kanesim("run " + chain + " --set N=3 --stop-time 20 --interval 0.001 -o disk/out.csv --animation roomy.glb", d);
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_EQ(Slurp(d + "/roomy.glb"), roomy) << "a run whose CSV could not be written replaced the animation";
  EXPECT_TRUE(Temps(d + "/roomy.glb").empty());
  // test --update on the full disk: the golden stays as recorded.
  Write(d + "/g.toml", "model = \"" + kSpring + "\"\ngolden = \"disk/g.csv\"\n[run]\nstop_time = 0.2\n");
  ASSERT_EQ(Kanesim("test g.toml --update", d).rc, 0);
  const std::string golden = Slurp(d + "/disk/g.csv");
  Write(d + "/filler.sh", "cat /dev/zero > '" + d + "/disk/filler' 2>/dev/null; true");
  std::system(("bash '" + d + "/filler.sh'").c_str());
  Write(d + "/g.toml", "model = \"" + kSpring + "\"\ngolden = \"disk/g.csv\"\n[run]\nstop_time = 0.3\n");
  Result u = Kanesim("test g.toml --update", d);
  EXPECT_EQ(u.rc, 1) << u.out << u.err;
  EXPECT_EQ(Slurp(d + "/disk/g.csv"), golden);
}

// RLIMIT_FSIZE: the kernel stops the process (SIGXFSZ) when its output passes the limit,
// like a kill in the middle of writing. The previous files stay whole; the rows computed so
// far are in the temporary, whole rows, recognizably not the output; the next run to the
// same target removes that temporary.
TEST(OutputReplace, AProcessStoppedWhileWritingKeepsThePreviousFiles) {
  const std::string d = Work("replace_fsize");
  const std::string chain = kSrc + "/examples/chain.mech";
  ASSERT_EQ(Kanesim("run " + chain + " --set N=2 --stop-time 0.5 --interval 0.01 -o out.csv --animation out.glb", d).rc,
            0);
  const std::string csv = Slurp(d + "/out.csv"), glb = Slurp(d + "/out.glb");
  for (const std::string big : {"-o out.csv", "-o /dev/null --animation out.glb"}) {
    // 64 blocks of 1 KiB: more than the good files, less than these runs write.
    Write(d + "/limited.sh", "cd '" + d + "' && ulimit -f 64 && exec '" + Bin() + "' run " + chain +
                                 " --set N=3 --stop-time 20 --interval 0.001 " + big + " 2>err.txt");
    const int rc = std::system(("bash '" + d + "/limited.sh'").c_str());
    EXPECT_NE(rc, 0) << big;
    EXPECT_EQ(Slurp(d + "/out.csv"), csv) << big << ": the previous CSV was not kept";
    EXPECT_EQ(Slurp(d + "/out.glb"), glb) << big << ": the previous animation was not kept";
  }
  const std::vector<std::string> left = Temps(d + "/out.csv");
  ASSERT_EQ(left.size(), 1u) << "the stopped run's rows";
  EXPECT_TRUE(Slurp(left[0]).starts_with(csv.substr(0, csv.find('\n')))) << "it starts with the header";
  ASSERT_EQ(Temps(d + "/out.glb").size(), 1u) << "the stopped animation's folder";
  ASSERT_EQ(Kanesim("run " + chain + " --set N=2 --stop-time 0.5 --interval 0.01 -o out.csv --animation out.glb", d).rc,
            0);
  EXPECT_TRUE(Temps(d + "/out.csv").empty()) << "the stale temporary was removed";
  EXPECT_TRUE(Temps(d + "/out.glb").empty()) << "the stale animation folder was removed";
}

// run -o: the file appears only when the run ends; a numerical failure (exit 2) still
// renames it, since its rows are correct (the rows before the failure, checked by
// nan_rows_test); a usage error leaves the previous file.
TEST(OutputReplace, RunReplacesTheOutputAtTheEnd) {
  const std::string d = Work("replace_run_end");
  Write(d + "/out.csv", "previous\n");
  Write(d + "/nan.mech",
        "model N\n  World world;\n  Revolute hinge(axis = {0, 0, 1});\n  Rod rod(L = 1, m = 1);\n"
        "  Real f = sqrt(0.3 - time);\nequation\n  connect(world.frame_b, hinge.frame_a);\n"
        "  connect(hinge.frame_b, rod.frame_a);\n  hinge.tau = f;\n"
        "  annotation(experiment(StopTime = 1, Interval = 0.01));\nend N;\n");
  Result r = Kanesim("run nan.mech -o out.csv", d);
  if (r.rc == 2) {
    EXPECT_NE(Slurp(d + "/out.csv"), "previous\n");
    EXPECT_GE(CsvRows(d + "/out.csv"), 29) << "rows up to t = 0.28 are kept";
  } else {
    ADD_FAILURE() << "the model was meant to fail at t = 0.3: rc " << r.rc << "\n" << r.err;
  }
  Write(d + "/out.csv", "previous\n");
  Result usage = Kanesim("run " + kSpring + " --stop-time 0.1 --output nosuchsignal -o out.csv", d);
  EXPECT_EQ(usage.rc, 1) << usage.err;
  EXPECT_EQ(Slurp(d + "/out.csv"), "previous\n");
  EXPECT_TRUE(Temps(d + "/out.csv").empty());
  // Through a symbolic link: the linked file gets the rows, the link stays a link.
  Write(d + "/real.csv", "previous\n");
  std::filesystem::create_symlink("real.csv", d + "/link.csv");
  ASSERT_EQ(Kanesim("run " + kSpring + " --stop-time 0.1 -o link.csv", d).rc, 0);
  EXPECT_TRUE(std::filesystem::is_symlink(d + "/link.csv"));
  EXPECT_GT(CsvRows(d + "/real.csv"), 5);
  // Nothing but the outputs is left: no temporary, no lock file.
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(d))
    if (e.path().filename().string().find(".lock") != std::string::npos || !Temps(e.path().string()).empty())
      left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << left.front();
}

// linearize -o (the JSON model, and the root locus CSV of --sweep) is written like run -o:
// stopped while writing (RLIMIT_FSIZE: SIGXFSZ in the middle of the file, as a kill) or on a
// full disk, the previous good file stays byte for byte (before: it was truncated at once
// and left torn). Outputs of 210-230 kB against a 64 KiB limit / a 192 KiB disk; the good
// ones are small.
const std::vector<std::pair<std::string, std::string>> kLinearizeBig = {
    {"out.json", "linearize " + kSrc + "/examples/chain.mech --set N=30 --equilibrium -o "},
    {"locus.csv", "linearize " + kSpring + " --sweep k=1:1:2000 -o "}};
const std::vector<std::string> kLinearizeSmall = {"linearize " + kSrc + "/examples/chain.mech --set N=2 --equilibrium -o ",
                                                  "linearize " + kSpring + " --sweep k=1:1:5 -o "};

TEST(OutputReplace, LinearizeStoppedWhileWritingKeepsThePreviousFile) {
  const std::string d = Work("replace_linearize_fsize");
  for (size_t k = 0; k < kLinearizeBig.size(); ++k) {
    const auto& [name, big] = kLinearizeBig[k];
    ASSERT_EQ(Kanesim(kLinearizeSmall[k] + name, d).rc, 0) << name;
    const std::string good = Slurp(d + "/" + name);
    ASSERT_GT(good.size(), 100u);
    ASSERT_LT(good.size(), 32000u);
    Write(d + "/limited.sh", "cd '" + d + "' && ulimit -f 64 && exec '" + Bin() + "' " + big + name +
                                 " >/dev/null 2>err.txt");
    const int rc = std::system(("bash '" + d + "/limited.sh'").c_str());
    EXPECT_NE(rc, 0) << name << ": the limit was meant to stop it";
    EXPECT_EQ(Slurp(d + "/" + name), good) << name << ": the previous file was not kept";
    ASSERT_EQ(Temps(d + "/" + name).size(), 1u) << name << ": the stopped run's partial file";
    // Unlimited, the same command replaces the file whole and removes the stale temporary.
    Result r = Kanesim(big + name, d);
    ASSERT_EQ(r.rc, 0) << r.err;
    EXPECT_GT(Slurp(d + "/" + name).size(), 200000u) << name;
    EXPECT_TRUE(Temps(d + "/" + name).empty()) << name;
  }
  EXPECT_TRUE(Slurp(d + "/out.json").ends_with("}\n")) << "the JSON is complete";
  EXPECT_FALSE(std::filesystem::exists(d + "/.out.json.lock")) << "no lock file is left";
}

TEST(OutputReplace, LinearizeOnAFullDiskKeepsThePreviousFile) {
  ::umount2((std::string(KANESIM_WORK_DIR) + "/replace_linearize_disk/disk").c_str(), MNT_DETACH);
  const std::string d = Work("replace_linearize_disk");
  SmallDisk disk(d + "/disk", "192k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs (not root?); the RLIMIT_FSIZE test covers it";
  for (size_t k = 0; k < kLinearizeBig.size(); ++k) {
    const auto& [name, big] = kLinearizeBig[k];
    ASSERT_EQ(Kanesim(kLinearizeSmall[k] + "disk/" + name, d).rc, 0) << name;
    const std::string good = Slurp(d + "/disk/" + name);
    Result r = Kanesim(big + "disk/" + name, d);
    EXPECT_EQ(r.rc, 1) << name << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "No space left on device")) << name << "\n" << r.err;
    EXPECT_EQ(Slurp(d + "/disk/" + name), good) << name << ": the previous file was not kept";
    EXPECT_TRUE(Temps(d + "/disk/" + name).empty()) << name;
  }
}

// linearize -o onto a directory or a socket: refused, left as it is; onto the model (a hard
// link to it): refused before any work.
TEST(OutputReplace, LinearizeRefusesSpecialFilesAndTheModel) {
  const std::string d = Work("replace_linearize_special");
  Write(d + "/m.mech", Slurp(kSpring));
  for (const auto& [name, what] : MakeSpecialFiles(d)) {
    if (name == "fifo" || name == "chardev") continue;  // streamed into, as run -o does
    const std::string type = FileType(d + "/" + name);
    Result r = Kanesim("linearize m.mech -o " + name, d);
    EXPECT_EQ(r.rc, 1) << name << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "cannot open '" + name + "' for writing")) << name << "\n" << r.err;
    EXPECT_EQ(FileType(d + "/" + name), type) << name << " was replaced";
  }
  std::filesystem::create_hard_link(d + "/m.mech", d + "/hard.json");
  for (const std::string opt : {"-o hard.json", "--sweep k=1:1:3 -o hard.json"}) {
    Result r = Kanesim("linearize m.mech " + opt, d);
    EXPECT_EQ(r.rc, 1) << opt << "\n" << r.err;
    EXPECT_EQ(Slurp(d + "/m.mech"), Slurp(kSpring)) << opt;
  }
  // Through a symbolic link: the linked file gets the model, the link stays a link.
  Write(d + "/real.json", "previous\n");
  std::filesystem::create_symlink("real.json", d + "/link.json");
  ASSERT_EQ(Kanesim("linearize m.mech -o link.json", d).rc, 0);
  EXPECT_TRUE(std::filesystem::is_symlink(d + "/link.json"));
  EXPECT_TRUE(Slurp(d + "/real.json").starts_with("{")) << Slurp(d + "/real.json");
}

}  // namespace
}  // namespace kanesim::clitest
