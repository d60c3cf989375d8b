#include "viz/scene_json.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace kanesim::viz {
namespace {

// The page decodes little-endian arrays (JavaScript typed arrays on every platform a browser
// runs on); a big-endian host swaps bytes before encoding.
template <typename T>
std::string EncodeArray(std::vector<T> values) {
  if constexpr (std::endian::native == std::endian::big) {
    for (T& v : values) {
      unsigned char bytes[sizeof(T)];
      std::memcpy(bytes, &v, sizeof(T));
      std::reverse(bytes, bytes + sizeof(T));
      std::memcpy(&v, bytes, sizeof(T));
    }
  }
  return Base64(values.data(), values.size() * sizeof(T));
}

void AppendVec3(std::vector<float>& out, const Vec3& v) {
  out.push_back(static_cast<float>(v.x()));
  out.push_back(static_cast<float>(v.y()));
  out.push_back(static_cast<float>(v.z()));
}

std::string MeshJson(const VisualMesh& mesh) {
  std::vector<float> positions, normals;
  positions.reserve(3 * mesh.vertices.size());
  normals.reserve(3 * mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    AppendVec3(positions, mesh.vertices[i]);
    AppendVec3(normals, mesh.normals[i]);
  }
  const bool small = mesh.vertices.size() <= 65535;
  std::string indices;
  if (small) {
    std::vector<uint16_t> idx;
    idx.reserve(3 * mesh.triangles.size());
    for (const geometry::Tri& t : mesh.triangles)
      for (uint32_t i : t) idx.push_back(static_cast<uint16_t>(i));
    indices = EncodeArray(std::move(idx));
  } else {
    std::vector<uint32_t> idx;
    idx.reserve(3 * mesh.triangles.size());
    for (const geometry::Tri& t : mesh.triangles)
      for (uint32_t i : t) idx.push_back(i);
    indices = EncodeArray(std::move(idx));
  }
  return fmt::format(R"({{"vertices":{},"positions":"{}","normals":"{}","index_bytes":{},"indices":"{}"}})",
                     mesh.vertices.size(), EncodeArray(std::move(positions)), EncodeArray(std::move(normals)),
                     small ? 2 : 4, indices);
}

std::string Rgba(const std::array<float, 4>& c) { return fmt::format("[{},{},{},{}]", c[0], c[1], c[2], c[3]); }

std::string BodiesJson(const ViewerScene& scene) {
  std::string out = "[";
  for (const ViewerBody& b : scene.bodies) {
    if (out.size() > 1) out += ',';
    out += fmt::format(R"({{"name":{},"label":{},"rgba":{},"mesh":{}}})", JsonString(b.name), JsonString(b.label),
                       Rgba(b.rgba), MeshJson(b.mesh));
  }
  return out + "]";
}

std::string DecorationsJson(const ViewerScene& scene) {
  std::string out = "[";
  for (const ViewerDecoration& d : scene.decorations) {
    if (out.size() > 1) out += ',';
    out += fmt::format(R"({{"name":{},"body":{},"rgba":{},"mesh":{}}})", JsonString(d.name), d.body, Rgba(d.rgba),
                       MeshJson(d.mesh));
  }
  return out + "]";
}

// Per instant, per body: p_WB (x, y, z) then q_WB (w, x, y, z), normalised.
std::string PosesBase64(const ViewerScene& scene, const std::vector<size_t>& instants) {
  const size_t n_bodies = scene.bodies.size();
  std::vector<float> out;
  out.reserve(instants.size() * n_bodies * 7);
  for (size_t k : instants) {
    for (size_t b = 0; b < n_bodies; ++b) {
      const Vec3& p = scene.poses.p_WB[k * n_bodies + b];
      const Eigen::Quaterniond q = scene.poses.q_WB[k * n_bodies + b].normalized();
      AppendVec3(out, p);
      for (double c : {q.w(), q.x(), q.y(), q.z()}) out.push_back(static_cast<float>(c));
    }
  }
  return EncodeArray(std::move(out));
}

std::string SignalsJson(const ViewerScene& scene, const std::vector<size_t>& instants) {
  std::string out = "[";
  std::vector<float> values;
  for (const ViewerSignal& s : scene.signals) {
    values.clear();
    for (size_t k : instants) values.push_back(static_cast<float>(s.values[k]));
    if (out.size() > 1) out += ',';
    out += fmt::format(R"({{"name":{},"unit":{},"plot":{},"values":"{}"}})", JsonString(s.name), JsonString(s.unit),
                       s.plot ? "true" : "false", EncodeArray(values));
  }
  return out + "]";
}

std::string EventsJson(const ViewerScene& scene) {
  std::string out = "[";
  for (const ViewerEvent& e : scene.events) {
    if (out.size() > 1) out += ',';
    out += fmt::format(R"({{"t":{:.17g},"element":{},"kind":{}}})", e.time, JsonString(e.element), JsonString(e.kind));
  }
  return out + "]";
}

uint64_t VertexCount(const ViewerScene& scene) {
  uint64_t n = 0;
  for (const ViewerBody& b : scene.bodies) n += b.mesh.vertices.size();
  for (const ViewerDecoration& d : scene.decorations) n += d.mesh.vertices.size();
  return n;
}

}  // namespace

std::string Base64(const void* data, size_t n) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::string out((n + 2) / 3 * 4, '=');
  size_t o = 0, i = 0;
  for (; i + 3 <= n; i += 3) {
    const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8 | bytes[i + 2];
    out[o++] = kDigits[v >> 18];
    out[o++] = kDigits[(v >> 12) & 63];
    out[o++] = kDigits[(v >> 6) & 63];
    out[o++] = kDigits[v & 63];
  }
  if (i < n) {  // one or two bytes left: two or three digits, then padding
    const uint32_t v = uint32_t(bytes[i]) << 16 | (i + 1 < n ? uint32_t(bytes[i + 1]) << 8 : 0);
    out[o++] = kDigits[v >> 18];
    out[o++] = kDigits[(v >> 12) & 63];
    if (i + 1 < n) out[o++] = kDigits[(v >> 6) & 63];
  }
  return out;
}

std::string JsonString(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || c == '<' || c == '>' || c == '&') {
      out += fmt::format("\\u{:04x}", u);
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::vector<size_t> ChooseInstants(size_t n_times, uint64_t per_instant, uint64_t max_values, uint64_t* stride) {
  *stride = 1;
  std::vector<size_t> chosen;
  if (n_times == 0) return chosen;
  const uint64_t max_count = per_instant == 0 ? n_times : max_values / per_instant;
  if (max_count < std::min<uint64_t>(n_times, 2)) return chosen;
  if (n_times > max_count) {
    // count(s) = ⌊(n − 1)/s⌋ + 1, plus the last instant when s does not divide n − 1.
    auto count = [&](uint64_t s) { return (n_times - 1) / s + 1 + ((n_times - 1) % s != 0 ? 1 : 0); };
    uint64_t s = (n_times - 1 + max_count - 2) / (max_count - 1);
    while (count(s) > max_count) ++s;
    *stride = s;
  }
  for (size_t k = 0; k < n_times; k += *stride) chosen.push_back(k);
  if (chosen.back() != n_times - 1) chosen.push_back(n_times - 1);
  return chosen;
}

EncodedScene EncodeScene(const ViewerScene& scene, const PageOptions& options, std::string* error) {
  EncodedScene result;
  *error = CheckScene(scene);
  if (!error->empty()) return result;
  if (const uint64_t n = VertexCount(scene); n > options.max_vertices) {
    *error = fmt::format("the drawings have {} vertices; the limit is {}", n, options.max_vertices);
    return result;
  }
  const uint64_t per_instant = 7 * scene.bodies.size() + scene.signals.size();
  const std::vector<size_t> instants =
      ChooseInstants(scene.poses.times.size(), per_instant, options.max_values, &result.stride);
  if (instants.empty()) {
    *error = fmt::format("{} numbers per instant leave fewer than two instants under the limit of {} numbers",
                         per_instant, options.max_values);
    return result;
  }
  std::vector<double> times;
  times.reserve(instants.size());
  for (size_t k : instants) times.push_back(scene.poses.times[k]);
  const Vec3 up = scene.up_W.normalized();
  result.instants = instants.size();
  result.json = fmt::format(
      R"({{"format":"kanesim-viewer","version":1,"title":{},"up":[{},{},{}],"n_times":{},"stride":{},)"
      R"("times":"{}","bodies":{},"decorations":{},"poses":"{}","signals":{},"events":{}}})",
      JsonString(scene.title), up.x(), up.y(), up.z(), instants.size(), result.stride, EncodeArray(std::move(times)),
      BodiesJson(scene), DecorationsJson(scene), PosesBase64(scene, instants), SignalsJson(scene, instants),
      EventsJson(scene));
  return result;
}

}  // namespace kanesim::viz
