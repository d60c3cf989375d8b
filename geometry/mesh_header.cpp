// Declared sizes of PLY and binary STL files against the file's size and the limits
// (mesh_header.h, eqs. 1-2).
#include "geometry/mesh_header.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <sstream>

namespace kanesim::geometry {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool StartsWith(const std::string& s, const std::string& prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

// A PLY element: its count and the fewest bytes one instance takes (eqs. 1-2).
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  uint64_t min_bytes = 0;  // per instance
};

// Size in bytes of a PLY scalar type, 0 for an unknown name.
uint64_t PlyTypeBytes(const std::string& type) {
  static const std::pair<const char*, uint64_t> kTypes[] = {
      {"char", 1},  {"uchar", 1},  {"int8", 1},  {"uint8", 1},  {"short", 2},   {"ushort", 2},
      {"int16", 2}, {"uint16", 2}, {"int", 4},   {"uint", 4},   {"int32", 4},   {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  for (const auto& [name, bytes] : kTypes)
    if (type == name) return bytes;
  return 0;
}

bool ParseCount(const std::string& text, uint64_t* out) {
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, *out);
  return ec == std::errc() && ptr == end;
}

bool Problem(std::vector<MeshProblem>& problems, MeshProblemKind kind, std::string message, uint64_t count = 0) {
  problems.push_back(MakeProblem(kind, std::move(message), count));
  return false;
}

// The PLY header: elements with their counts and per-instance sizes, and where the data
// starts. False with a problem when the header is malformed in a way that hides the counts.
bool ParsePlyHeader(const std::string& path, const std::string& head, bool* ascii, std::vector<PlyElement>* elements,
                    uint64_t* data_offset, std::vector<MeshProblem>& problems) {
  std::istringstream in(head);
  std::string line;
  uint64_t consumed = 0;
  *ascii = true;
  while (std::getline(in, line)) {
    consumed += line.size() + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") {
      *data_offset = consumed;
      return true;
    }
    if (keyword == "format") {
      std::string format;
      words >> format;
      *ascii = format == "ascii";
    } else if (keyword == "element") {
      PlyElement e;
      std::string count;
      words >> e.name >> count;
      if (!ParseCount(count, &e.count))
        return Problem(problems, MeshProblemKind::kImportFailed,
                       fmt::format("mesh file {}: PLY element '{}' has no valid count ('{}')", path, e.name, count));
      elements->push_back(e);
    } else if (keyword == "property" && !elements->empty()) {
      std::string type;
      words >> type;
      // A list's count is one value (eq. 1) of its count type (eq. 2); its items may be none.
      if (type == "list") words >> type;
      const uint64_t bytes = PlyTypeBytes(type);
      if (bytes == 0)
        return Problem(problems, MeshProblemKind::kImportFailed,
                       fmt::format("mesh file {}: PLY property of unknown type '{}'", path, type));
      elements->back().min_bytes += *ascii ? 2 : bytes;
    }
  }
  return Problem(problems, MeshProblemKind::kImportFailed,
                 fmt::format("mesh file {}: no end_header in the first {} bytes of the PLY header", path,
                             std::min<uint64_t>(head.size(), kHeaderBytes)));
}

// A PLY element's count limit: vertices and faces (each face at least one triangle) by
// their own limit, anything else by the larger one.
uint64_t PlyLimit(const std::string& element, const MeshLimits& limits) {
  if (element == "vertex") return limits.max_vertices;
  if (element == "face") return limits.max_triangles;
  return std::max(limits.max_vertices, limits.max_triangles);
}

bool CheckPly(const std::string& path, const std::string& head, uint64_t file_bytes, const MeshLimits& limits,
              std::vector<MeshProblem>& problems) {
  bool ascii = true;
  std::vector<PlyElement> elements;
  uint64_t data_offset = 0;
  if (!ParsePlyHeader(path, head, &ascii, &elements, &data_offset, problems)) return false;
  // The limits first: they bound the counts, so the byte sum below cannot overflow (the
  // properties per element are bounded by the header's 64 KiB).
  for (const PlyElement& e : elements)
    if (e.count > PlyLimit(e.name, limits))
      return Problem(problems, MeshProblemKind::kTooLarge,
                     fmt::format("mesh file {} declares {} {} elements in its PLY header; the limit is {}", path,
                                 e.count, e.name, PlyLimit(e.name, limits)),
                     e.count);
  uint64_t needed = 0;
  for (const PlyElement& e : elements) needed += e.count * e.min_bytes;
  if (ascii && needed > 0) needed -= 1;  // the last value needs no separator after it
  const uint64_t held = file_bytes - std::min(file_bytes, data_offset);
  if (needed <= held) return true;
  std::string counts;
  for (const PlyElement& e : elements) counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", e.count, e.name);
  return Problem(problems, MeshProblemKind::kDeclaredBeyondFile,
                 fmt::format("mesh file {} declares {} in its PLY header ({}: at least {} bytes of data), but holds "
                             "only {} bytes after the header",
                             path, counts, ascii ? "ascii" : "binary", needed, held));
}

// Binary STL: an 80-byte header, a uint32 triangle count n (little-endian), 50 bytes per
// triangle. An ASCII STL starts with "solid" and has no count; a binary file whose size is
// exactly 84 + 50 n is binary even when its header starts with "solid" (as assimp decides).
bool CheckStl(const std::string& path, const std::string& head, uint64_t file_bytes, const MeshLimits& limits,
              std::vector<MeshProblem>& problems) {
  // (assimp skips leading white space before "solid")
  const size_t text_at = std::min(head.find_first_not_of(" \t\r\n"), head.size());
  const bool looks_ascii = StartsWith(Lower(head.substr(text_at, 5)), "solid");
  if (file_bytes < 84) {
    if (looks_ascii || file_bytes == 0) return true;  // text, or empty (assimp says what is wrong)
    return Problem(problems, MeshProblemKind::kDeclaredBeyondFile,
                   fmt::format("mesh file {} has {} bytes: too short for a binary STL (84-byte header) and not an "
                               "ASCII STL (no 'solid' at the start)",
                               path, file_bytes));
  }
  const auto byte = [&](int i) { return static_cast<uint64_t>(static_cast<unsigned char>(head[80 + i])); };
  const uint64_t n = byte(0) | byte(1) << 8 | byte(2) << 16 | byte(3) << 24;
  const uint64_t expected = 84 + 50 * n;
  if (expected == file_bytes) {
    if (n <= limits.max_triangles) return true;
    return Problem(problems, MeshProblemKind::kTooLarge,
                   fmt::format("mesh file {} has {} triangles; the limit is {}", path, n, limits.max_triangles), n);
  }
  // assimp's own test compares 84 + 50 n in 32 bits: a wrapped size passes it.
  const bool binary_to_assimp = static_cast<uint32_t>(expected) == static_cast<uint32_t>(file_bytes);
  if (looks_ascii && !binary_to_assimp) return true;
  return Problem(problems, MeshProblemKind::kDeclaredBeyondFile,
                 fmt::format("mesh file {} is a binary STL declaring {} triangles ({} bytes), but has {} bytes: "
                             "the count is wrong or the file is truncated",
                             path, n, expected, file_bytes));
}

// OFF: a header line ("OFF", "COFF", "NOFF", ...; the counts may follow on it), the counts
// "nv nf [ne]", nv vertex lines of at least 3 numbers, nf face lines "k i_1 ... i_k". assimp
// allocates nf faces before it reads them and aborts the process (an assertion in its
// triangulation) when fewer follow, so the whole structure is checked here; the file is
// text, so reading it all costs what assimp's reading does.
bool CheckOff(const std::string& path, const std::string& text, const MeshLimits& limits,
              std::vector<MeshProblem>& problems) {
  std::istringstream in(text);
  std::string line;
  const auto next = [&](std::vector<std::string>* words) {
    words->clear();
    while (std::getline(in, line)) {
      if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      std::istringstream w(line);
      words->clear();
      for (std::string word; w >> word;) words->push_back(word);
      if (!words->empty()) return true;
    }
    return false;
  };
  std::vector<std::string> header, counts;
  if (!next(&header)) return true;  // empty: assimp says so
  counts.assign(header.begin() + 1, header.end());
  if (counts.empty() && !next(&counts)) counts.clear();
  uint64_t nv = 0, nf = 0;
  if (counts.size() < 2 || !ParseCount(counts[0], &nv) || !ParseCount(counts[1], &nf))
    return Problem(problems, MeshProblemKind::kImportFailed,
                   fmt::format("mesh file {}: the OFF header has no vertex and face counts", path));
  if (nv > limits.max_vertices || nf > limits.max_triangles)
    return Problem(problems, MeshProblemKind::kTooLarge,
                   fmt::format("mesh file {} declares {} vertices and {} faces in its OFF header; the limits are {} "
                               "and {}",
                               path, nv, nf, limits.max_vertices, limits.max_triangles),
                   std::max(nv, nf));
  const auto beyond = [&](const std::string& what) {
    return Problem(problems, MeshProblemKind::kDeclaredBeyondFile,
                   fmt::format("mesh file {} declares {} vertices and {} faces in its OFF header, but {}", path, nv,
                               nf, what));
  };
  std::vector<std::string> words;
  for (uint64_t v = 0; v < nv; ++v)
    if (!next(&words) || words.size() < 3)
      return beyond(fmt::format("vertex {} is {}", v + 1, words.empty() ? "missing" : "not 3 numbers"));
  for (uint64_t f = 0; f < nf; ++f) {
    uint64_t k = 0;
    if (!next(&words) || !ParseCount(words[0], &k) || words.size() < k + 1)
      return beyond(fmt::format("face {} is {}", f + 1, words.empty() ? "missing" : "not 'k i_1 ... i_k'"));
    for (uint64_t i = 1; i <= k; ++i) {
      uint64_t index = 0;
      if (!ParseCount(words[i], &index) || index >= nv)
        return beyond(fmt::format("face {} names vertex '{}', not one of 0 to {}", f + 1, words[i], nv - 1));
    }
  }
  return true;
}

// The .glb container: a 12-byte header, then chunks (length, type, data); the first is the
// JSON, an optional second the BIN buffer.
bool CheckGlb(const std::string& path, const std::string& file, const MeshLimits& limits,
              std::vector<MeshProblem>& problems) {
  const auto u32 = [&](size_t at) {
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = v << 8 | static_cast<unsigned char>(file[at + static_cast<size_t>(i)]);
    return static_cast<uint64_t>(v);
  };
  const auto truncated = [&](const std::string& what) {
    return Problem(problems, MeshProblemKind::kDeclaredBeyondFile,
                   fmt::format("mesh file {} (binary glTF) {}; it has {} bytes", path, what, file.size()));
  };
  if (file.size() < 20) return truncated("is too short for the 12-byte header and a chunk header");
  if (u32(8) != file.size()) return truncated(fmt::format("declares a total length of {} bytes", u32(8)));
  const uint64_t json_bytes = u32(12);
  if (20 + json_bytes > file.size()) return truncated(fmt::format("declares a JSON chunk of {} bytes", json_bytes));
  int64_t bin_bytes = -1;
  const uint64_t bin_at = 20 + json_bytes;
  if (bin_at + 8 <= file.size()) {
    bin_bytes = static_cast<int64_t>(u32(bin_at));
    if (bin_at + 8 + static_cast<uint64_t>(bin_bytes) > file.size())
      return truncated(fmt::format("declares a BIN chunk of {} bytes", bin_bytes));
  }
  return CheckGltfDeclaredSizes(path, file.substr(20, json_bytes), bin_bytes, limits, problems);
}

// The whole file (a .gltf or .glb is read in full by assimp too; the size limit holds).
std::string ReadAll(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  std::string text;
  if (f == nullptr) return text;
  char buffer[65536];
  for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
  std::fclose(f);
  return text;
}

}  // namespace

bool CheckDeclaredSizes(const std::string& path, const std::string& head, uint64_t file_bytes,
                        const MeshLimits& limits, std::vector<MeshProblem>& problems) {
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  if (StartsWith(head, "ply\n") || StartsWith(head, "ply\r\n")) return CheckPly(path, head, file_bytes, limits, problems);
  if (ext == ".stl") return CheckStl(path, head, file_bytes, limits, problems);
  if (StartsWith(head, "glTF")) return CheckGlb(path, ReadAll(path), limits, problems);
  if (ext == ".gltf") return CheckGltfDeclaredSizes(path, ReadAll(path), -1, limits, problems);
  if (ext == ".off") return CheckOff(path, ReadAll(path), limits, problems);
  return true;
}

}  // namespace kanesim::geometry
