// The viewer page: the 3-D animation of a ViewerScene beside time plots of its signals
// (docs/visualization.md, "Viewer").
//
// The page is the project's own HTML, CSS and JavaScript (viz/page/, embedded in the
// binary at build time) with three third-party libraries read at run time from Debian's
// installed files: three.js r111 and its OrbitControls (libjs-three) and dygraphs 2.2
// (libjs-dygraphs). Nothing is fetched from the internet.
//
// Two ways to open it:
//   WriteViewerHtml  one self-contained .html file (libraries and data inlined) that opens
//                    offline by double-click;
//   ServeViewer      (viz/server.h) an HTTP server on 127.0.0.1 that serves the same page.
#pragma once

#include <cstdint>
#include <string>

#include "viz/viewer_scene.h"

namespace kanesim::viz {

// Where Debian installs the libraries (libjs-three, libjs-dygraphs).
inline constexpr const char* kDebianJavaScriptRoot = "/usr/share/javascript";

struct PageOptions {
  std::string js_root = kDebianJavaScriptRoot;  // the directory holding three/ and dygraphs/
  // Stated limit: the numbers of the motion and signals written into the page,
  // n_times · (7 n_bodies + n_signals), at most this many (4 bytes each, base64: 5.3 bytes in
  // the file). Above it every stride-th instant is written, and the last; stride the smallest
  // that fits. 8,000,000 is a page of about 43 MB.
  uint64_t max_values = 8'000'000;
  // Stated limit: the vertices of all drawings together (meshes are never decimated).
  uint64_t max_vertices = 4'000'000;
};

struct PageResult {
  bool ok = false;
  std::string error;            // why not, when !ok: bad scene, a missing library (named with
                                // its Debian package), a limit, or the file could not be written
  uint64_t stride = 1;          // decimation: every stride-th instant (and the last) was written
  uint64_t instants = 0;        // instants written
  uint64_t bytes = 0;           // size of the page (WriteViewerHtml) or of the scene JSON (served)
};

// Writes the self-contained page to `path` (through a temporary file beside it, renamed at the
// end, so a failure leaves no half-written page).
PageResult WriteViewerHtml(const ViewerScene& scene, const std::string& path, const PageOptions& options = {});

}  // namespace kanesim::viz
