// Mass properties of a closed triangle mesh (uniform density), in double precision.
#pragma once

#include "geometry/tri_mesh.h"

namespace kanesim::geometry {

// The volume integrals of the region a closed, outward-oriented mesh encloses:
// V = ∫ dV, s = ∫ r dV, C = ∫ r rᵀ dV, with r measured from M's origin and resolved in M.
// For an inside-out mesh all three change sign.
struct VolumeIntegrals {
  double volume = 0;                // V  (m³)
  Vec3 first_moment = Vec3::Zero();  // s  (m⁴)
  Mat3 second_moment = Mat3::Zero(); // C  (m⁵), symmetric
};

// Integrates over the triangles (mass_properties.cpp, eqs. 1-4). The mesh should be closed:
// for an open one the result depends on where M's origin is.
VolumeIntegrals IntegrateVolume(const TriMesh& mesh);

// How the mass follows from the shape: a density, or a total mass (then density = m / V and
// the distribution of the shape is kept).
struct MassSpec {
  enum class Kind { kDensity, kMass };
  Kind kind = Kind::kDensity;
  double value = 1.0;  // kg/m³ for kDensity, kg for kMass; finite and >= 0
  static MassSpec Density(double rho) { return {Kind::kDensity, rho}; }
  static MassSpec Mass(double m) { return {Kind::kMass, m}; }
};

// The rigid-body data a Body needs (docs/notation.md names).
struct MassProperties {
  double volume = 0;             // V  (m³), > 0
  double density = 0;            // ρ  (kg/m³)
  double mass = 0;               // m = ρ V  (kg)
  Vec3 p_MBcm = Vec3::Zero();    // centre of mass from M's origin, resolved in M  (m)
  Mat3 I_Bcm_M = Mat3::Zero();   // inertia about the centre of mass, resolved in M  (kg m²)
};

// Mass properties of the solid a closed, outward-oriented mesh encloses (check it first with
// CheckSolid, mesh_check.h). Throws std::invalid_argument when the volume is not positive or
// the spec's value is negative or not finite: both are the caller's bugs, not user input.
MassProperties ComputeMassProperties(const TriMesh& mesh, const MassSpec& spec);

// Principal moments (ascending) and axes (columns of R_MP, a proper rotation) of an inertia.
struct PrincipalInertia {
  Vec3 moments = Vec3::Zero();  // I1 <= I2 <= I3  (kg m²)
  Mat3 R_MP = Mat3::Identity(); // principal axes resolved in M; I = R_MP diag(moments) R_MPᵀ
};
PrincipalInertia Principal(const Mat3& I);

}  // namespace kanesim::geometry
