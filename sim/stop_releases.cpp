// The joints held at their stops with their exact friction released together (sim/end_stops.h
// ReleaseTogether; docs/events.md "Held at the stop"). A joint at rest on its stop is held by
// the stop's reaction lambda >= 0 and its static friction |tau| <= B = mu_s r N + C_s; it leaves
// where the pull passes both, lambda + B < 0 ((3) of sim/end_stops.cpp), sliding away with its
// friction sliding. Letting one go changes what every other one needs: the stuck joints'
// forces and the normal forces move with it. So the set R released from the held set H is
// decided together, with every stuck force and N solved for that choice (StickSlipEvents::
// AtStops): it is consistent when
//   held k in H \ R:    lambda_k + B_k + noise_k >= 0          (the stop and friction hold it)
//   released k in R:    d2g_k/dt2 >= -(100 eps + rtol) |udot|   (it slides away, not back in)   (4)
// (noise_k: the reaction's round-off, ReactionNoise; the acceleration's bound is Unseen's). The
// choices are enumerated, fewer released first, the joints pulled hardest first among equal
// counts: the complementarity problem of the stops with friction, solved by enumeration as
// the friction laws at rest are (sim/stick_slip_laws.cpp). One at a time, each with the other
// stuck forces from before it, j[1] and j[2] of a chain of 6 (tests/stress/models/
// friction_stop_chain.mech, issue 41) were both let go at 0.2916 s, and j[2], with j[1]
// sliding, then accelerated into its stop (exit 2 in all five integrators).
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "sim/end_stops.h"
#include "sim/stick_slip.h"

namespace kanesim::sim {

namespace {
constexpr size_t kMaxTogether = 8;  // 2^8 - 1 choices at most
}  // namespace

int StickSlipEvents::AtStops(rt::Workspace& ws, double t, const double* y,
                             const std::vector<std::pair<int, int>>& laws) {
  for (const auto& [u, law] : laws)
    for (Joint& j : joints_)
      if (j.f.u == u) j.mode = law, j.tau = 0.0, j.leader = -1;
  return Resolve(ws, t, y);
}

int EndStopEvents::ReleaseTogether(rt::Workspace& ws, double t, const double* y, bool* released) {
  *released = false;
  if (!stick_) return 0;
  std::vector<double> lambda, noise, a_held(static_cast<size_t>(nu_));
  if (int s = Reactions(ws, t, y, &lambda, a_held.data(), &noise); s != 0) return s;
  std::vector<int> H;  // the held sides with friction, pulled hardest first
  for (int i = 0; i < Count(); ++i)
    if (sides_[static_cast<size_t>(i)].resting && HeldWithFriction(sides_[static_cast<size_t>(i)])) H.push_back(i);
  if (H.size() < 2 || H.size() > kMaxTogether) return 0;
  const auto pull = [&](int i) {
    return lambda[static_cast<size_t>(i)] + StaticFriction(ws, sides_[static_cast<size_t>(i)]);
  };
  std::stable_sort(H.begin(), H.end(), [&](int a, int b) { return pull(a) < pull(b); });
  const size_t n = H.size();
  std::vector<unsigned> choices;  // bit k: H[k] released
  for (unsigned c = 1; c < (1u << n); ++c) choices.push_back(c);
  std::stable_sort(choices.begin(), choices.end(), [](unsigned a, unsigned b) {
    const int pa = std::popcount(a), pb = std::popcount(b);
    return pa != pb ? pa < pb : a < b;  // (bit 0 the hardest pulled: a < b prefers it)
  });
  const auto laws = [&](unsigned c) {
    std::vector<std::pair<int, int>> out;
    for (size_t k = 0; k < n; ++k) {
      Side& s = sides_[static_cast<size_t>(H[k])];
      s.resting = !(c >> k & 1u);
      out.emplace_back(stops_[static_cast<size_t>(s.stop)].u, s.resting ? 0 : (s.upper ? -1 : 1));
    }
    return out;
  };
  for (unsigned c : choices) {
    if (int s = stick_->AtStops(ws, t, y, laws(c)); s != 0) continue;  // (no unique forces: not this one)
    if (Reactions(ws, t, y, &lambda, a_held.data(), &noise) != 0) continue;
    double scale = 1.0;
    for (double a : a_held) scale = std::max(scale, std::abs(a));
    bool consistent = true;
    for (size_t k = 0; k < n && consistent; ++k) {
      const Side& s = sides_[static_cast<size_t>(H[k])];
      if (s.resting) {
        consistent = lambda[static_cast<size_t>(H[k])] + LeaveMargin(ws, s, noise[static_cast<size_t>(H[k])]) >= 0.0;
        continue;
      }
      double gap = 0.0, cb = 0.0, a = 0.0;
      if (int r = Row(ws, t, y, s, &gap, J_.data(), &cb); r != 0) return r;
      a = cb;
      for (int i = 0; i < nu_; ++i) a += J_[static_cast<size_t>(i)] * a_held[static_cast<size_t>(i)];
      consistent = a >= -(kLeaveRoundoffs * std::numeric_limits<double>::epsilon() + rtol_) * scale;
    }
    if (!consistent) continue;
    for (size_t k = 0; k < n; ++k)
      if (c >> k & 1u) {
        sides_[static_cast<size_t>(H[k])].resting = true;  // (Leave's own bookkeeping)
        Leave(ws, H[k]);
      }
    *released = true;
    return 0;
  }
  return stick_->AtStops(ws, t, y, laws(0));  // every one held again
}

}  // namespace kanesim::sim
