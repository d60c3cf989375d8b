// ServeViewer (viz/server.h): the routes and nothing else, the URL given to on_ready, and the
// three ways it stops (GET /quit, the timeout, SIGINT, with the previous handler restored).
#include "viz/server.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <csignal>
#include <fstream>
#include <future>
#include <regex>
#include <sstream>
#include <thread>

#include "viz/scene_json.h"
#include "tests/viz/circling_scene.h"

namespace kanesim::viz {
namespace {

std::string Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs ServeViewer on a thread; url() waits until it listens.
class Running {
 public:
  explicit Running(ServeOptions options, const ViewerScene& scene = testing::CirclingScene('z', 21)) {
    options.on_ready = [this](const std::string& url) { ready_.set_value(url); };
    done_ = std::async(std::launch::async, [options, scene] { return ServeViewer(scene, options); });
  }
  std::string url() {
    auto f = ready_.get_future();
    return f.wait_for(std::chrono::seconds(20)) == std::future_status::ready ? f.get() : "";
  }
  ServeResult result() { return done_.get(); }

 private:
  std::promise<std::string> ready_;
  std::future<ServeResult> done_;
};

// Wrong if the page, the scene or a library were served other than written, or anything else
// (a path outside the routes, e.g. into /usr/share/javascript) were served.
TEST(ServeViewer, ServesTheRoutesAndStopsOnQuit) {
  ServeOptions options;
  options.enable_quit = true;
  options.timeout_s = 60;
  Running server(options);
  const std::string url = server.url();
  std::smatch m;
  ASSERT_TRUE(std::regex_match(url, m, std::regex(R"(http://127\.0\.0\.1:(\d+)/)"))) << url;
  httplib::Client client("127.0.0.1", std::stoi(m[1]));
  auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("data-src=\"scene.json\""), std::string::npos);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  auto scene = client.Get("/scene.json");
  ASSERT_TRUE(scene);
  std::string error;
  EXPECT_EQ(scene->body, EncodeScene(testing::CirclingScene('z', 21), {}, &error).json);
  auto three = client.Get("/lib/three.min.js");
  ASSERT_TRUE(three);
  EXPECT_EQ(three->body, Read("/usr/share/javascript/three/build/three.min.js"));
  EXPECT_EQ(three->get_header_value("Content-Type"), "text/javascript; charset=utf-8");
  // Not compressed on the fly even when the browser accepts it (brotli takes ~1 s for three.js).
  auto accepted = client.Get("/lib/three.min.js", {{"Accept-Encoding", "br, gzip, deflate"}});
  ASSERT_TRUE(accepted);
  EXPECT_EQ(accepted->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(accepted->get_header_value("Content-Length"), std::to_string(three->body.size()));
  for (const char* path : {"/lib/", "/lib/three/build/three.min.js", "/lib/../three/three.js", "/etc/passwd",
                           "/scene.json/x"}) {
    auto r = client.Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
  }
  auto post = client.Post("/quit", "", "text/plain");
  ASSERT_TRUE(post);
  EXPECT_NE(post->status, 200);  // only GET
  auto quit = client.Get("/quit");
  ASSERT_TRUE(quit);
  EXPECT_EQ(quit->status, 200);
  const ServeResult r = server.result();
  EXPECT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stopped_by, "quit");
  EXPECT_EQ(r.url, url);
  EXPECT_EQ(r.page.bytes, scene->body.size());
}

// Wrong if a test server could outlive its test, or /quit worked without being enabled.
TEST(ServeViewer, StopsAtTheTimeoutAndQuitIsOffByDefault) {
  ServeOptions options;
  options.timeout_s = 0.5;
  Running server(options);
  const std::string url = server.url();
  ASSERT_FALSE(url.empty());
  httplib::Client client(url.substr(0, url.size() - 1));
  auto quit = client.Get("/quit");
  ASSERT_TRUE(quit);
  EXPECT_EQ(quit->status, 404);
  const ServeResult r = server.result();
  EXPECT_EQ(r.stopped_by, "timeout");
}

// Wrong if Ctrl-C killed the program instead of stopping the server, or the program's own
// SIGINT handler were lost afterwards.
TEST(ServeViewer, SigintStopsAndRestoresTheHandler) {
  static volatile std::sig_atomic_t own = 0;
  struct sigaction mine {}, before {};
  mine.sa_handler = [](int) { own = 1; };
  sigemptyset(&mine.sa_mask);
  sigaction(SIGINT, &mine, &before);
  {
    ServeOptions options;
    options.timeout_s = 30;
    Running server(options);
    ASSERT_FALSE(server.url().empty());
    std::raise(SIGINT);
    const ServeResult r = server.result();
    EXPECT_EQ(r.stopped_by, "sigint");
  }
  EXPECT_EQ(own, 0);
  std::raise(SIGINT);
  EXPECT_EQ(own, 1);
  sigaction(SIGINT, &before, nullptr);
}

// Wrong if a port in use (by a server with httplib's default SO_REUSEPORT, which would share it), a bad scene or a missing library started a server that shows nothing.
TEST(ServeViewer, FailsBeforeListening) {
  httplib::Server other;
  const int port = other.bind_to_any_port("127.0.0.1");
  ServeOptions options;
  options.port = port;
  options.handle_sigint = false;
  options.timeout_s = 5;  // were it to start after all
  ServeResult r = ServeViewer(testing::CirclingScene('z', 3), options);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("cannot listen on 127.0.0.1 port " + std::to_string(port)), std::string::npos) << r.error;
  options.port = 0;
  options.page.js_root = "/nonexistent";
  r = ServeViewer(testing::CirclingScene('z', 3), options);
  EXPECT_NE(r.error.find("libjs-three"), std::string::npos) << r.error;
  r = ServeViewer(ViewerScene{}, options);
  EXPECT_EQ(r.error, "no instants to show");
}

}  // namespace
}  // namespace kanesim::viz
