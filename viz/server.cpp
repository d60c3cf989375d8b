#include "viz/server.h"

#include <cmath>
#include <string>

#include "viz/http_module.h"
#include "viz/page.h"
#include "viz/scene_json.h"

namespace kanesim::viz {

ServeResult ServeViewer(const ViewerScene& scene, const ServeOptions& options) {
  ServeResult result;
  // A NaN or negative timeout would never be reached: the server would run for ever.
  if (!std::isfinite(options.timeout_s) || options.timeout_s < 0) {
    result.error = "the timeout must be a finite number of seconds >= 0 (0: until stopped), not " +
                   std::to_string(options.timeout_s);
    return result;
  }
  EncodedScene encoded = EncodeScene(scene, options.page, &result.error);
  if (!result.error.empty()) return result;
  const std::vector<LibraryFile> libraries = ReadLibraries(options.page.js_root, &result.error);
  if (!result.error.empty()) return result;
  const http::ModuleApi* module = http::Module(&result.error);
  if (module == nullptr) return result;
  result.page.stride = encoded.stride;
  result.page.instants = encoded.instants;
  result.page.bytes = encoded.json.size();

  http::ServeRequest request;
  request.host = options.host;
  request.port = options.port;
  request.enable_quit = options.enable_quit;
  request.timeout_s = options.timeout_s;
  request.handle_sigint = options.handle_sigint;
  request.on_ready = options.on_ready;
  request.routes.push_back(
      {"/", RenderPage(PageMode::kServed, scene.title, libraries, ""), "text/html; charset=utf-8"});
  request.routes.push_back({"/scene.json", std::move(encoded.json), "application/json"});
  for (const LibraryFile& lib : libraries)
    request.routes.push_back(
        {"/lib/" + lib.name, lib.text, lib.css ? "text/css; charset=utf-8" : "text/javascript; charset=utf-8"});
  const http::ServeReply reply = module->serve(request);
  result.ok = reply.ok;
  result.error = reply.error;
  result.port = reply.port;
  result.url = reply.url;
  result.stopped_by = reply.stopped_by;
  return result;
}

}  // namespace kanesim::viz
