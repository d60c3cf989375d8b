// The boundary between kanesim_viz (static, no HTTP library) and the HTTP module
// libkanesim_viz_http.so (cpp-httplib), which ServeViewer loads with dlopen the first time a
// page is served. cpp-httplib as Debian builds it brings libssl, libcrypto, zlib and brotli;
// a program that never serves a page never maps them (docs/visualization.md, "Viewer").
//
// The module knows nothing of scenes: it serves fixed bodies at fixed paths. Both sides are
// built together by this project's CMake with one compiler and standard library, so the
// structs cross the boundary as C++ types; kAbiVersion guards against a stale module.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace kanesim::viz::http {

inline constexpr int kAbiVersion = 1;

struct Route {
  std::string path;          // e.g. "/scene.json" (GET only, exact match)
  std::string body;
  std::string content_type;  // e.g. "application/json"
};

struct ServeRequest {
  std::string host;  // address to listen on
  int port = 0;      // 0: any free port
  std::vector<Route> routes;
  bool enable_quit = false;   // GET /quit stops the server
  double timeout_s = 0;       // > 0: stop after this many seconds
  bool handle_sigint = true;  // SIGINT stops the server; the previous handler is restored after
  std::function<void(const std::string& url)> on_ready;  // called once listening
};

struct ServeReply {
  bool ok = false;
  std::string error;       // why it could not listen
  int port = 0;
  std::string url;         // http://host:port/
  std::string stopped_by;  // "sigint", "quit", "timeout" or "stop"
};

struct ModuleApi {
  int abi_version;
  ServeReply (*serve)(const ServeRequest&);
};

// The entry point the module exports (extern "C" so that dlsym finds it by this name).
inline constexpr const char* kEntryPoint = "kanesim_viz_http_api";
using EntryFunction = const ModuleApi* (*)();

// The module, loaded once per process (thread-safe). Null with *error set when it cannot be
// found or is stale. Where: $KANESIM_VIZ_HTTP_MODULE when set (and nowhere else), otherwise
// the directory of the running executable, then the build tree's copy.
const ModuleApi* Module(std::string* error);

}  // namespace kanesim::viz::http
