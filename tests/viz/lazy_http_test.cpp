// The HTTP module is loaded only to serve (viz/http_module.h).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "viz/server.h"
#include "tests/viz/circling_scene.h"

namespace kanesim::viz {
namespace {

bool HttpLibraryMapped() {
  std::ifstream maps("/proc/self/maps");
  std::stringstream text;
  text << maps.rdbuf();
  return text.str().find("libcpp-httplib") != std::string::npos;
}

// Wrong if linking kanesim_viz mapped cpp-httplib (and libssl, libcrypto) at start: every run
// of the program would pay for it. ctest runs each test in a process of its own.
TEST(LazyHttp, MappedOnlyWhenAPageIsServed) {
  if (std::getenv("KANESIM_VIZ_HTTP_MODULE")) GTEST_SKIP() << "the module path is overridden";
  EXPECT_FALSE(HttpLibraryMapped());
  ServeOptions options;
  options.timeout_s = 0.05;
  options.handle_sigint = false;
  const ServeResult r = ServeViewer(testing::CirclingScene('z', 3), options);
  EXPECT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stopped_by, "timeout");
  EXPECT_TRUE(HttpLibraryMapped());
}

// Wrong if a missing module crashed or hung instead of saying what was tried (ctest runs this
// with KANESIM_VIZ_HTTP_MODULE pointing at a file that does not exist).
TEST(LazyHttp, ModuleMissing) {
  const char* path = std::getenv("KANESIM_VIZ_HTTP_MODULE");
  if (!path) GTEST_SKIP() << "run by ctest as viz.http_module_missing";
  ServeOptions options;
  options.timeout_s = 5;
  const ServeResult r = ServeViewer(testing::CirclingScene('z', 3), options);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, std::string("cannot load the viewer's HTTP server library libkanesim_viz_http.so; tried: ") +
                         path + " (absent)");
}

}  // namespace
}  // namespace kanesim::viz
