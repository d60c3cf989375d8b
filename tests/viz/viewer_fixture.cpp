// The pages the browser tests open (browser_test.py):
//   viewer_fixture html OUT.html UP [N_TIMES N_BODIES]
//                                       writes the offline page of CirclingScene(UP, …)
//   viewer_fixture edge OUT.html        writes EdgeScene(): one instant, a body without a drawing,
//                                       a signal of NaN only, names with markup, no decorations
//   viewer_fixture serve UP             serves it on 127.0.0.1 (any free port), prints the URL
//                                       on the first line of stdout, stops on GET /quit or
//                                       after 120 s
// UP is z or y. Exit 0 on success, 1 with a message otherwise.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "viz/server.h"
#include "viz/viewer.h"
#include "tests/viz/circling_scene.h"

using namespace kanesim::viz;

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "edge") == 0) {
    const PageResult r = WriteViewerHtml(testing::EdgeScene(), argv[2]);
    if (!r.ok) std::fprintf(stderr, "%s\n", r.error.c_str());
    return r.ok ? 0 : 1;
  }
  const bool html = (argc == 4 || argc == 6) && std::strcmp(argv[1], "html") == 0;
  const bool serve = argc == 3 && std::strcmp(argv[1], "serve") == 0;
  const char* up = argv[html ? 3 : argc - 1];
  if ((!html && !serve) || (std::strcmp(up, "z") != 0 && std::strcmp(up, "y") != 0)) {
    std::fprintf(stderr, "usage: %s html OUT.html z|y [N_TIMES N_BODIES] | edge OUT.html | serve z|y\n", argv[0]);
    return 1;
  }
  const ViewerScene scene =
      argc == 6 ? testing::CirclingScene(up[0], std::atoi(argv[4]), std::atoi(argv[5])) : testing::CirclingScene(up[0]);
  if (html) {
    const PageResult r = WriteViewerHtml(scene, argv[2]);
    if (!r.ok) std::fprintf(stderr, "%s\n", r.error.c_str());
    return r.ok ? 0 : 1;
  }
  ServeOptions options;
  options.enable_quit = true;
  options.timeout_s = 120;
  options.on_ready = [](const std::string& url) {
    std::printf("%s\n", url.c_str());
    std::fflush(stdout);
  };
  const ServeResult r = ServeViewer(scene, options);
  if (!r.ok) std::fprintf(stderr, "%s\n", r.error.c_str());
  else std::fprintf(stderr, "stopped by %s\n", r.stopped_by.c_str());
  return r.ok && r.stopped_by == "quit" ? 0 : 1;
}
