// The scene as the page reads it: compact JSON with the numbers as base64 little-endian arrays.
//
// Format "kanesim-viewer", version 1 (the page's scene.js reads it):
//   { "format": "kanesim-viewer", "version": 1, "title": string,
//     "up": [x, y, z]                  up_W, unit
//     "n_times": N, "stride": s        instants written, and the decimation stride
//     "times": F64[N]                  seconds
//     "bodies": [{"name", "label", "rgba": [r, g, b, a], "mesh": MESH}]          (n_bodies)
//     "decorations": [{"name", "body": index or -1, "rgba", "mesh": MESH}]
//     "poses": F32[N · n_bodies · 7]   per instant, per body: p_WB (x, y, z), q_WB (w, x, y, z)
//     "signals": [{"name", "unit", "plot": bool, "values": F32[N]}],
//     "events": [{"t": seconds, "element", "kind"}] }   (the run's events, in time order)
//   MESH = {"vertices": n, "positions": F32[3n], "normals": F32[3n], "index_bytes": 2 or 4,
//           "indices": U16 or U32[3 · n_triangles]}  (U16 when n <= 65535)
// where F32[k] etc. is a base64 string of k little-endian numbers. Strings are JSON-escaped
// with '<', '>' and '&' as \u escapes, so the JSON can sit inside a <script> element.
// Positions, rotations and signal values are single precision (what WebGL draws with);
// times are double.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "viz/viewer.h"

namespace kanesim::viz {

// RFC 4648 base64 (with '=' padding) of n bytes.
std::string Base64(const void* data, size_t n);

// A JSON string literal (with the quotes) for UTF-8 text.
std::string JsonString(std::string_view text);

struct EncodedScene {
  std::string json;       // the scene in the format above
  uint64_t stride = 1;    // every stride-th instant (and the last) is in it
  uint64_t instants = 0;  // N
};

// Checks the scene (CheckScene) and the limits of `options`, chooses the instants, encodes.
// On failure *error says why and the result is empty.
EncodedScene EncodeScene(const ViewerScene& scene, const PageOptions& options, std::string* error);

// The instants written for n_times instants of `per_instant` numbers each under a limit of
// max_values: 0, s, 2s, … and the last, s the smallest stride that fits. Empty when even two
// instants (or one, if n_times == 1) do not fit.
std::vector<size_t> ChooseInstants(size_t n_times, uint64_t per_instant, uint64_t max_values, uint64_t* stride);

}  // namespace kanesim::viz
