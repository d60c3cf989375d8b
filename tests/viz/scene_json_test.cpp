// The scene as the page reads it (viz/scene_json.h): base64 against RFC 4648's vectors, JSON
// escaping, the choice of instants under the size limit, the arrays decoded back (by a decoder
// written here, not the encoder's) equal to the scene's numbers, and CheckScene's errors.
#include "viz/scene_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "geometry/primitives.h"
#include "tests/viz/circling_scene.h"

namespace kanesim::viz {
namespace {

// An independent base64 decoder (RFC 4648 §4).
std::vector<unsigned char> Decode(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::vector<unsigned char> out;
  uint32_t bits = 0;
  int n = 0;
  for (char c : text) {
    if (c == '=') break;
    const int v = value(c);
    EXPECT_GE(v, 0) << "not a base64 digit: " << c;
    bits = bits << 6 | uint32_t(v);
    if ((n += 6) >= 8) {
      n -= 8;
      out.push_back(static_cast<unsigned char>(bits >> n));
    }
  }
  return out;
}

template <typename T>
std::vector<T> DecodeArray(const std::string& text) {
  const std::vector<unsigned char> bytes = Decode(text);
  EXPECT_EQ(bytes.size() % sizeof(T), 0u);
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));  // the test host is little-endian
  return out;
}

// The base64 string of the JSON field `key` (the first "key":"..." after `from`).
std::string Field(const std::string& json, const std::string& key, size_t from = 0) {
  const std::string open = "\"" + key + "\":\"";
  const size_t at = json.find(open, from);
  if (at == std::string::npos) return "";
  const size_t start = at + open.size();
  return json.substr(start, json.find('"', start) - start);
}

std::string Encode(const ViewerScene& scene, const PageOptions& options = {}, EncodedScene* out = nullptr) {
  std::string error;
  EncodedScene encoded = EncodeScene(scene, options, &error);
  if (out != nullptr) *out = encoded;
  return error.empty() ? encoded.json : "error: " + error;
}

// Wrong if the page decodes different bytes than were written.
TEST(Base64, Rfc4648Vectors) {
  const char* plain[] = {"", "f", "fo", "foo", "foob", "fooba", "foobar"};
  const char* coded[] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
  for (int i = 0; i < 7; ++i) EXPECT_EQ(Base64(plain[i], std::strlen(plain[i])), coded[i]);
  const unsigned char all[] = {0x00, 0xff, 0xfe, 0x80, 0x7f, 0x3e, 0x3f};
  EXPECT_EQ(Base64(all, sizeof all), "AP/+gH8+Pw==");
}

// Wrong if a body name could end the <script> element holding the scene, or break the JSON.
TEST(JsonString, EscapesQuotesControlCharactersAndTags) {
  EXPECT_EQ(JsonString("a\"b\\c</script>&\n\x01é"), "\"a\\\"b\\\\c\\u003c/script\\u003e\\u0026\\u000a\\u0001é\"");
}

// Wrong if a long run overflows the stated limit, drops its last instant, or is decimated
// more than it needs to be.
TEST(ChooseInstants, SmallestStrideThatFitsKeepsTheLast) {
  uint64_t stride = 0;
  EXPECT_EQ(ChooseInstants(101, 7, 707, &stride).size(), 101u);
  EXPECT_EQ(stride, 1u);
  for (size_t n : {2, 3, 10, 101, 1000, 12345})
    for (uint64_t max_count : {2, 3, 7, 50, 99, 100, 1000}) {
      const std::vector<size_t> k = ChooseInstants(n, 5, 5 * max_count, &stride);
      ASSERT_FALSE(k.empty()) << n << " " << max_count;
      EXPECT_LE(k.size(), std::min<uint64_t>(n, max_count)) << n << " " << max_count;
      EXPECT_EQ(k.front(), 0u);
      EXPECT_EQ(k.back(), n - 1);
      for (size_t i = 1; i + 1 < k.size(); ++i) EXPECT_EQ(k[i] - k[i - 1], stride);
      if (stride > 1) {  // one less would not fit
        const uint64_t s = stride - 1;
        const uint64_t count = (n - 1) / s + 1 + ((n - 1) % s != 0 ? 1 : 0);
        EXPECT_GT(count, max_count) << n << " " << max_count;
      }
    }
  EXPECT_TRUE(ChooseInstants(1, 8, 7, &stride).empty());
  EXPECT_TRUE(ChooseInstants(5, 8, 15, &stride).empty());  // not even two instants
  EXPECT_EQ(ChooseInstants(1, 8, 8, &stride).size(), 1u);
}

// Wrong if the page receives other poses, times or signal values than the scene holds
// (beyond rounding to single precision), or in another order (e.g. q as x, y, z, w).
TEST(EncodeScene, ArraysDecodeToTheScene) {
  const ViewerScene scene = testing::CirclingScene('z', 37);
  const std::string json = Encode(scene);
  ASSERT_EQ(json.rfind("error", 0), std::string::npos) << json;
  const std::vector<double> times = DecodeArray<double>(Field(json, "times"));
  ASSERT_EQ(times, scene.poses.times);
  const std::vector<float> poses = DecodeArray<float>(Field(json, "poses"));
  ASSERT_EQ(poses.size(), 37u * 2 * 7);
  for (size_t i = 0; i < 37 * 2; ++i) {
    const Vec3& p = scene.poses.p_WB[i];
    const Eigen::Quaterniond& q = scene.poses.q_WB[i];
    const double expected[7] = {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()};
    for (int j = 0; j < 7; ++j) EXPECT_EQ(poses[7 * i + j], static_cast<float>(expected[j])) << i << " " << j;
  }
  size_t at = json.find("\"signals\":");
  for (const ViewerSignal& s : scene.signals) {
    at = json.find("\"name\":\"" + s.name + "\"", at);
    ASSERT_NE(at, std::string::npos) << s.name;
    const std::vector<float> values = DecodeArray<float>(Field(json, "values", at));
    ASSERT_EQ(values.size(), s.values.size());
    for (size_t k = 0; k < values.size(); ++k) EXPECT_EQ(values[k], static_cast<float>(s.values[k]));
  }
  EXPECT_NE(json.find("\"up\":[0,0,1]"), std::string::npos);
  EXPECT_NE(json.find("\"n_times\":37,\"stride\":1"), std::string::npos);
}

// Wrong if a mesh's triangles reach the page other than given, with 16- or 32-bit indices.
TEST(EncodeScene, MeshesDecodeToTheirVerticesAndTriangles) {
  ViewerScene scene = testing::CirclingScene('y', 3);
  scene.decorations.clear();
  // 70,000 vertices: beyond 16-bit indices.
  VisualMesh big;
  for (uint32_t i = 0; i < 70000; ++i) {
    big.vertices.push_back(Vec3(i * 1e-5, 1, 2));
    big.normals.push_back(Vec3::UnitZ());
  }
  for (uint32_t i = 0; i + 2 < 70000; i += 3) big.triangles.push_back({i, i + 1, 69999 - i});
  scene.bodies[1].mesh = big;
  const std::string json = Encode(scene);
  for (int b = 0; b < 2; ++b) {
    const VisualMesh& m = scene.bodies[b].mesh;
    const size_t at = json.find("\"name\":\"" + scene.bodies[b].name + "\"");
    ASSERT_NE(at, std::string::npos);
    const std::vector<float> positions = DecodeArray<float>(Field(json, "positions", at));
    ASSERT_EQ(positions.size(), 3 * m.vertices.size());
    for (size_t i = 0; i < m.vertices.size(); ++i)
      for (int j = 0; j < 3; ++j) ASSERT_EQ(positions[3 * i + j], static_cast<float>(m.vertices[i][j]));
    std::vector<uint32_t> indices;
    if (b == 0) {
      EXPECT_NE(json.find("\"index_bytes\":2", at), std::string::npos);
      for (uint16_t i : DecodeArray<uint16_t>(Field(json, "indices", at))) indices.push_back(i);
    } else {
      EXPECT_NE(json.find("\"index_bytes\":4", at), std::string::npos);
      indices = DecodeArray<uint32_t>(Field(json, "indices", at));
    }
    ASSERT_EQ(indices.size(), 3 * m.triangles.size());
    for (size_t t = 0; t < m.triangles.size(); ++t)
      for (int j = 0; j < 3; ++j) ASSERT_EQ(indices[3 * t + j], m.triangles[t][j]);
  }
}

// Wrong if a long run is written whole past the limit, or the written instants are not the
// ones reported.
TEST(EncodeScene, DecimatesToTheLimit) {
  const ViewerScene scene = testing::CirclingScene('z', 1001);
  PageOptions options;
  options.max_values = 100 * (2 * 7 + 5);  // 100 instants of 2 bodies and 5 signals
  EncodedScene encoded;
  const std::string json = Encode(scene, options, &encoded);
  EXPECT_EQ(encoded.stride, 11u);  // ⌊1000/11⌋ + 1 + 1 = 92 <= 100 < ⌊1000/10⌋ + 1 = 101
  EXPECT_EQ(encoded.instants, 92u);
  const std::vector<double> times = DecodeArray<double>(Field(json, "times"));
  ASSERT_EQ(times.size(), 92u);
  for (size_t i = 0; i + 1 < times.size(); ++i) EXPECT_EQ(times[i], scene.poses.times[11 * i]);
  EXPECT_EQ(times.back(), scene.poses.times.back());
  EXPECT_EQ(DecodeArray<float>(Field(json, "poses")).size(), 92u * 14);
  options.max_values = 2 * 19 - 1;
  EXPECT_NE(Encode(scene, options).find("fewer than two instants"), std::string::npos);
  options = {};
  options.max_vertices = 100;
  EXPECT_NE(Encode(scene, options).find("vertices; the limit is 100"), std::string::npos);
}

// Wrong if bad input reaches the page (where it would draw garbage) instead of a message.
TEST(CheckScene, NamesEveryProblem) {
  const ViewerScene good = testing::CirclingScene('z', 5);
  EXPECT_EQ(CheckScene(good), "");
  struct Case {
    const char* expected;
    void (*mutate)(ViewerScene&);
  };
  const Case cases[] = {
      {"up direction", [](ViewerScene& s) { s.up_W = Vec3::Zero(); }},
      {"empty name", [](ViewerScene& s) { s.bodies[1].name = ""; }},
      {"two bodies are named 'orbiter'", [](ViewerScene& s) { s.bodies[1].name = "orbiter"; }},
      {"normals for", [](ViewerScene& s) { s.bodies[0].mesh.normals.pop_back(); }},
      {"refers to vertex 999", [](ViewerScene& s) { s.bodies[0].mesh.triangles[0][1] = 999; }},
      {"non-finite position", [](ViewerScene& s) { s.bodies[0].mesh.vertices[2].y() = NAN; }},
      {"colour", [](ViewerScene& s) { s.bodies[1].rgba[3] = 1.5f; }},
      {"carried by body 2", [](ViewerScene& s) { s.decorations[1].body = 2; }},
      {"no instants", [](ViewerScene& s) { s.poses = {}; }},
      {"need 10 each", [](ViewerScene& s) { s.poses.q_WB.pop_back(); }},
      {"must not decrease", [](ViewerScene& s) { s.poses.times[3] = 0; }},
      {"not finite", [](ViewerScene& s) { s.poses.times[4] = INFINITY; }},
      {"'spinner' at t = 0.05: position not finite", [](ViewerScene& s) { s.poses.p_WB[3].z() = NAN; }},
      {"not a unit quaternion (norm 1.1", [](ViewerScene& s) { s.poses.q_WB[2].coeffs() *= 1.1; }},
      {"two signals are named 'energy'", [](ViewerScene& s) { s.signals[0].name = "energy"; }},
      {"signal 'orbiter.y' has 4 values for 5", [](ViewerScene& s) { s.signals[1].values.pop_back(); }},
  };
  for (const Case& c : cases) {
    ViewerScene s = good;
    c.mutate(s);
    const std::string error = CheckScene(s);
    EXPECT_NE(error.find(c.expected), std::string::npos) << "expected '" << c.expected << "' in '" << error << "'";
  }
  ViewerScene nearly = good;  // off unit length within the tolerance: accepted, written normalised
  nearly.poses.q_WB[0].coeffs() *= 1 + 5e-5;
  EXPECT_EQ(CheckScene(nearly), "");
  ViewerScene gaps = good;  // NaN signal values are gaps in the plot, not errors
  gaps.signals[0].values[2] = NAN;
  EXPECT_EQ(CheckScene(gaps), "");
}

}  // namespace
}  // namespace kanesim::viz
