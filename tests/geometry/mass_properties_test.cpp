// Mass properties of closed meshes against closed forms (geometry/mass_properties.h).
#include "geometry/mass_properties.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "geometry/mesh_check.h"
#include "geometry/mesh_load.h"
#include "geometry/primitives.h"
#include "tests/support/mesh_files.h"

namespace kanesim::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
// Double-precision sums over a few hundred triangles: round-off only.
constexpr double kRoundOff = 1e-12;

Mat3 BoxInertia(double m, const Vec3& s) {
  return m / 12 * Vec3(s.y() * s.y() + s.z() * s.z(), s.x() * s.x() + s.z() * s.z(), s.x() * s.x() + s.y() * s.y())
                      .asDiagonal()
                      .toDenseMatrix();
}

void ExpectMatrixNear(const Mat3& a, const Mat3& b, double tol) {
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), tol) << "got\n" << a << "\nexpected\n" << b;
}

// Wrong if the signed-tetrahedron sums (eqs. 1-6) are wrong: a box's V, centre, inertia.
TEST(MassProperties, BoxMatchesClosedForm) {
  const Vec3 size(0.3, 0.2, 0.1);
  const MassProperties mp = ComputeMassProperties(BoxSolid(size), MassSpec::Density(7800));
  const double V = 0.3 * 0.2 * 0.1;
  EXPECT_NEAR(mp.volume, V, kRoundOff * V);
  EXPECT_NEAR(mp.mass, 7800 * V, kRoundOff * 7800 * V);
  EXPECT_LE(mp.p_MBcm.norm(), kRoundOff);
  ExpectMatrixNear(mp.I_Bcm_M, BoxInertia(7800 * V, size), kRoundOff * mp.I_Bcm_M.norm());
}

// Wrong if the centre of mass or the rotation of the inertia is mishandled, or digits are
// lost to cancellation far from the origin: a box turned by R and moved 100 m away has
// centre t and inertia R I0 Rᵀ.
TEST(MassProperties, TranslatedRotatedBox) {
  const Vec3 size(0.5, 0.1, 0.05), t(100, -30, 50);
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  TriMesh box = BoxSolid(size);
  Transform(box, R, t);
  const MassProperties mp = ComputeMassProperties(box, MassSpec::Density(1000));
  const double V = size.prod(), m = 1000 * V;
  EXPECT_NEAR(mp.volume, V, 1e-11 * V);
  EXPECT_LE((mp.p_MBcm - t).norm(), 1e-12 * t.norm());
  const Mat3 I = R * BoxInertia(m, size) * R.transpose();
  // Relative to the inertia's size; the vertices at 100 m carry 1e-16 * 100 absolute error.
  ExpectMatrixNear(mp.I_Bcm_M, I, 1e-9 * I.norm());
}

// Wrong if a given total mass does not keep the distribution: same centre, inertia scaled
// by m / (ρ V), density = m / V.
TEST(MassProperties, GivenMassKeepsDistribution) {
  const TriMesh box = BoxSolid(Vec3(0.4, 0.3, 0.2));
  const MassProperties by_density = ComputeMassProperties(box, MassSpec::Density(1));
  const MassProperties by_mass = ComputeMassProperties(box, MassSpec::Mass(3.0));
  EXPECT_DOUBLE_EQ(by_mass.mass, 3.0);
  EXPECT_NEAR(by_mass.density, 3.0 / (0.4 * 0.3 * 0.2), 1e-12 * by_mass.density);
  ExpectMatrixNear(by_mass.I_Bcm_M, by_density.I_Bcm_M * (3.0 / by_density.mass), 1e-14);
  ExpectMatrixNear(by_mass.I_Bcm_M, BoxInertia(3.0, Vec3(0.4, 0.3, 0.2)), 1e-14);
}

// Wrong if the icosahedron's volume differs from 5 (3 + √5) a³ / 12 (edge a = 4R/√(10+2√5)),
// or if subdivided icospheres break the bounds 4/3 π h³ <= V <= 4/3 π R³ (h the smallest
// distance from the centre to a face plane), or differ from the pyramid sum Σ A_f h_f / 3,
// or lose icosahedral symmetry (their inertia must be isotropic), or do not converge to the
// sphere's 2/5 m R².
TEST(MassProperties, IcosphereVolumeAndInertia) {
  const double R = 0.7;
  const double a = 4 * R / std::sqrt(10 + 2 * std::sqrt(5.0));
  const double V_ico = 5 * (3 + std::sqrt(5.0)) * a * a * a / 12;
  EXPECT_NEAR(ComputeMassProperties(IcosphereSolid(R, 0), MassSpec::Density(1)).volume, V_ico, kRoundOff);

  double previous_error = 1;
  for (int s = 1; s <= 4; ++s) {
    const TriMesh m = IcosphereSolid(R, s);
    const MassProperties mp = ComputeMassProperties(m, MassSpec::Density(1));
    double pyramids = 0, h_min = R;
    for (const Tri& t : m.triangles) {
      const Vec3 &p0 = m.vertices[t[0]], &p1 = m.vertices[t[1]], &p2 = m.vertices[t[2]];
      const Vec3 n = (p1 - p0).cross(p2 - p0);
      const double h = p0.dot(n.normalized());
      pyramids += 0.5 * n.norm() * h / 3;
      h_min = std::min(h_min, h);
    }
    const double V_sphere = 4.0 / 3 * kPi * R * R * R;
    EXPECT_NEAR(mp.volume, pyramids, kRoundOff) << "subdivisions " << s;
    EXPECT_LT(mp.volume, V_sphere);
    EXPECT_GT(mp.volume, 4.0 / 3 * kPi * h_min * h_min * h_min);
    const Mat3 I = mp.I_Bcm_M;
    EXPECT_NEAR(I(0, 0), I(1, 1), kRoundOff);
    EXPECT_NEAR(I(0, 0), I(2, 2), kRoundOff);
    EXPECT_LE((I - Mat3(I.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), kRoundOff);
    EXPECT_LE(mp.p_MBcm.norm(), kRoundOff);
    const double error = std::abs(I(0, 0) / (0.4 * mp.mass * R * R) - 1);
    EXPECT_LT(error, previous_error / 3) << "the inertia error must fall about 4x per subdivision";
    previous_error = error;
  }
  EXPECT_LT(previous_error, 2e-3);
}

// Wrong if the cylinder mesh differs from the closed form of the N-sided prism inscribed in
// it (cross-section A = N R² sin(α) / 2, polar moment J = N R⁴ sin(α) (2 + cos α) / 12,
// α = 2π/N), or does not approach stdlib Cylinder's m r²/2 and m (3 r² + L²)/12.
TEST(MassProperties, CylinderPrismClosedForm) {
  const double r = 0.05, L = 0.4, rho = 7800;
  for (int n : {6, 32, 256}) {
    const MassProperties mp = ComputeMassProperties(CylinderSolid(r, L, n), MassSpec::Density(rho));
    const double alpha = 2 * kPi / n;
    const double A = n * r * r * std::sin(alpha) / 2;
    const double J = n * std::pow(r, 4) * std::sin(alpha) * (2 + std::cos(alpha)) / 12;
    EXPECT_NEAR(mp.volume, A * L, kRoundOff * A * L);
    const double I_axis = rho * L * J, I_side = rho * (L * J / 2 + A * L * L * L / 12);
    ExpectMatrixNear(mp.I_Bcm_M, Vec3(I_axis, I_side, I_side).asDiagonal().toDenseMatrix(), kRoundOff * I_side);
    // Against the round cylinder (stdlib Cylinder): the prism's deficit in area, 1 − N sin(α)/(2π),
    // bounds the relative error of the mass.
    const double m_round = rho * kPi * r * r * L;
    const double deficit = 1 - n * std::sin(alpha) / (2 * kPi);
    EXPECT_NEAR(mp.mass / m_round, 1 - deficit, kRoundOff);
    EXPECT_NEAR(mp.I_Bcm_M(0, 0) / (m_round * r * r / 2), 1, 2.5 * deficit);
    EXPECT_NEAR(mp.I_Bcm_M(1, 1) / (m_round * (3 * r * r + L * L) / 12), 1, 2.5 * deficit);
  }
}

// Wrong if the scale is not applied to the file's coordinates: a box written in millimetres
// (binary STL), loaded with scale 0.001, has the box's mass properties in metres.
TEST(MassProperties, MillimetreMeshScaled) {
  const std::string dir = testing::TempDir("mm");
  TriMesh box = BoxSolid(Vec3(0.1, 0.04, 0.02));
  Transform(box, Mat3::Identity(), Vec3(0.25, 0, 0));
  testing::WriteBinaryStl(dir + "/part_mm.stl", box, 1000.0);
  const MeshLoadResult loaded = LoadMesh(dir + "/part_mm.stl", testing::Scaled(0.001));
  ASSERT_TRUE(loaded.ok()) << loaded.problems.front().message;
  const MassProperties mp = ComputeMassProperties(loaded.mesh, MassSpec::Density(2700));
  const double V = 0.1 * 0.04 * 0.02;
  EXPECT_NEAR(mp.volume, V, 1e-12 * V);
  EXPECT_LE((mp.p_MBcm - Vec3(0.25, 0, 0)).norm(), 1e-14);
  ExpectMatrixNear(mp.I_Bcm_M, BoxInertia(2700 * V, Vec3(0.1, 0.04, 0.02)), 1e-12 * mp.I_Bcm_M.norm());
}

// Wrong if negative or non-finite specs, or a non-positive volume, pass silently.
TEST(MassProperties, RejectsBadInput) {
  const TriMesh box = BoxSolid(Vec3(1, 1, 1));
  EXPECT_THROW(ComputeMassProperties(box, MassSpec::Density(-1)), std::invalid_argument);
  EXPECT_THROW(ComputeMassProperties(box, MassSpec::Mass(NAN)), std::invalid_argument);
  TriMesh inverted = box;
  for (Tri& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(ComputeMassProperties(inverted, MassSpec::Density(1)), std::invalid_argument);
}

// Wrong if the inertia-equivalent shapes (MuJoCo's) are not the shapes they stand for: a box's
// own inertia gives back its sides, an ellipsoid mesh's gives back its semi-axes (to its
// tessellation error), and the principal axes follow a rotated inertia.
TEST(EquivalentShape, RecoversBoxAndEllipsoid) {
  const Vec3 size(0.6, 0.2, 0.1);
  const Mat3 R = Eigen::AngleAxisd(0.4, Vec3(0, 0, 1)).toRotationMatrix();
  const double m = 2.0;
  const EquivalentShape box = InertiaBox(m, Vec3(1, 2, 3), R * BoxInertia(m, size) * R.transpose());
  // Ascending principal moments: the smallest is about the longest side, which comes first.
  EXPECT_NEAR(box.size[0], 0.6, 1e-12);
  EXPECT_NEAR(box.size[1], 0.2, 1e-12);
  EXPECT_NEAR(box.size[2], 0.1, 1e-12);
  EXPECT_NEAR(std::abs(box.R_BP.col(0).dot(R.col(0))), 1, 1e-12);
  EXPECT_NEAR(box.R_BP.determinant(), 1, 1e-12);
  EXPECT_EQ(box.p_BBcm, Vec3(1, 2, 3));

  const Vec3 semi(0.3, 0.2, 0.1);
  const MassProperties ell = ComputeMassProperties(EllipsoidSolid(semi, 4), MassSpec::Density(1));
  const EquivalentShape e = InertiaEllipsoid(ell.mass, ell.p_MBcm, ell.I_Bcm_M);
  EXPECT_NEAR(e.size[0], 0.3, 2e-3 * 0.3);
  EXPECT_NEAR(e.size[1], 0.2, 2e-3 * 0.2);
  EXPECT_NEAR(e.size[2], 0.1, 2e-3 * 0.1);
}

}  // namespace
}  // namespace kanesim::geometry
