// What the viewer shows: the bodies and their drawings, the motion (a pose per body and
// output instant), extra drawings (ground grid, frame axes) and time signals to plot.
//
// Frames and units (docs/notation.md): W is the simulation's world frame, B a body frame;
// lengths in metres, times in seconds, rotations as unit quaternions (p_W = R(q_WB) p_B).
// The page draws W turned so that up_W points up on the screen; everything in this struct
// stays in W.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "geometry/gltf_export.h"
#include "geometry/tri_mesh.h"

namespace kanesim::viz {

using geometry::Vec3;
using geometry::VisualMesh;

// One moving body.
struct ViewerBody {
  std::string name;   // unique and non-empty; shown on hover; the key of the page's test hook
  std::string label;  // optional second line on hover (e.g. "Box, model.mech:12"); may be empty
  VisualMesh mesh;    // the drawing, resolved in B  (m); may be empty (an invisible frame)
  std::array<float, 4> rgba{0.7f, 0.7f, 0.75f, 1.0f};  // base colour, linear RGBA in [0, 1] (as glTF)
};

// A drawing that is not a body: a ground grid, a frame's axes, a joint marker. Fixed in the
// world, or carried by a body.
struct ViewerDecoration {
  std::string name;  // shown on hover when non-empty (an empty name is not pickable)
  int body = -1;     // -1: fixed in W; otherwise the index into ViewerScene::bodies that carries it
  VisualMesh mesh;   // resolved in W (body = -1) or in that body's frame B  (m)
  std::array<float, 4> rgba{0.6f, 0.6f, 0.6f, 1.0f};  // linear RGBA in [0, 1]
};

// A time series aligned with the output instants: a joint coordinate, an energy, a
// constraint force. Plotted in its own panel with its own y axis.
struct ViewerSignal {
  std::string name;            // unique and non-empty, e.g. "shoulder.q"
  std::string unit;            // e.g. "rad", "J", "N"; may be empty
  std::vector<double> values;  // one per instant  (n_times); NaN or ±inf leave a gap in the plot
  bool plot = false;           // plotted when the page opens (none set: the first three are)
};

// A discrete event of the run (an impact, a stop taken or left, a when clause firing; the
// `--events` log): the page marks its time on the time line and in the plots.
struct ViewerEvent {
  double time = 0.0;     // seconds, finite
  std::string element;   // "j1", "floor", "when (ball.mech:9)"
  std::string kind;      // "impact at q_min, speed -1 -> 0.8", "rests on the plane", "fires"
};

struct ViewerScene {
  std::string title = "kanesim";  // the page's title (e.g. the model's name)
  Vec3 up_W = Vec3::UnitY();      // the world's up direction (−g), resolved in W; finite, non-zero
  std::vector<ViewerBody> bodies;            // (n_bodies)
  std::vector<ViewerDecoration> decorations;
  // The motion, instant by instant: entry k · n_bodies + b of p_WB and q_WB is body b at
  // times[k]. times: seconds, finite, non-decreasing, at least one (n_times); p_WB: B's origin
  // from W's origin resolved in W (m); q_WB: B's orientation in W, unit within 1e-4 (it is
  // normalised). Between instants the page interpolates linearly (positions) and by slerp
  // (rotations).
  geometry::PoseSequence poses;
  std::vector<ViewerSignal> signals;
  std::vector<ViewerEvent> events;  // in time order
};

// Why a scene cannot be shown (empty when it can): sizes that do not match, names empty or
// repeated, non-finite numbers, a quaternion off unit length, colours outside [0, 1], a
// triangle referring to a missing vertex, a decoration on a body that does not exist.
std::string CheckScene(const ViewerScene& scene);

}  // namespace kanesim::viz
