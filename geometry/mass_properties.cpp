// Mass properties of a polyhedron by the divergence theorem, written as a sum over signed
// tetrahedra.
//
// Sources: B. Mirtich, "Fast and accurate computation of polyhedral mass properties", Journal
// of Graphics Tools 1(2), 1996 (volume integrals reduced to surface integrals by the divergence
// theorem); D. Eberly, "Polyhedral Mass Properties (Revisited)", Geometric Tools, 2002;
// F. Tonon, "Explicit exact formulas for the 3-D tetrahedron inertia tensor in terms of its
// vertex coordinates", Journal of Mathematics and Statistics 1(1), 2005.
//
// Each triangle (a, b, c) of the closed surface spans, with a reference point o, the
// tetrahedron (o, a, b, c); its signed volume is positive when o lies behind the triangle
// (on the side its outward normal points away from). The signed tetrahedra add up to the
// enclosed region exactly: a point inside is covered once more positively than negatively,
// a point outside as often positively as negatively. This is the
// divergence theorem applied to the fields r, r rᵀ, and it is exact for any polyhedron:
// no quadrature error. With a, b, c measured from o:
//
//   (1)  V_t = det[a b c] / 6 = a · (b × c) / 6
//   (2)  ∫_t r dV     = V_t (a + b + c) / 4
//   (3)  ∫_t r rᵀ dV  = V_t / 20 (a aᵀ + b bᵀ + c cᵀ + d dᵀ),   d = a + b + c
//
// (3) follows from the unit tetrahedron (0, e1, e2, e3), where ∫ ξ_i ξ_j dξ = (1 + δ_ij)/120,
// mapped by r = [a b c] ξ: ∫ r rᵀ dV = det[a b c] [a b c] (1 + 11ᵀ) [a b c]ᵀ / 120.
//
// Sums over the triangles give V, s, C about o (VolumeIntegrals). With density ρ:
//
//   (4)  m = ρ V,   c = s / V (the centre of mass from o),
//   (5)  C_cm = C − V c cᵀ (second moment about the centre of mass),
//   (6)  I_cm = ρ (tr(C_cm) 1 − C_cm)       (I = ∫ ρ (|r|² 1 − r rᵀ) dV).
//
// Precision: o is the centre of the mesh's bounding box, so that a part far from its frame's
// origin does not lose digits to cancellation in (5); everything is accumulated in double.
#include "geometry/mass_properties.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>

namespace kanesim::geometry {
namespace {

Vec3 BoxCentre(const std::vector<Vec3>& v) {
  if (v.empty()) return Vec3::Zero();
  Vec3 lo = v[0], hi = v[0];
  for (const Vec3& p : v) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return 0.5 * (lo + hi);
}

// Eqs. (1)-(3) summed over the triangles, with r measured from o.
VolumeIntegrals IntegrateAbout(const TriMesh& mesh, const Vec3& o) {
  double six_v = 0;           // Σ det[a b c]
  Vec3 s24 = Vec3::Zero();    // Σ det (a + b + c)            = 24 s
  Mat3 c120 = Mat3::Zero();   // Σ det (a aᵀ + b bᵀ + c cᵀ + d dᵀ) = 120 C
  for (const Tri& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[t[0]] - o, b = mesh.vertices[t[1]] - o, c = mesh.vertices[t[2]] - o;
    const double det = a.dot(b.cross(c));  // eq. (1)
    const Vec3 d = a + b + c;
    six_v += det;
    s24 += det * d;                        // eq. (2)
    c120.noalias() += det * (a * a.transpose() + b * b.transpose() + c * c.transpose() + d * d.transpose());  // eq. (3)
  }
  return {six_v / 6, s24 / 24, c120 / 120};
}

}  // namespace

VolumeIntegrals IntegrateVolume(const TriMesh& mesh) {
  const Vec3 o = BoxCentre(mesh.vertices);
  const VolumeIntegrals about_o = IntegrateAbout(mesh, o);
  // Move the moments from o to M's origin: r = r_o + o.
  VolumeIntegrals out;
  out.volume = about_o.volume;
  out.first_moment = about_o.first_moment + about_o.volume * o;
  out.second_moment = about_o.second_moment + about_o.first_moment * o.transpose() +
                      o * about_o.first_moment.transpose() + about_o.volume * o * o.transpose();
  return out;
}

MassProperties ComputeMassProperties(const TriMesh& mesh, const MassSpec& spec) {
  if (!std::isfinite(spec.value) || spec.value < 0)
    throw std::invalid_argument("ComputeMassProperties: density or mass must be finite and >= 0");
  // Integrate about the box centre o (not M's origin) so that eq. (5) cancels little.
  const Vec3 o = BoxCentre(mesh.vertices);
  const VolumeIntegrals vi = IntegrateAbout(mesh, o);
  if (!(vi.volume > 0) || !std::isfinite(vi.volume))
    throw std::invalid_argument("ComputeMassProperties: the mesh encloses no positive volume");

  MassProperties mp;
  mp.volume = vi.volume;
  mp.density = spec.kind == MassSpec::Kind::kDensity ? spec.value : spec.value / vi.volume;
  mp.mass = spec.kind == MassSpec::Kind::kDensity ? spec.value * vi.volume : spec.value;  // eq. (4)
  const Vec3 c_o = vi.first_moment / vi.volume;                                             // eq. (4)
  const Mat3 C_cm = vi.second_moment - vi.volume * c_o * c_o.transpose();                   // eq. (5)
  mp.p_MBcm = c_o + o;
  mp.I_Bcm_M = mp.density * (C_cm.trace() * Mat3::Identity() - C_cm);                        // eq. (6)
  mp.I_Bcm_M = 0.5 * (mp.I_Bcm_M + mp.I_Bcm_M.transpose()).eval();
  return mp;
}

PrincipalInertia Principal(const Mat3& I) {
  Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (I + I.transpose()));
  PrincipalInertia p;
  p.moments = eig.eigenvalues();  // ascending
  p.R_MP = eig.eigenvectors();
  if (p.R_MP.determinant() < 0) p.R_MP.col(2) *= -1;  // a proper rotation
  return p;
}

}  // namespace kanesim::geometry
