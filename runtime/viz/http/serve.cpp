// The HTTP module (http_module.h): serves fixed routes with cpp-httplib until GET /quit, the
// timeout or SIGINT.
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <memory>
#include <thread>

#include "runtime/viz/http_module.h"

namespace kanesim::viz::http {
namespace {

// Set by the SIGINT handler; the watcher thread stops the server when it sees it. A flag is
// all a signal handler may safely touch.
volatile std::sig_atomic_t g_sigint = 0;
extern "C" void OnSigint(int) { g_sigint = 1; }

// Installs OnSigint for the lifetime of the object and restores the previous handler after.
class SigintScope {
 public:
  explicit SigintScope(bool active) : active_(active) {
    if (!active_) return;
    g_sigint = 0;
    struct sigaction action {};
    action.sa_handler = OnSigint;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_);
  }
  ~SigintScope() {
    if (active_) sigaction(SIGINT, &previous_, nullptr);
  }
  SigintScope(const SigintScope&) = delete;
  SigintScope& operator=(const SigintScope&) = delete;

 private:
  bool active_;
  struct sigaction previous_ {};
};

std::string HostForUrl(const std::string& host) {
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;  // an IPv6 literal
}

// Binds the listening socket: port 0 picks any free one. -1 when it cannot.
int Bind(httplib::Server& server, const ServeRequest& request) {
  // httplib's default sets SO_REUSEPORT, which lets a second server bind a port that one
  // already listens on (the kernel then splits the connections between them); SO_REUSEADDR
  // alone refuses that and still allows a restart while old connections linger.
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  if (request.port == 0) return server.bind_to_any_port(request.host);
  return server.bind_to_port(request.host, request.port) ? request.port : -1;
}

ServeReply Serve(const ServeRequest& request) {
  ServeReply reply;
  httplib::Server server;
  std::atomic<bool> quit_requested{false};
  for (const Route& route : request.routes) {
    auto shared = std::make_shared<const Route>(route);
    // A content provider of known length: httplib compresses in-memory bodies when the
    // browser accepts it, and brotli takes about a second for three.js; on the loopback
    // interface compression gains nothing.
    server.Get(route.path, [shared](const httplib::Request&, httplib::Response& response) {
      response.set_header("Cache-Control", "no-store");
      response.set_content_provider(
          shared->body.size(), shared->content_type.c_str(),
          [shared](size_t offset, size_t length, httplib::DataSink& sink) {
            return sink.write(shared->body.data() + offset, std::min(length, shared->body.size() - offset));
          });
    });
  }
  if (request.enable_quit) {
    server.Get("/quit", [&](const httplib::Request&, httplib::Response& response) {
      response.set_content("stopping\n", "text/plain");
      quit_requested = true;
    });
  }
  const int port = Bind(server, request);
  if (port < 0) {
    reply.error = "cannot listen on " + request.host +
                  (request.port == 0 ? "" : " port " + std::to_string(request.port) + " (in use?)");
    return reply;
  }
  reply.port = port;
  reply.url = "http://" + HostForUrl(request.host) + ":" + std::to_string(port) + "/";

  SigintScope sigint(request.handle_sigint);
  std::atomic<bool> done{false};
  std::string stopped_by = "stop";
  // The watcher: polls the stop conditions (a signal handler cannot call server.stop()), and
  // repeats stop() until the listener has returned (a stop before it started is a no-op).
  std::thread watcher([&] {
    const auto start = std::chrono::steady_clock::now();
    const char* reason = nullptr;
    while (!done) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (reason == nullptr) {
        if (g_sigint && request.handle_sigint) reason = "sigint";
        else if (quit_requested) reason = "quit";
        else if (request.timeout_s > 0 && elapsed >= request.timeout_s) reason = "timeout";
        if (reason != nullptr) stopped_by = reason;
      }
      if (reason != nullptr) server.stop();
    }
  });
  if (request.on_ready) request.on_ready(reply.url);
  server.listen_after_bind();
  done = true;
  watcher.join();
  reply.stopped_by = stopped_by;
  reply.ok = true;
  return reply;
}

const ModuleApi kApi{kAbiVersion, &Serve};

}  // namespace
}  // namespace kanesim::viz::http

extern "C" __attribute__((visibility("default"))) const kanesim::viz::http::ModuleApi* kanesim_viz_http_api() {
  return &kanesim::viz::http::kApi;
}
