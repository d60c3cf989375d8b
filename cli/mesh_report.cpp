// `kanesim check`'s report of mesh bodies: the mass properties computed from each mesh
// (MeshBody; lang/elab_mesh.cpp), with the parameter values of this run.
#include <fmt/core.h>

#include <ostream>

#include "cli/scene.h"

namespace kanesim::cli {

void PrintMeshBodies(const flat::Mechanism& mech, std::ostream& out) {
  size_t n = 0;
  // A BodyShape's mesh (no `volume`) is drawn only; its mass properties are given.
  auto solid = [&](const flat::Shape& s) {
    return s.kind == flat::ShapeKind::Mesh && s.body >= 0 && mech.FindParam(s.name + ".volume") >= 0;
  };
  for (const auto& s : mech.shapes) n += solid(s);
  if (n == 0) return;
  const std::vector<double> p = flat::EvaluateParams(mech);
  auto val = [&](flat::ExprId e) { return flat::EvalParamExpr(mech, p, e); };
  out << fmt::format("  mesh bodies {} (mass properties from the closed mesh, uniform density)\n", n);
  for (const auto& s : mech.shapes) {
    if (!solid(s)) continue;
    const flat::Body& b = mech.bodies[static_cast<size_t>(s.body)];
    const int vi = mech.FindParam(s.name + ".volume");
    const double volume = vi >= 0 ? p[static_cast<size_t>(vi)] : 0;
    const double m = val(b.mass);
    out << fmt::format("    {:<20} {} (scale {:.6g})\n", s.name, s.mesh_file, val(s.size[0]));
    out << fmt::format("      volume {:.10g} m3, mass {:.10g} kg, density {:.10g} kg/m3\n", volume, m,
                       volume > 0 ? m / volume : 0.0);
    out << fmt::format("      r_CM   {{{:.10g}, {:.10g}, {:.10g}}} m\n", val(b.r_cm[0]), val(b.r_cm[1]), val(b.r_cm[2]));
    out << fmt::format("      I      {{{{{:.10g}, {:.10g}, {:.10g}}}, {{{:.10g}, {:.10g}, {:.10g}}}, "
                       "{{{:.10g}, {:.10g}, {:.10g}}}}} kg.m2 (about the centre of mass)\n",
                       val(b.inertia[0]), val(b.inertia[1]), val(b.inertia[2]), val(b.inertia[3]), val(b.inertia[4]),
                       val(b.inertia[5]), val(b.inertia[6]), val(b.inertia[7]), val(b.inertia[8]));
  }
}

}  // namespace kanesim::cli
