// The settings record of a sweep summary (settings_record.h) and the guards on written
// files (file_guard.h): what --resume, merge and every writer rely on.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "batch/file_guard.h"
#include "batch/settings_record.h"
#include "tests/support/dead_pid.h"

namespace kanesim::batch {
namespace {

std::string Dir(const std::string& name) {
  std::string d = ::testing::TempDir() + "/" + name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// Wrong if a record does not read back as written, or if a difference in a deciding key
// is missed, or one in an informational key (version, shard) refuses a resume.
TEST(SettingsRecord, RoundTripAndDifferences) {
  SettingsRecord a;
  a.Set("kanesim_version", "0.1.0");
  a.Set("model_text", "fnv1a64:0011");
  a.Set("set", "k=1; c=2");
  a.Set("rtol", "1e-08");
  a.Set("shard", "1/2");
  a.Set("model_name", "");
  const std::string path = Dir("settings") + "/summary.settings";
  std::ofstream(path) << FormatSettings(a);
  SettingsRecord b;
  std::string err;
  ASSERT_TRUE(ReadSettings(path, &b, &err)) << err;
  EXPECT_EQ(b.entries, a.entries);
  EXPECT_TRUE(SettingsDifferences(a, b, "x", "y").empty());
  b.Set("shard", "2/2");
  b.Set("kanesim_version", "0.2.0");
  EXPECT_TRUE(SettingsDifferences(a, b, "x", "y").empty());
  b.Set("rtol", "1e-07");
  b.Set("atol", "1e-09");  // not in the recorded one
  auto d = SettingsDifferences(a, b, "recorded", "now");
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0], "rtol: 1e-08 (recorded), 1e-07 (now)");
  EXPECT_EQ(d[1], "atol: (not recorded) (recorded), 1e-09 (now)");
  EXPECT_EQ(SettingsPathFor("out/summary.shard-1-of-2.csv"), "out/summary.shard-1-of-2.settings");
}

// Wrong if another name for the same file (hard link, symbolic link, other spelling)
// is taken for a different file, or different files for the same.
TEST(FileGuard, SameFileByInode) {
  const std::string d = Dir("same_file");
  std::ofstream(d + "/a") << "a";
  std::ofstream(d + "/b") << "a";
  std::filesystem::create_hard_link(d + "/a", d + "/hard");
  std::filesystem::create_symlink(d + "/a", d + "/sym");
  EXPECT_TRUE(SameFile(d + "/a", d + "/hard"));
  EXPECT_TRUE(SameFile(d + "/a", d + "/sym"));
  EXPECT_TRUE(SameFile(d + "/a", d + "/./../" + std::filesystem::path(d).filename().string() + "/a"));
  EXPECT_FALSE(SameFile(d + "/a", d + "/b"));
  EXPECT_FALSE(SameFile(d + "/a", d + "/missing"));
  EXPECT_EQ(OverwrittenInput(d + "/sym", {d + "/b", d + "/a"}), d + "/a");
  EXPECT_EQ(OverwrittenInput(d + "/new", {d + "/b", d + "/a"}), "");
}

// Wrong if a temporary of a process that still runs is removed, or a stale one of
// ours is kept, or a file that only looks similar is touched.
TEST(FileGuard, StaleTemporariesOnly) {
  const std::string d = Dir("temps");
  const std::string target = d + "/g.csv";
  const std::string mine = TempPathFor(target);
  const std::string host = mine.substr(target.size() + 5, mine.rfind('.') - target.size() - 5);
  const std::string dead = std::to_string(test::DeadPid());
  for (const std::string& f : {mine, target + ".tmp." + dead, target + ".tmp." + host + "." + dead,
                               target + ".tmp.elsewhere." + dead, target + ".tmpx." + dead, d + "/h.csv.tmp." + dead})
    std::ofstream(f) << "x";
  EXPECT_EQ(RemoveStaleTemps(target), 2);
  EXPECT_TRUE(std::filesystem::exists(mine)) << "ours, running";
  EXPECT_TRUE(std::filesystem::exists(target + ".tmp.elsewhere." + dead)) << "another machine's";
  EXPECT_TRUE(std::filesystem::exists(target + ".tmpx." + dead));
  EXPECT_TRUE(std::filesystem::exists(d + "/h.csv.tmp." + dead)) << "another target's";
  EXPECT_EQ(RemoveStaleTempsIn(d), 1);  // h.csv's
}

// Wrong if two writers can hold one lock, or a released lock stays taken.
TEST(FileGuard, LockIsExclusiveAndReleased) {
  const std::string path = Dir("lock") + "/.summary.csv.lock";
  std::string err;
  {
    FileLock first;
    ASSERT_TRUE(first.Acquire(path, "'summary.csv'", &err)) << err;
    FileLock second;
    EXPECT_FALSE(second.Acquire(path, "'summary.csv'", &err));
    EXPECT_NE(err.find("another kanesim process is writing 'summary.csv'"), std::string::npos) << err;
  }
  FileLock again;
  EXPECT_TRUE(again.Acquire(path, "'summary.csv'", &err)) << err;
}

}  // namespace
}  // namespace kanesim::batch
