// Serving the viewer page over HTTP (cpp-httplib, Debian's libcpp-httplib-dev). The server
// lives in the module libkanesim_viz_http.so, loaded with dlopen on the first call
// (http_module.h): a program that links kanesim_viz but serves nothing does not map
// libcpp-httplib and the TLS and compression libraries it brings.
//
// Routes (GET; nothing else is served, nothing is listed):
//   /                        the page (its own script and style inline, as in the offline page)
//   /scene.json              the scene (the same JSON the offline page inlines)
//   /lib/three.min.js, /lib/OrbitControls.js, /lib/dygraph.min.js, /lib/dygraph.min.css
//                            the libraries, read from PageOptions::js_root when the server starts
//   /quit                    stops the server, only when ServeOptions::enable_quit (tests)
#pragma once

#include <functional>
#include <string>

#include "viz/viewer.h"

namespace kanesim::viz {

struct ServeOptions {
  std::string host = "127.0.0.1";  // the address to listen on (a loopback address keeps the page local)
  int port = 0;                    // 0: any free port (the URL given to on_ready says which)
  // Called once the socket listens, before requests are answered: e.g. print the URL.
  std::function<void(const std::string& url)> on_ready;
  double timeout_s = 0;      // > 0: stop after this many seconds (tests); 0: run until stopped
  bool enable_quit = false;  // GET /quit stops the server (tests)
  bool handle_sigint = true; // SIGINT (Ctrl-C) stops the server; the previous handler is restored after
  PageOptions page;          // libraries and limits, as for the offline page
};

struct ServeResult {
  bool ok = false;
  std::string error;     // why the server could not start: bad scene, missing library (named with its
                         // Debian package), the HTTP module not found, the port in use
  int port = 0;          // the port it listened on
  std::string url;       // http://host:port/
  std::string stopped_by;  // "sigint", "quit", "timeout" or "stop" (a failure of the listener)
  PageResult page;       // stride, instants, and the scene JSON's size in bytes
};

// Serves the page until SIGINT, GET /quit (enable_quit) or the timeout. Blocks; returns when
// stopped. The scene is encoded once, before listening.
ServeResult ServeViewer(const ViewerScene& scene, const ServeOptions& options = {});

}  // namespace kanesim::viz
