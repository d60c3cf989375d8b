// The HTTP module (http_module.h): serves fixed routes with cpp-httplib until GET /quit, the
// timeout or SIGINT.
//
// Guards (docs/visualization.md, "Serving"):
// - slow or idle clients cannot starve the others: a read that waits more than
//   kReadTimeout, an idle kept-alive connection after kKeepAlive, and a thread per
//   connection up to kMaxThreads (httplib's own pool has max(8, cores - 1) threads, so
//   eight connections sending one header line a second held every thread);
// - only requests for this server by its loopback name are answered (Host check): a web page
//   elsewhere whose name is rebound to 127.0.0.1 (DNS rebinding) is refused with 403;
// - a Range that no byte of the file satisfies is answered 416 (httplib would answer 206
//   and read past the body), an end beyond the file is clipped (RFC 9110, sec. 14).
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "viz/http_module.h"

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

constexpr time_t kReadTimeout = 2;    // s: a loopback client sends its request at once
constexpr time_t kWriteTimeout = 5;   // s
constexpr time_t kKeepAlive = 2;      // s an idle kept-alive connection is held
constexpr size_t kKeepAliveMax = 100; // requests per connection (httplib's default: 5)
constexpr size_t kMaxThreads = 128;   // connections served at once; more wait for a thread
constexpr size_t kMaxPayload = 64 * 1024;  // bytes of a request body (only GET is served)
constexpr int kListenBacklog = 128;        // connections waiting to be accepted

// A thread per connection, up to max_threads; a connection beyond waits in the queue for
// the first free one. Threads stay until shutdown (at most max_threads of them).
class GrowingPool final : public httplib::TaskQueue {
 public:
  explicit GrowingPool(size_t max_threads) : max_threads_(max_threads) {}
  ~GrowingPool() override = default;

  void enqueue(std::function<void()> fn) override {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(fn));
    // More jobs waiting than threads waiting for jobs: one more thread, if allowed.
    if (jobs_.size() > waiting_ && threads_.size() < max_threads_) threads_.emplace_back([this] { Work(); });
    cond_.notify_one();
  }
  void shutdown() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      shutdown_ = true;
    }
    cond_.notify_all();
    for (std::thread& t : threads_) t.join();  // (no enqueue after shutdown: the listener has returned)
  }

 private:
  void Work() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      ++waiting_;
      cond_.wait(lock, [this] { return !jobs_.empty() || shutdown_; });
      --waiting_;
      if (jobs_.empty()) return;  // shut down, nothing left
      std::function<void()> fn = std::move(jobs_.front());
      jobs_.pop_front();
      lock.unlock();
      fn();
      lock.lock();
    }
  }

  const size_t max_threads_;
  std::mutex mutex_;
  std::condition_variable cond_;
  std::deque<std::function<void()>> jobs_;
  std::vector<std::thread> threads_;
  size_t waiting_ = 0;  // threads inside cond_.wait
  bool shutdown_ = false;
};

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The Host values this server answers: its loopback names with the port.
std::vector<std::string> AllowedHosts(const std::string& listen_host, int port) {
  const std::string p = ":" + std::to_string(port);
  // The printed URL's own host first (the message names it).
  return {Lower(listen_host.find(':') != std::string::npos ? "[" + listen_host + "]" : listen_host) + p,
          "127.0.0.1" + p, "localhost" + p, "[::1]" + p};
}

// A refusal: status and a short text. Without a body when the request has a Range (httplib
// would cut the text by the range).
void Refuse(const httplib::Request& request, httplib::Response& response, int status, const std::string& text) {
  response.status = status;
  if (request.ranges.empty()) response.set_content(text + "\n", "text/plain; charset=utf-8");
}

// Checks the requested ranges against a body of `size` bytes: false when one is
// unsatisfiable (416) or there are several (each would be served whole: refused). Ends past
// the body are clipped to its last byte, so that httplib's Content-Range and length agree.
bool ClipRanges(const httplib::Request& request, size_t size) {
  if (request.ranges.size() > 1) return false;
  // httplib hands handlers a const request that it owns as a mutable local; the clip must
  // change what it serves next, so the range is rewritten in place.
  auto& ranges = const_cast<httplib::Request&>(request).ranges;
  const auto n = static_cast<ssize_t>(size);
  for (auto& [first, last] : ranges) {
    if (first < 0) {  // a suffix "-N": the last N bytes
      if (last <= 0 || n == 0) return false;
      last = std::min(last, n);
      continue;
    }
    if (first >= n || (last >= 0 && last < first)) return false;
    if (last >= n) last = n - 1;
  }
  return true;
}

std::string HostForUrl(const std::string& host) {
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;  // an IPv6 literal
}

// Binds the listening socket: port 0 picks any free one. -1 when it cannot.
int Bind(httplib::Server& server, const ServeRequest& request) {
  // httplib's default sets SO_REUSEPORT, which lets a second server bind a port that one
  // already listens on (the kernel then splits the connections between them); SO_REUSEADDR
  // alone refuses that and still allows a restart while old connections linger.
  auto listen_fd = std::make_shared<socket_t>(INVALID_SOCKET);
  server.set_socket_options([listen_fd](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
    *listen_fd = sock;
  });
  const int port = request.port == 0 ? server.bind_to_any_port(request.host)
                                     : (server.bind_to_port(request.host, request.port) ? request.port : -1);
  // Debian's libcpp-httplib listens with a backlog of 5: a burst of connections beyond it
  // waits a second for the client's SYN to be sent again. A second listen(2) on the bound
  // socket raises the backlog (Linux).
  if (port >= 0 && *listen_fd != INVALID_SOCKET) ::listen(*listen_fd, kListenBacklog);
  return port;
}

ServeReply Serve(const ServeRequest& request) {
  ServeReply reply;
  httplib::Server server;
  server.new_task_queue = [] { return new GrowingPool(kMaxThreads); };
  server.set_read_timeout(kReadTimeout, 0);
  server.set_write_timeout(kWriteTimeout, 0);
  server.set_keep_alive_timeout(kKeepAlive);
  server.set_keep_alive_max_count(kKeepAliveMax);
  server.set_payload_max_length(kMaxPayload);
  std::atomic<bool> quit_requested{false};
  std::map<std::string, size_t> sizes;  // route -> body bytes (for the ranges)
  for (const Route& route : request.routes) sizes[route.path] = route.body.size();
  std::atomic<int> bound_port{0};       // set once bound, before any request is read
  server.set_pre_routing_handler([&, sizes](const httplib::Request& req, httplib::Response& res) {
    const auto allowed = AllowedHosts(request.host, bound_port);
    if (std::find(allowed.begin(), allowed.end(), Lower(req.get_header_value("Host"))) == allowed.end()) {
      Refuse(req, res, 403,
             "kanesim view answers only requests for http://" + allowed.front() +
                 "/ (this request names another host, as a page that rebinds its name to this machine would)");
      return httplib::Server::HandlerResponse::Handled;
    }
    const auto route = sizes.find(req.path);
    if (route != sizes.end() && !req.ranges.empty() && !ClipRanges(req, route->second)) {
      res.status = 416;
      res.set_header("Content-Range", "bytes */" + std::to_string(route->second));
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
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
            if (offset >= shared->body.size()) return false;  // (ranges are clipped first: never)
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
  bound_port = port;
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
