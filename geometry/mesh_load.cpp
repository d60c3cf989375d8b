#include "geometry/mesh_load.h"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "geometry/assimp_module.h"
#include "geometry/mesh_header.h"

namespace kanesim::geometry {
namespace {

// What a path names when it is not a regular file (for the message).
const char* NonRegularKind(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "a directory";
  if (S_ISFIFO(st.st_mode)) return "a named pipe (FIFO)";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a regular file";
}

// The file's first bytes (at most kHeaderBytes) through an open descriptor.
std::string ReadHead(int fd, uint64_t file_bytes) {
  std::string head(static_cast<size_t>(std::min<uint64_t>(file_bytes, kHeaderBytes)), '\0');
  size_t got = 0;
  while (got < head.size()) {
    const ssize_t n = ::read(fd, head.data() + got, head.size() - got);
    if (n <= 0) break;
    got += static_cast<size_t>(n);
  }
  head.resize(got);
  return head;
}

// The checks before assimp sees the file: scale, existence, a regular file (a FIFO or a
// device would block the reader forever or never end), readability, size, and the counts
// its header declares (mesh_header.h: assimp allocates by them).
bool CheckFile(const std::string& path, const LoadMeshOptions& options, std::vector<MeshProblem>& problems) {
  if (!std::isfinite(options.scale) || !(options.scale > 0)) {
    problems.push_back(MakeProblem(MeshProblemKind::kBadScale,
                                   fmt::format("scale must be finite and positive, not {}", options.scale)));
    return false;
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) {
      problems.push_back(MakeProblem(MeshProblemKind::kFileMissing, fmt::format("mesh file not found: {}", path)));
    } else {
      problems.push_back(MakeProblem(MeshProblemKind::kFileUnreadable,
                                     fmt::format("cannot read mesh file {}: {}", path, std::strerror(errno))));
    }
    return false;
  }
  if (S_ISDIR(st.st_mode)) {
    problems.push_back(
        MakeProblem(MeshProblemKind::kFileUnreadable, fmt::format("cannot read mesh file {}: it is a directory", path)));
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    problems.push_back(MakeProblem(MeshProblemKind::kNotRegularFile,
                                   fmt::format("cannot read mesh file {}: it is {}, not a regular file", path,
                                               NonRegularKind(st))));
    return false;
  }
  // O_NONBLOCK: should the path have become a FIFO since stat, open does not wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    problems.push_back(MakeProblem(MeshProblemKind::kFileUnreadable,
                                   fmt::format("cannot read mesh file {}: {}", path, std::strerror(errno))));
    return false;
  }
  struct stat opened {};
  const bool regular = ::fstat(fd, &opened) == 0 && S_ISREG(opened.st_mode);
  const uint64_t bytes = regular ? static_cast<uint64_t>(opened.st_size) : 0;
  const std::string head = regular && bytes <= options.limits.max_file_bytes ? ReadHead(fd, bytes) : std::string();
  ::close(fd);
  if (!regular) {
    problems.push_back(MakeProblem(MeshProblemKind::kNotRegularFile,
                                   fmt::format("cannot read mesh file {}: it is {}, not a regular file", path,
                                               NonRegularKind(opened))));
    return false;
  }
  if (bytes > options.limits.max_file_bytes) {
    problems.push_back(MakeProblem(MeshProblemKind::kTooLarge,
                                   fmt::format("mesh file {} has {} bytes; the limit is {} bytes", path, bytes,
                                               options.limits.max_file_bytes),
                                   bytes));
    return false;
  }
  return CheckDeclaredSizes(path, head, bytes, options.limits, problems);
}

// assimp's reading of the file, or a problem.
bool Import(const std::string& path, bool with_normals, assimp_io::ImportReply& reply,
            std::vector<MeshProblem>& problems) {
  std::string error;
  const assimp_io::ModuleApi* api = assimp_io::Module(&error);
  if (!api) {
    problems.push_back(MakeProblem(MeshProblemKind::kModuleMissing, error));
    return false;
  }
  reply = api->import_mesh({path, with_normals});
  if (!reply.ok) {
    problems.push_back(MakeProblem(MeshProblemKind::kImportFailed,
                                   fmt::format("assimp could not read mesh file {}: {}", path, reply.error)));
    return false;
  }
  if (reply.triangles.empty()) {
    problems.push_back(MakeProblem(MeshProblemKind::kNoTriangles,
                                   fmt::format("mesh file {} has no triangles (points, lines or nothing)", path)));
    return false;
  }
  return true;
}

bool WithinLimit(const char* what, uint64_t n, uint64_t limit, const std::string& path,
                 std::vector<MeshProblem>& problems) {
  if (n <= limit) return true;
  problems.push_back(MakeProblem(MeshProblemKind::kTooLarge,
                                 fmt::format("mesh file {} has {} {}; the limit is {}", path, n, what, limit), n));
  return false;
}

}  // namespace

MeshLoadResult LoadMesh(const std::string& path, const LoadMeshOptions& options) {
  MeshLoadResult result;
  assimp_io::ImportReply reply;
  if (!CheckFile(path, options, result.problems) || !Import(path, false, reply, result.problems)) return result;
  if (!WithinLimit("triangles", reply.triangles.size(), options.limits.max_triangles, path, result.problems))
    return result;
  for (Vec3& p : reply.vertices) p *= options.scale;
  result.mesh = WeldByPosition(reply.vertices, reply.triangles);
  if (!WithinLimit("distinct vertices", result.mesh.vertices.size(), options.limits.max_vertices, path,
                   result.problems))
    return result;
  result.report = CheckSolid(result.mesh);
  for (MeshProblem& p : result.report.problems) result.problems.push_back(p);
  return result;
}

VisualMeshResult LoadVisualMesh(const std::string& path, const LoadMeshOptions& options) {
  VisualMeshResult result;
  assimp_io::ImportReply reply;
  if (!CheckFile(path, options, result.problems) || !Import(path, true, reply, result.problems)) return result;
  if (!WithinLimit("triangles", reply.triangles.size(), options.limits.max_triangles, path, result.problems) ||
      !WithinLimit("vertices", reply.vertices.size(), options.limits.max_vertices, path, result.problems))
    return result;
  uint64_t non_finite = 0;
  for (const Vec3& p : reply.vertices) non_finite += !p.allFinite();
  if (non_finite > 0) {
    result.problems.push_back(MakeProblem(
        MeshProblemKind::kNonFinite, fmt::format("{} vert{} of {} {} NaN or infinite coordinates", non_finite, non_finite == 1 ? "ex" : "ices", path, non_finite == 1 ? "has" : "have"),
        non_finite));
    return result;
  }
  VisualMesh& m = result.mesh;
  m.vertices = std::move(reply.vertices);
  for (Vec3& p : m.vertices) p *= options.scale;
  m.normals = std::move(reply.normals);
  for (Vec3& n : m.normals) {
    const double len = n.allFinite() ? n.norm() : 0.0;
    n = len > 0 ? Vec3(n / len) : Vec3::UnitZ();
  }
  m.triangles = std::move(reply.triangles);
  return result;
}

}  // namespace kanesim::geometry
