// Reading model files (lang::ReadSourceFile, used by LoadProgram): every kind of path a
// user can give — a directory, a device, a pipe with or without a writer, a socket, a
// missing file, files at and over the size limit — ends in the text or in a message that
// says what the path is, promptly. A failure means a misleading message ("larger than
// 4194304 bytes" for a directory), a hang on a device or pipe, or an unbounded read.
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "lang/elaborate.h"
#include "lang/source.h"

namespace kanesim::lang {
namespace {

namespace fs = std::filesystem;

class ReadSourceFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kanesim_source_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

struct Outcome {
  ReadStatus status;
  std::string text, message;
};
Outcome Read(const std::string& path) {
  Outcome o;
  o.status = ReadSourceFile(path, &o.text, &o.message);
  return o;
}

// Paths that are not files: refused, the message naming the path and its kind.
TEST_F(ReadSourceFileTest, NonFilesAreNamedForWhatTheyAre) {
  const std::string fifo = Path("pipe"), socket_path = Path("sock");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", socket_path.c_str());
  ASSERT_EQ(::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  const struct {
    std::string path, kind;
  } cases[] = {
      {dir_.string(), "is a directory"},
      {"/dev/null", "is a character device"},
      {"/dev/zero", "is a character device"},
      {socket_path, "cannot open"},  // a socket cannot be open()ed: the system says why
  };
  for (const auto& c : cases) {
    Outcome o = Read(c.path);
    EXPECT_NE(o.status, ReadStatus::Ok) << c.path;
    EXPECT_NE(o.status, ReadStatus::TooLarge) << c.path;
    EXPECT_NE(o.message.find("'" + c.path + "'"), std::string::npos) << o.message;
    EXPECT_NE(o.message.find(c.kind), std::string::npos) << o.message;
  }
  ::close(sock);
  Outcome missing = Read(Path("missing.mech"));
  EXPECT_EQ(missing.status, ReadStatus::CannotOpen);
  EXPECT_NE(missing.message.find("No such file or directory"), std::string::npos) << missing.message;
}

// A pipe is read to its end (`gen | kanesim check /dev/stdin`); a named pipe nobody writes
// to is an empty text at once, not a wait.
TEST_F(ReadSourceFileTest, PipesAreReadToTheirEndWithoutWaitingForAWriter) {
  const std::string fifo = Path("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  Outcome idle = Read(fifo);
  EXPECT_EQ(idle.status, ReadStatus::Ok) << idle.message;
  EXPECT_EQ(idle.text, "");
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const std::string model = "model M\nend M;\n";
  ASSERT_EQ(::write(fds[1], model.data(), model.size()), static_cast<ssize_t>(model.size()));
  ::close(fds[1]);
  Outcome o = Read("/dev/fd/" + std::to_string(fds[0]));
  ::close(fds[0]);
  EXPECT_EQ(o.status, ReadStatus::Ok) << o.message;
  EXPECT_EQ(o.text, model);
}

// Sizes: exactly the limit is read, one byte more is TooLarge with the limit in the
// message, for a regular file and for a pipe (which has no size to look at first: the
// read stops one byte past the limit however much the writer sends).
TEST_F(ReadSourceFileTest, TheSizeLimitHoldsForFilesAndPipes) {
  for (std::size_t size : {std::size_t{0}, SourceManager::kMaxFileBytes, SourceManager::kMaxFileBytes + 1}) {
    const std::string path = Path("f" + std::to_string(size) + ".mech");
    {
      std::ofstream out(path, std::ios::binary);
      out << std::string(size, ' ');
    }
    Outcome o = Read(path);
    EXPECT_EQ(o.status, size > SourceManager::kMaxFileBytes ? ReadStatus::TooLarge : ReadStatus::Ok) << size;
    if (o.status == ReadStatus::Ok) {
      EXPECT_EQ(o.text.size(), size);
    } else {
      EXPECT_NE(o.message.find("4194304"), std::string::npos) << o.message;
    }
  }
  std::signal(SIGPIPE, SIG_IGN);  // the writer learns of the closed reader from EPIPE
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  std::thread writer([w = fds[1]] {
    const std::string chunk(1 << 16, ' ');
    for (std::size_t sent = 0; sent < 4 * SourceManager::kMaxFileBytes; sent += chunk.size())
      if (::write(w, chunk.data(), chunk.size()) < 0) break;
    ::close(w);
  });
  Outcome o = Read("/dev/fd/" + std::to_string(fds[0]));
  ::close(fds[0]);
  writer.join();
  EXPECT_EQ(o.status, ReadStatus::TooLarge) << o.message;
}

// LoadProgram maps the outcomes to diagnostics: a directory is E221 saying so (it was L005
// "larger than 4194304 bytes").
TEST_F(ReadSourceFileTest, LoadProgramSaysADirectoryIsADirectory) {
  Program program;
  Diagnostics diags(&program.sources);
  EXPECT_FALSE(LoadProgram(dir_.string(), {}, &program, diags));
  ASSERT_EQ(diags.All().size(), 1u);
  EXPECT_EQ(diags.All()[0].code, DiagCode::NotAModel);
  EXPECT_NE(diags.All()[0].message.find("is a directory"), std::string::npos) << diags.All()[0].message;
}

// A UTF-8 byte-order mark opening a file is dropped: columns count from the first
// character the user sees.
TEST(SourceManager, ByteOrderMarkIsDropped) {
  SourceManager sm;
  int f = sm.Add("bom.mech", "\xEF\xBB\xBFmodel M end M;");
  EXPECT_EQ(sm.Text(f), "model M end M;");
  EXPECT_EQ(sm.Locate(f, 6).col, 7);
}

}  // namespace
}  // namespace kanesim::lang
