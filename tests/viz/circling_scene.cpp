#include "tests/viz/circling_scene.h"

#include <cmath>
#include <cstdlib>
#include <string>

#include "geometry/primitives.h"

namespace kanesim::viz::testing {
namespace {

using Eigen::AngleAxisd;
using Eigen::Quaterniond;

constexpr double kR = 0.8, kOmega = 1.3, kH = 0.3;

struct Axes {
  Vec3 e1, e2, up;
};

Axes AxesFor(char up) {
  if (up == 'y') return {Vec3::UnitZ(), Vec3::UnitX(), Vec3::UnitY()};
  return {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
}

void AddPose(ViewerScene& s, const Vec3& p, const Quaterniond& q) {
  s.poses.p_WB.push_back(p);
  s.poses.q_WB.push_back(q);
}

}  // namespace

ViewerScene CirclingScene(char up, int n_times, int n_bodies) {
  const Axes a = AxesFor(up);
  ViewerScene s;
  s.title = std::string("circling bodies, up +") + up;
  s.up_W = a.up;
  s.bodies.push_back({"orbiter", "Box 0.3 x 0.2 x 0.12 m", geometry::DrawBox(Vec3(0.3, 0.2, 0.12)), {0.8f, 0.1f, 0.1f, 1}});
  VisualMesh cylinder = geometry::DrawCylinder(0.1, 0.3);
  s.bodies.push_back({"spinner", "Cylinder r 0.1 m", cylinder, {0.1f, 0.2f, 0.85f, 1}});
  for (int b = 2; b < n_bodies; ++b)
    s.bodies.push_back({"extra" + std::to_string(b), "", geometry::DrawSphere(0.05, 2), {0.3f, 0.7f, 0.3f, 1}});

  s.decorations.push_back({"ground", -1, geometry::DrawGrid(a.up, 1.5, 0.25, 0.008), {0.55f, 0.55f, 0.6f, 1}});
  const auto axes = geometry::DrawAxes(0.25);
  const std::array<std::array<float, 4>, 3> rgb{{{0.9f, 0.1f, 0.1f, 1}, {0.1f, 0.8f, 0.1f, 1}, {0.1f, 0.1f, 0.9f, 1}}};
  for (int i = 0; i < 3; ++i) s.decorations.push_back({"", 0, axes[i], rgb[i]});

  ViewerSignal x{"orbiter.x", "m", {}, true}, y{"orbiter.y", "m", {}, false}, height{"spinner.height", "m", {}, true},
      angle{"orbiter.angle", "rad", {}, false}, energy{"energy", "J", {}, true};
  const Vec3 axis = Vec3(1, 2, 3).normalized();
  for (int k = 0; k < n_times; ++k) {
    const double t = k / 20.0;
    s.poses.times.push_back(t);
    const double c = std::cos(kOmega * t), sn = std::sin(kOmega * t);
    AddPose(s, kR * c * a.e1 + kR * sn * a.e2 + kH * a.up, Quaterniond(AngleAxisd(2.1 * t, axis)));
    AddPose(s, (0.9 + 0.2 * std::sin(2 * t)) * a.up,
            Quaterniond(AngleAxisd(1.1 * t, a.up)) * Quaterniond(AngleAxisd(0.6, a.e1)));
    for (int b = 2; b < n_bodies; ++b) {
      const double r = 0.2 + 0.05 * b, w = 0.5 + 0.1 * b;
      AddPose(s, r * std::cos(w * t) * a.e1 + r * std::sin(w * t) * a.e2 + 0.05 * b * a.up,
              Quaterniond(AngleAxisd(w * t, a.up)));
    }
    x.values.push_back(kR * c);
    y.values.push_back(kR * sn);
    height.values.push_back(0.9 + 0.2 * std::sin(2 * t));
    angle.values.push_back(2.1 * t);
    energy.values.push_back(1 + 0.5 * sn * sn);
  }
  s.signals = {x, y, height, angle, energy};
  return s;
}

ViewerScene EdgeScene() {
  ViewerScene s;
  s.title = "edge <cases>";
  s.up_W = -Vec3::UnitX();
  s.bodies.push_back({"frame", "", {}, {0.5f, 0.5f, 0.5f, 1}});
  s.bodies.push_back({"</script><b>x", "<label>", geometry::DrawBox(Vec3(0.2, 0.2, 0.2)), {0.9f, 0.6f, 0.1f, 0.5f}});
  s.poses.times = {2.0};
  AddPose(s, Vec3(1, 2, 3), Quaterniond(AngleAxisd(std::acos(-1.0) / 2, Vec3::UnitZ())));
  AddPose(s, Vec3::Zero(), Quaterniond::Identity());
  s.signals = {{"gap", "", {NAN}, true}, {"<i>one</i>", "m", {7.5}, true}};
  return s;
}

}  // namespace kanesim::viz::testing
