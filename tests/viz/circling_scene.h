// The scene the viewer's browser tests open (browser_test.py computes the same closed forms
// on its own and compares them with what the page renders), also used by the unit tests and
// the benchmark.
//
// With e_up the world's up axis and (e1, e2, e_up) right-handed — up 'z': (x, y, z);
// up 'y': (z, x, y) — and t_k = k / 20 (k = 0 … n_times − 1):
//   orbiter  p = R cos(ω t) e1 + R sin(ω t) e2 + h e_up,  q = rotation by φ = 2.1 t about (1, 2, 3)/√14
//            (R = 0.8 m, ω = 1.3 rad/s, h = 0.3 m): a red box 0.3 × 0.2 × 0.12 m centred on B
//   spinner  p = (0.9 + 0.2 sin 2t) e_up,  q = rotation by 1.1 t about e_up, then by 0.6 rad about e1
//            (q = q_up(1.1 t) q_e1(0.6)): a blue cylinder of radius 0.1 m and length 0.3 m along B's x
// and bodies 2 … n_bodies − 1 (the benchmark's extra bodies) on circles of their own.
// Decorations: a grey ground grid in the plane through W's origin normal to e_up, and the
// orbiter's axes. Signals: orbiter.x, orbiter.y (m), spinner.height (m), orbiter.angle (rad),
// energy (J) = 1 + 0.5 sin²(ω t); plotted when the page opens: orbiter.x, spinner.height, energy.
#pragma once

#include "viz/viewer_scene.h"

namespace kanesim::viz::testing {

ViewerScene CirclingScene(char up, int n_times = 101, int n_bodies = 2);

// Corner cases the page must survive: one instant at t = 2 s; "frame" (no drawing) at
// (1, 2, 3) turned a quarter turn about z; "</script><b>x" (a 0.2 m box) at the origin, half
// transparent; signals "gap" (NaN only) and "<i>one</i>" (7.5); gravity along +x (up −x).
ViewerScene EdgeScene();

}  // namespace kanesim::viz::testing
