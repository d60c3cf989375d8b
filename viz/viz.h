// The layer viz/ (kanesim_viz): the viewer page (the 3-D animation beside time plots, one
// self-contained HTML file or served on 127.0.0.1; the HTTP server loaded only when
// serving) and the root-locus page of `linearize --sweep`. Layers above include this header
// or the parts it lists.
#pragma once

#include "viz/locus_page.h"    // the root locus as one offline page
#include "viz/scene_json.h"    // the scene as the page reads it
#include "viz/server.h"        // serving the page over HTTP
#include "viz/viewer.h"        // the viewer page
#include "viz/viewer_scene.h"  // what the viewer shows
