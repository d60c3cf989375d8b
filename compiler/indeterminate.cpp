// Compile stage: which constraint-force components the equations determine
// (docs/constraints.md "Indeterminate constraint forces").
//
// The multipliers enter the equations only through the generalized force they exert on
// the free speeds (runtime/constraints/reactions.cpp eq. 1):
//   A^T lambda = M udot - f                                                         (1)
// so with redundant constraints (rank A < n_c: a planar loop built from spatial joints, a
// contact row a joint already enforces) lambda is fixed only up to the null space of the
// constraint-force map A^T:
//   lambda = lambda_0 + N y,   A^T N = 0,   N orthonormal (n_c x (n_c - rank))         (2)
// Every reaction signal is linear in lambda, the bodies' terms being fixed by the motion
// (runtime/constraints/reactions.cpp eq. 5):
//   r_k = r_k0 + c_k . lambda                                                        (3)
// so r_k is determined iff c_k is orthogonal to N (c_k in the row space of A^T, the range
// of A), and statically indeterminate otherwise. Numerically:
//   N   the last n_c - rank columns of Q of the column-pivoted QR  A P = Q R, with the
//       rank threshold of assembly (kRankTol), so that n_c - rank is the count of
//       redundant rows AssembleLoops reports;
//   c_k the reactions of lambda = e_i, i = 1..n_c (MultiplierReactions), column by column;
//   k indeterminate when  |N^T c_k| > kIndeterminateTol |c_k|                        (4)
// Decided once at the assembled start; the assumption (as for the rank and the DOF) is
// that the redundancy of the start holds along the motion, which it does for the
// mechanisms whose redundancy is structural (planar loops, a contact on a planar joint).
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "compiler/compile_internal.h"
#include "runtime/constraints/contacts.h"
#include "runtime/constraints/reactions.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

namespace {

// (4): relative size of c_k's component in the null space above which component k is
// indeterminate. Exact zeros for structural redundancy come out at round-off (1e-16 of
// |c_k|, measured 0 for the planar four-bar); lengths of the order of the loop size keep
// translation (N) and alignment (N m) multipliers comparable.
constexpr double kIndeterminateTol = 1e-8;

}  // namespace

void FindIndeterminateReactions(Program& p, Workspace& ws) {
  const flat::Mechanism& m = *p.mech;
  const auto nc = static_cast<Eigen::Index>(p.rows.size());
  p.reaction_indeterminate.assign(m.joints.size(), 0);
  p.contact_indeterminate.assign(p.contacts.size(), 0);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(ws.A);
  qr.setThreshold(kRankTol);
  const Eigen::Index rank = qr.rank();
  if (rank == nc) return;
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(nc, nc);
  const Eigen::MatrixXd N = Q.rightCols(nc - rank);  // (2)

  // The components with signals: 6 per tree and cut joint, 3 forces per contact.
  std::vector<int> joints;
  for (const TreeJoint& j : p.joints) joints.push_back(j.flat_index);
  for (const LoopClosure& l : p.loops) joints.push_back(l.flat_index);
  const auto nj = static_cast<Eigen::Index>(joints.size());
  Eigen::MatrixXd C(6 * nj + 3 * static_cast<Eigen::Index>(p.contacts.size()), nc);  // rows c_k^T (3)
  for (Eigen::Index i = 0; i < nc; ++i) {
    ws.lambda_c.setZero();
    ws.lambda_c[i] = 1.0;
    MultiplierReactions(p, ws);
    for (Eigen::Index j = 0; j < nj; ++j)
      C.block<6, 1>(6 * j, i) = JointReactionInFrameB(p, ws, joints[static_cast<size_t>(j)]);
    for (size_t ci = 0; ci < p.contacts.size(); ++ci) {
      ContactPoint cp;
      const Vec3 F = ContactForce(p, ws, static_cast<int>(ci), &cp);
      Vec3 lon, lat;
      ContactDirections(p.contacts[ci], cp, &lon, &lat);
      const Eigen::Index k = 6 * nj + 3 * static_cast<Eigen::Index>(ci);
      C(k, i) = F.dot(p.contacts[ci].n_W);
      C(k + 1, i) = F.dot(lon);
      C(k + 2, i) = F.dot(lat);
    }
  }
  ws.lambda_c.setZero();
  const Eigen::MatrixXd D = C * N;
  for (Eigen::Index k = 0; k < C.rows(); ++k) {
    const double c = C.row(k).norm();
    if (!(D.row(k).norm() > kIndeterminateTol * c)) continue;  // (4)
    const auto bit = static_cast<std::uint8_t>(1u << (k < 6 * nj ? k % 6 : (k - 6 * nj) % 3));
    if (k < 6 * nj)
      p.reaction_indeterminate[static_cast<size_t>(joints[static_cast<size_t>(k / 6)])] |= bit;
    else
      p.contact_indeterminate[static_cast<size_t>((k - 6 * nj) / 3)] |= bit;
  }

  // Coulomb friction reads the force across its joint's axis (friction.cpp eq. 1): when
  // a component of it is indeterminate, the friction force follows the minimum-norm share
  // of the normal force, which is one admissible distribution, not a determined one.
  for (int L : p.friction_joints) {
    const TreeJoint& j = p.joints[static_cast<size_t>(L)];
    if (j.mu == 0.0) continue;  // constant friction only: it reads no normal force
    const std::uint8_t bits = p.reaction_indeterminate[static_cast<size_t>(j.flat_index)];
    for (int k = 0; k < 3; ++k)
      if (((bits >> k) & 1u) != 0 && std::fabs(j.axis[k]) < 1.0 - 1e-12) {
        p.friction_indeterminate.push_back(L);
        break;
      }
  }
}

CompileMessage IndeterminateWarning(const Program& p, const std::vector<std::string>& signals) {
  std::string list;
  for (const std::string& s : signals) list += (list.empty() ? "" : ", ") + s;
  CompileMessage w;
  w.code = flat::DiagCode::IndeterminateSignals;
  w.message = std::to_string(signals.size()) + " constraint-force component" + (signals.size() == 1 ? " is" : "s are") +
              " statically indeterminate (redundant constraints) and written as nan: " + list;
  // One note per owner of redundant rows (a cut joint or a contact), in row order
  // (redundant_rows is sorted).
  std::vector<int> owners;  // loop index, or -1 - contact index
  for (int r : p.redundant_rows) {
    const ConstraintRow& row = p.rows[static_cast<size_t>(r)];
    if (row.coupling >= 0) continue;  // a coupling's force is a joint force, no reaction signal
    const int owner = row.contact >= 0 ? -1 - row.contact : row.loop;
    if (std::find(owners.begin(), owners.end(), owner) == owners.end()) owners.push_back(owner);
  }
  for (int owner : owners) {
    std::string rows;
    for (int r : p.redundant_rows) {
      const ConstraintRow& row = p.rows[static_cast<size_t>(r)];
      if (row.coupling < 0 && (row.contact >= 0 ? -1 - row.contact : row.loop) == owner) rows += (rows.empty() ? "" : ", ") + row.what;
    }
    const bool contact = owner < 0;
    const std::string& name = contact ? p.contacts[static_cast<size_t>(-1 - owner)].name : p.loops[static_cast<size_t>(owner)].name;
    const flat::SourceLoc& loc = contact ? p.contacts[static_cast<size_t>(-1 - owner)].loc : p.loops[static_cast<size_t>(owner)].loc;
    if (w.loc.file.empty()) w.loc = loc;
    w.notes.push_back({loc, std::string("redundant constraint(s) of ") + (contact ? "contact '" : "joint '") + name +
                                "': " + rows});
  }
  w.hint = "the equations fix only what these constraints carry together; `--reactions min-norm` writes the "
           "minimum-norm share (one admissible distribution, not a measured one)";
  return w;
}

CompileMessage FrictionIndeterminateWarning(const Program& p) {
  CompileMessage w;
  if (p.friction_indeterminate.empty()) return w;
  w.code = flat::DiagCode::FrictionIndeterminate;
  std::string names;
  for (int L : p.friction_indeterminate) {
    const TreeJoint& j = p.joints[static_cast<size_t>(L)];
    names += (names.empty() ? "'" : ", '") + j.name + "'";
    if (w.loc.file.empty()) w.loc = j.loc;
    w.notes.push_back({j.loc, "joint '" + j.name + "' has friction (mu = " + std::to_string(j.mu) +
                                  ") and a statically indeterminate force across its axis"});
  }
  w.message = "Coulomb friction in " + names +
              " reads a normal force that redundant constraints leave undetermined; it uses the minimum-norm share";
  w.hint = "the friction force then depends on an arbitrary split of the load; remove the redundancy (e.g. a "
           "spherical or universal joint in the loop) to make the normal force determined";
  return w;
}

}  // namespace kanesim::rt
