// glTF 2.0's declared sizes (mesh_header.h): every buffer, buffer view and accessor must fit
// in what holds it, before assimp allocates by them (glTF 2.0 specification, sec. 3.6):
//
//   buffer b:       byteLength_b ≤ the bytes it has (external file, base64 data URI, GLB BIN chunk)
//   buffer view v:  byteOffset_v + byteLength_v ≤ byteLength_b(v)
//   accessor a:     byteOffset_a + (count_a − 1) · stride_v + size_a ≤ byteLength_v(a),
//                   size_a = component bytes · components of its type, stride_v = byteStride_v or size_a
//   and count_a ≤ max(max_vertices, 3 max_triangles) (an index accessor holds 3 per triangle).
//
// The JSON is read by a small recursive-descent parser of its own (no JSON library is a
// dependency), nesting bounded by kMaxDepth so that a hostile file cannot exhaust the stack.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

#include "geometry/mesh_header.h"

namespace kanesim::geometry {
namespace {

constexpr int kMaxDepth = 64;

// A JSON value; objects keep only what the checks read (numbers, strings, nesting).
struct Json {
  enum Kind { kNull, kBool, kNumber, kString, kArray, kObject } kind = kNull;
  double number = 0;
  std::string text;
  std::vector<Json> items;                 // kArray
  std::map<std::string, Json> members;     // kObject (a repeated key: the last)
  const Json* Get(const std::string& key) const {
    auto it = members.find(key);
    return kind == kObject && it != members.end() ? &it->second : nullptr;
  }
};

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}
  bool Parse(Json* out) {
    if (!Value(out, 0)) return false;
    Space();
    return at_ == s_.size();
  }

 private:
  void Space() {
    while (at_ < s_.size() && (s_[at_] == ' ' || s_[at_] == '\t' || s_[at_] == '\n' || s_[at_] == '\r')) ++at_;
  }
  bool Eat(char c) {
    Space();
    if (at_ < s_.size() && s_[at_] == c) return ++at_, true;
    return false;
  }
  // value = object | array | string | number | true | false | null
  bool Value(Json* v, int depth) {
    if (depth > kMaxDepth) return false;
    Space();
    if (at_ >= s_.size()) return false;
    const char c = s_[at_];
    if (c == '{') return Object(v, depth);
    if (c == '[') return Array(v, depth);
    if (c == '"') return v->kind = Json::kString, String(&v->text);
    for (const char* word : {"true", "false", "null"})
      if (s_.compare(at_, std::strlen(word), word) == 0) {
        at_ += std::strlen(word);
        v->kind = word[0] == 'n' ? Json::kNull : Json::kBool;
        return true;
      }
    return Number(v);
  }
  // object = '{' [string ':' value {',' string ':' value}] '}'
  bool Object(Json* v, int depth) {
    v->kind = Json::kObject;
    ++at_;
    if (Eat('}')) return true;
    do {
      std::string key;
      Space();
      if (at_ >= s_.size() || s_[at_] != '"' || !String(&key) || !Eat(':')) return false;
      Json member;
      if (!Value(&member, depth + 1)) return false;
      v->members[key] = std::move(member);
    } while (Eat(','));
    return Eat('}');
  }
  // array = '[' [value {',' value}] ']'
  bool Array(Json* v, int depth) {
    v->kind = Json::kArray;
    ++at_;
    if (Eat(']')) return true;
    do {
      v->items.emplace_back();
      if (!Value(&v->items.back(), depth + 1)) return false;
    } while (Eat(','));
    return Eat(']');
  }
  // string = '"' {char | '\' escape} '"'  (escapes kept as written: keys and URIs the
  // checks read have none that matter)
  bool String(std::string* out) {
    ++at_;
    while (at_ < s_.size() && s_[at_] != '"') {
      if (s_[at_] == '\\') out->push_back(s_[at_++]);
      if (at_ < s_.size()) out->push_back(s_[at_++]);
    }
    return at_ < s_.size() && s_[at_++] == '"';
  }
  bool Number(Json* v) {
    const char* begin = s_.c_str() + at_;
    char* end = nullptr;
    v->number = std::strtod(begin, &end);
    if (end == begin) return false;
    v->kind = Json::kNumber;
    at_ += static_cast<size_t>(end - begin);
    return true;
  }

  const std::string& s_;
  size_t at_ = 0;
};

// A non-negative integer member (`fallback` when absent); -1 when present but not one.
double Count(const Json& object, const char* key, double fallback = 0) {
  const Json* v = object.Get(key);
  if (v == nullptr) return fallback;
  if (v->kind != Json::kNumber || !(v->number >= 0) || v->number != std::floor(v->number)) return -1;
  return v->number;
}

// The bytes a buffer has: its data URI decoded, its external file, or the GLB BIN chunk.
// -1 when unknown (a file that does not exist: assimp says so).
double BytesHeld(const std::string& path, const Json& buffer, int64_t bin_bytes) {
  const Json* uri = buffer.Get("uri");
  if (uri == nullptr || uri->kind != Json::kString) return static_cast<double>(bin_bytes);
  const std::string& u = uri->text;
  if (u.compare(0, 5, "data:") == 0) {
    const size_t comma = u.find(',');
    if (comma == std::string::npos || u.rfind(";base64", comma) == std::string::npos) return -1;
    size_t n = u.size() - comma - 1;
    size_t pad = 0;
    while (pad < 2 && n > pad && u[u.size() - 1 - pad] == '=') ++pad;
    return static_cast<double>(n / 4 * 3 + (n % 4 == 0 ? 0 : n % 4 - 1) - pad);
  }
  std::error_code ec;
  const auto file = std::filesystem::path(path).parent_path() / u;
  if (!std::filesystem::is_regular_file(file, ec)) return -1;
  const auto size = std::filesystem::file_size(file, ec);
  return ec ? -1 : static_cast<double>(size);
}

int Components(const std::string& type) {
  static const std::pair<const char*, int> kTypes[] = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4},
                                                      {"MAT2", 4},   {"MAT3", 9}, {"MAT4", 16}};
  for (const auto& [name, n] : kTypes)
    if (type == name) return n;
  return 0;
}

int ComponentBytes(double type) {
  if (type == 5120 || type == 5121) return 1;  // BYTE, UNSIGNED_BYTE
  if (type == 5122 || type == 5123) return 2;  // SHORT, UNSIGNED_SHORT
  if (type == 5125 || type == 5126) return 4;  // UNSIGNED_INT, FLOAT
  return 0;
}

const std::vector<Json>& Items(const Json& root, const char* key) {
  static const std::vector<Json> kNone;
  const Json* v = root.Get(key);
  return v != nullptr && v->kind == Json::kArray ? v->items : kNone;
}

bool Beyond(std::vector<MeshProblem>& problems, const std::string& path, const std::string& what) {
  problems.push_back(MakeProblem(MeshProblemKind::kDeclaredBeyondFile, fmt::format("mesh file {}: glTF {}", path, what)));
  return false;
}

}  // namespace

bool CheckGltfDeclaredSizes(const std::string& path, const std::string& json, int64_t bin_bytes,
                            const MeshLimits& limits, std::vector<MeshProblem>& problems) {
  Json root;
  if (!Parser(json).Parse(&root) || root.kind != Json::kObject) {
    problems.push_back(MakeProblem(MeshProblemKind::kImportFailed,
                                   fmt::format("mesh file {}: its glTF JSON is malformed (or nested deeper than {})",
                                               path, kMaxDepth)));
    return false;
  }
  const std::vector<Json>& buffers = Items(root, "buffers");
  std::vector<double> buffer_bytes;
  for (size_t b = 0; b < buffers.size(); ++b) {
    const double declared = Count(buffers[b], "byteLength", -1);
    if (declared < 0) return Beyond(problems, path, fmt::format("buffer {} has no valid byteLength", b));
    if (declared > static_cast<double>(limits.max_file_bytes)) {
      problems.push_back(MakeProblem(MeshProblemKind::kTooLarge,
                                     fmt::format("mesh file {}: glTF buffer {} declares {} bytes; the limit is {}", path,
                                                 b, declared, limits.max_file_bytes)));
      return false;
    }
    const double held = BytesHeld(path, buffers[b], bin_bytes);
    if (held >= 0 && declared > held)
      return Beyond(problems, path, fmt::format("buffer {} declares {} bytes but holds {}", b, declared, held));
    buffer_bytes.push_back(declared);
  }
  const std::vector<Json>& views = Items(root, "bufferViews");
  std::vector<double> view_bytes, view_stride;
  for (size_t v = 0; v < views.size(); ++v) {
    const double buffer = Count(views[v], "buffer", -1), offset = Count(views[v], "byteOffset"),
                 length = Count(views[v], "byteLength", -1), stride = Count(views[v], "byteStride");
    if (buffer < 0 || buffer >= static_cast<double>(buffer_bytes.size()) || offset < 0 || length < 0 || stride < 0)
      return Beyond(problems, path, fmt::format("buffer view {} names no buffer or has an invalid size", v));
    if (offset + length > buffer_bytes[static_cast<size_t>(buffer)])
      return Beyond(problems, path,
                    fmt::format("buffer view {} spans bytes {} to {} of buffer {}, which has {}", v, offset,
                                offset + length, buffer, buffer_bytes[static_cast<size_t>(buffer)]));
    view_bytes.push_back(length);
    view_stride.push_back(stride);
  }
  const double max_count = static_cast<double>(std::max(limits.max_vertices, 3 * limits.max_triangles));
  const std::vector<Json>& accessors = Items(root, "accessors");
  for (size_t a = 0; a < accessors.size(); ++a) {
    const Json& acc = accessors[a];
    const double count = Count(acc, "count", -1);
    if (count < 0) return Beyond(problems, path, fmt::format("accessor {} has no valid count", a));
    if (count > max_count) {
      problems.push_back(MakeProblem(
          MeshProblemKind::kTooLarge,
          fmt::format("mesh file {}: glTF accessor {} declares {} elements; the limit is {}", path, a, count, max_count),
          static_cast<uint64_t>(count)));
      return false;
    }
    const double view = Count(acc, "bufferView", -1);
    if (acc.Get("bufferView") == nullptr || count == 0) continue;  // zeros (or sparse values only)
    const Json* type = acc.Get("type");
    const double size = ComponentBytes(Count(acc, "componentType", -1)) *
                        Components(type != nullptr && type->kind == Json::kString ? type->text : "");
    if (view < 0 || view >= static_cast<double>(view_bytes.size()) || size == 0)
      return Beyond(problems, path, fmt::format("accessor {} names no buffer view or has an unknown type", a));
    const double offset = Count(acc, "byteOffset"), stride = view_stride[static_cast<size_t>(view)];
    const double needed = offset + (count - 1) * (stride > 0 ? stride : size) + size;
    if (offset < 0 || needed > view_bytes[static_cast<size_t>(view)])
      return Beyond(problems, path,
                    fmt::format("accessor {} declares {} elements of {} bytes ({} bytes) but its buffer view {} "
                                "holds {}",
                                a, count, size, needed, view, view_bytes[static_cast<size_t>(view)]));
  }
  return true;
}

}  // namespace kanesim::geometry
