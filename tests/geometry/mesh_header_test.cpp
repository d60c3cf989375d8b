// A mesh file's declared sizes and kind, checked before assimp reads it (geometry/mesh_header.h,
// mesh_load.cpp CheckFile). Each test would fail if assimp were handed a file whose header
// claims more than the file holds or the limits allow (it allocates by the claim: minutes and
// gigabytes), or a path that is no regular file (a FIFO blocks the reader forever).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <thread>
#include <unistd.h>

#include "geometry/mesh_load.h"
#include "geometry/primitives.h"
#include "tests/support/mesh_files.h"

namespace kanesim::geometry {
namespace {

using namespace std::chrono_literals;

// Loading must decide within this bound: the header checks read at most 64 KiB (a full
// import of these tiny files takes milliseconds; the unchecked 10⁸-vertex PLY took > 60 s).
constexpr auto kPrompt = 5s;

bool Has(const std::vector<MeshProblem>& problems, MeshProblemKind kind) {
  for (const MeshProblem& p : problems)
    if (p.kind == kind) return true;
  return false;
}

std::string Describe(const std::vector<MeshProblem>& problems) {
  std::string s;
  for (const MeshProblem& p : problems) s += std::string(InfoOf(p.kind).id) + ": " + p.message + "\n";
  return s;
}

// `load(path)` on a detached thread, waited for at most kPrompt (a std::async future would
// wait for a hung load in its destructor). Null when it did not return in time.
template <typename Result>
std::shared_ptr<Result> Promptly(Result (*load)(const std::string&, const LoadMeshOptions&), const std::string& path) {
  auto done = std::make_shared<std::promise<std::shared_ptr<Result>>>();
  auto future = done->get_future();
  std::thread([done, load, path] { done->set_value(std::make_shared<Result>(load(path, {}))); }).detach();
  if (future.wait_for(kPrompt) != std::future_status::ready) return nullptr;
  return future.get();
}

// LoadMesh and LoadVisualMesh, each within kPrompt.
struct Both {
  bool in_time = false;
  MeshLoadResult solid;
  VisualMeshResult visual;
};
Both LoadPromptly(const std::string& path) {
  Both b;
  const auto solid = Promptly(&LoadMesh, path);
  if (!solid) return b;
  b.solid = *solid;
  const auto visual = Promptly(&LoadVisualMesh, path);
  if (!visual) return b;
  b.visual = *visual;
  b.in_time = true;
  return b;
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

const std::string kPlyHead = "ply\nformat ascii 1.0\nelement vertex ";
const std::string kPlyProps =
    "\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int "
    "vertex_indices\nend_header\n";

// The reproducer of issue 38: 167 bytes claiming 99,999,999 vertices, over the limit.
TEST(DeclaredSizes, PlyClaimingMoreVerticesThanTheLimitIsRefusedBeforeAssimp) {
  const std::string dir = testing::TempDir("ply_claims");
  WriteBytes(dir + "/claims.ply", kPlyHead + "99999999" + kPlyProps + "0 0 0\n");
  const Both b = LoadPromptly(dir + "/claims.ply");
  ASSERT_TRUE(b.in_time);
  EXPECT_TRUE(Has(b.solid.problems, MeshProblemKind::kTooLarge)) << Describe(b.solid.problems);
  EXPECT_TRUE(Has(b.visual.problems, MeshProblemKind::kTooLarge)) << Describe(b.visual.problems);
  EXPECT_NE(b.solid.problems.front().message.find("99999999 vertex"), std::string::npos);
}

// Within the limits but beyond the file: 3,000,000 vertices need at least 6 bytes each in
// ASCII ("0 0 0\n"), the file holds one line. Binary: 12 bytes per vertex.
TEST(DeclaredSizes, PlyClaimingMoreThanItHoldsIsRefused) {
  const std::string dir = testing::TempDir("ply_beyond");
  WriteBytes(dir + "/ascii.ply", kPlyHead + "3000000" + kPlyProps + "0 0 0\n3 0 0 0\n");
  std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float "
                       "y\nproperty float z\nend_header\n";
  binary.append(12 * 999, '\0');  // one vertex short
  WriteBytes(dir + "/binary.ply", binary);
  for (const char* name : {"ascii.ply", "binary.ply"}) {
    const Both b = LoadPromptly(dir + "/" + name);
    ASSERT_TRUE(b.in_time) << name;
    EXPECT_TRUE(Has(b.solid.problems, MeshProblemKind::kDeclaredBeyondFile)) << name << Describe(b.solid.problems);
    EXPECT_TRUE(Has(b.visual.problems, MeshProblemKind::kDeclaredBeyondFile)) << name;
  }
  // Another element than vertex and face, with an absurd count and no properties.
  WriteBytes(dir + "/other.ply", kPlyHead + "4" + kPlyProps.substr(0, kPlyProps.size() - 11) +
                                     "element material 5000000000\nend_header\n");
  EXPECT_TRUE(Has(LoadMesh(dir + "/other.ply").problems, MeshProblemKind::kTooLarge));
  // A count that is no number, and a header without end.
  WriteBytes(dir + "/nan.ply", kPlyHead + "-3" + kPlyProps);
  EXPECT_TRUE(Has(LoadMesh(dir + "/nan.ply").problems, MeshProblemKind::kImportFailed));
  WriteBytes(dir + "/endless.ply", kPlyHead + "8\nproperty float x\n");
  EXPECT_TRUE(Has(LoadMesh(dir + "/endless.ply").problems, MeshProblemKind::kImportFailed));
}

// Wrong if the bound (eqs. 1-2) refused a real file: the tightest ASCII PLY (one-digit
// coordinates, "0 0 0" lines, no trailing newline) and a binary PLY load as the tetrahedron
// they hold (volume 1/6).
TEST(DeclaredSizes, TightAndBinaryPlyLoad) {
  const std::string dir = testing::TempDir("ply_tight");
  WriteBytes(dir + "/tight.ply",
             kPlyHead + "4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar "
                        "int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3");
  const MeshLoadResult tight = LoadMesh(dir + "/tight.ply");
  ASSERT_TRUE(tight.ok()) << Describe(tight.problems);
  EXPECT_NEAR(tight.report.volume, 1.0 / 6.0, 1e-12);
  const TriMesh box = BoxSolid(Vec3(2, 1, 0.5));
  testing::WriteBinaryPly(dir + "/box.ply", box);
  const MeshLoadResult binary = LoadMesh(dir + "/box.ply");
  ASSERT_TRUE(binary.ok()) << Describe(binary.problems);
  EXPECT_NEAR(binary.report.volume, 1.0, 1e-12);
}

// Binary STL: 84 + 50 n bytes exactly. Counts above and below the 12 triangles held, the
// largest count, a count that passes assimp's 32-bit size test (2³¹ + 12: 50 · 2³¹ wraps
// to 0), a truncated file, and a file too short for the header.
TEST(DeclaredSizes, BinaryStlCountMustMatchTheSize) {
  const std::string dir = testing::TempDir("stl_counts");
  const TriMesh box = BoxSolid(Vec3(2, 1, 0.5));
  testing::WriteBinaryStl(dir + "/ok.stl", box);
  std::string good;
  {
    std::ifstream in(dir + "/ok.stl", std::ios::binary);
    good.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_EQ(good.size(), 84u + 50u * 12u);
  const auto with_count = [&](uint32_t n) {
    std::string s = good;
    std::memcpy(s.data() + 80, &n, 4);
    return s;
  };
  const std::pair<const char*, std::string> cases[] = {
      {"high.stl", with_count(1000000)},      {"low.stl", with_count(3)},
      {"max.stl", with_count(0xFFFFFFFFu)},   {"wrap.stl", with_count((1u << 31) + 12u)},
      {"truncated.stl", good.substr(0, 84 + 50 * 5 + 17)}, {"short.stl", good.substr(0, 40)}};
  for (const auto& [name, bytes] : cases) {
    WriteBytes(dir + "/" + name, bytes);
    const Both b = LoadPromptly(dir + "/" + name);
    ASSERT_TRUE(b.in_time) << name;
    EXPECT_TRUE(Has(b.solid.problems, MeshProblemKind::kDeclaredBeyondFile)) << name << Describe(b.solid.problems);
    EXPECT_TRUE(Has(b.visual.problems, MeshProblemKind::kDeclaredBeyondFile)) << name;
  }
  // A binary STL whose 80-byte header starts with "solid" (some exporters write that) is
  // still binary when its size matches; over the triangle limit it is refused before assimp.
  std::string solid_header = good;
  solid_header.replace(0, 5, "solid");
  WriteBytes(dir + "/solid_header.stl", solid_header);
  EXPECT_TRUE(LoadMesh(dir + "/solid_header.stl").ok());
  LoadMeshOptions ten;
  ten.limits.max_triangles = 10;
  EXPECT_TRUE(Has(LoadMesh(dir + "/ok.stl", ten).problems, MeshProblemKind::kTooLarge));
}

// glTF: a buffer larger than the file it names, a data URI shorter than its byteLength, a
// byteLength over the file limit, a view beyond its buffer, an accessor beyond its view (the
// probe's bad.gltf: 9,999,999 VEC3 floats in a 99,999,999-byte view of /etc/passwd), and a
// .glb whose declared length is not its size. Valid .gltf and .glb load (wrong if the parser
// or the bounds refused a real file).
TEST(DeclaredSizes, GltfBuffersViewsAndAccessorsMustFit) {
  const std::string dir = testing::TempDir("gltf_sizes");
  const TriMesh box = BoxSolid(Vec3(2, 1, 0.5));
  testing::WriteGltf(dir + "/ok.gltf", box, Vec3(1, 2, 3));
  testing::WriteGlb(dir + "/ok.glb", box, Vec3(1, 2, 3));
  for (const char* name : {"ok.gltf", "ok.glb"}) {
    const MeshLoadResult r = LoadMesh(dir + "/" + name);
    ASSERT_TRUE(r.ok()) << name << Describe(r.problems);
    EXPECT_NEAR(r.report.volume, 1.0, 1e-12) << name;
  }
  testing::WriteText(dir + "/small.bin", std::string(100, '\0'));
  const std::string tail =
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
  const std::pair<const char*, std::string> beyond[] = {
      {"file.gltf", R"({"asset":{"version":"2.0"},"buffers":[{"uri":"small.bin","byteLength":1000}],)" + tail},
      {"datauri.gltf",
       R"({"asset":{"version":"2.0"},"buffers":[{"uri":"data:application/octet-stream;base64,AAAA","byteLength":100}],)" +
           tail},
      {"view.gltf", R"({"asset":{"version":"2.0"},"buffers":[{"uri":"small.bin","byteLength":100}],)"
                    R"("bufferViews":[{"buffer":0,"byteOffset":60,"byteLength":48}],)" + tail},
      {"accessor.gltf", R"({"asset":{"version":"2.0"},"buffers":[{"uri":"small.bin","byteLength":100}],)"
                        R"("bufferViews":[{"buffer":0,"byteLength":100}],)"
                        R"("accessors":[{"bufferView":0,"componentType":5126,"count":9,"type":"VEC3"}],)" + tail},
      {"probe.gltf", R"({"asset":{"version":"2.0"},"buffers":[{"uri":"small.bin","byteLength":99999999}],)"
                     R"("bufferViews":[{"buffer":0,"byteLength":99999999}],)"
                     R"("accessors":[{"bufferView":0,"componentType":5126,"count":9999999,"type":"VEC3"}],)" + tail}};
  for (const auto& [name, text] : beyond) {
    testing::WriteText(dir + "/" + name, text);
    const Both b = LoadPromptly(dir + "/" + name);
    ASSERT_TRUE(b.in_time) << name;
    EXPECT_TRUE(Has(b.solid.problems, MeshProblemKind::kDeclaredBeyondFile)) << name << Describe(b.solid.problems);
  }
  testing::WriteText(dir + "/huge.gltf",
                     R"({"asset":{"version":"2.0"},"buffers":[{"uri":"data:application/octet-stream;base64,AAAA",)"
                     R"("byteLength":4000000000}],)" + tail);
  EXPECT_TRUE(Has(LoadMesh(dir + "/huge.gltf").problems, MeshProblemKind::kTooLarge));
  // Nested 100 deep: refused as malformed, not a stack overflow.
  testing::WriteText(dir + "/deep.gltf", std::string(100000, '[') + std::string(100000, ']'));
  EXPECT_TRUE(Has(LoadMesh(dir + "/deep.gltf").problems, MeshProblemKind::kImportFailed));
  // A .glb whose header says 8 bytes more than it has.
  std::string glb;
  {
    std::ifstream in(dir + "/ok.glb", std::ios::binary);
    glb.assign(std::istreambuf_iterator<char>(in), {});
  }
  const uint32_t longer = static_cast<uint32_t>(glb.size() + 8);
  std::memcpy(glb.data() + 8, &longer, 4);
  WriteBytes(dir + "/long.glb", glb);
  EXPECT_TRUE(Has(LoadMesh(dir + "/long.glb").problems, MeshProblemKind::kDeclaredBeyondFile));
}

// OFF: assimp allocates the declared faces before reading them (10⁹: killed for memory) and
// aborts the process when fewer follow (an assertion in its triangulation: 10 declared, 1
// held). Counts over the limits, missing faces, a short vertex line and an index out of
// range are refused; the tetrahedron loads, counts on the header line too (volume 1/6).
TEST(DeclaredSizes, OffStructureIsCheckedBeforeAssimp) {
  const std::string dir = testing::TempDir("off");
  const std::string tet = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  WriteBytes(dir + "/ok.off", "OFF\n# a comment\n4 4 0\n" + tet);
  WriteBytes(dir + "/inline.off", "OFF 4 4 0\n" + tet);
  for (const char* name : {"ok.off", "inline.off"}) {
    const MeshLoadResult r = LoadMesh(dir + "/" + name);
    ASSERT_TRUE(r.ok()) << name << Describe(r.problems);
    EXPECT_NEAR(r.report.volume, 1.0 / 6.0, 1e-12) << name;
  }
  WriteBytes(dir + "/huge.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_TRUE(Has(LoadMesh(dir + "/huge.off").problems, MeshProblemKind::kTooLarge));
  const std::pair<const char*, std::string> beyond[] = {
      {"faces.off", "OFF\n3 10 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"vertex.off", "OFF\n4 4 0\n0 0 0\n1 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
      {"index.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 9\n3 0 3 2\n3 1 2 3\n"},
      {"short_face.off", "OFF\n4 4 0\n" + tet.substr(0, tet.size() - 4) + "\n"}};
  for (const auto& [name, text] : beyond) {
    WriteBytes(dir + "/" + name, text);
    const Both b = LoadPromptly(dir + "/" + name);
    ASSERT_TRUE(b.in_time) << name;
    EXPECT_TRUE(Has(b.solid.problems, MeshProblemKind::kDeclaredBeyondFile)) << name << Describe(b.solid.problems);
  }
}

// An ASCII STL with white space before "solid" is text, not a binary STL with a wrong count:
// assimp 5.2 does not read it, and says so itself.
TEST(DeclaredSizes, AsciiStlAfterWhiteSpaceIsNotABinaryCount) {
  const std::string dir = testing::TempDir("stl_space");
  testing::WriteAsciiStl(dir + "/box.stl", BoxSolid(Vec3(2, 1, 0.5)));
  std::string text;
  {
    std::ifstream in(dir + "/box.stl");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  WriteBytes(dir + "/spaced.stl", "\n  " + text);
  const MeshLoadResult r = LoadMesh(dir + "/spaced.stl");
  EXPECT_FALSE(Has(r.problems, MeshProblemKind::kDeclaredBeyondFile)) << Describe(r.problems);
  EXPECT_TRUE(Has(r.problems, MeshProblemKind::kImportFailed)) << Describe(r.problems);
}

// A FIFO (no writer: open(2) would wait for one forever), a symbolic link to it, and a
// character device are refused at once, as not regular files.
TEST(DeclaredSizes, NonRegularFilesAreRefusedWithoutBlocking) {
  const std::string dir = testing::TempDir("fifo");
  const std::string fifo = dir + "/part.stl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::filesystem::create_symlink(fifo, dir + "/link.stl");
  for (const std::string& path : {fifo, dir + "/link.stl", std::string("/dev/null")}) {
    const Both b = LoadPromptly(path);
    if (!b.in_time) {
      // Unblock the reader (a writer arrives) so that the test ends, then fail.
      const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
      if (fd >= 0) ::close(fd);
      FAIL() << path << " blocked the reader";
    }
    EXPECT_TRUE(Has(b.solid.problems, MeshProblemKind::kNotRegularFile)) << path << Describe(b.solid.problems);
    EXPECT_TRUE(Has(b.visual.problems, MeshProblemKind::kNotRegularFile)) << path;
  }
}

}  // namespace
}  // namespace kanesim::geometry
