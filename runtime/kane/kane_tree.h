// Recursive path: Kane's equations of an open tree solved by eliminating the K-vector
// system body by body, leaves to root, then substituting back root to leaves
// (runtime/kane/kane_tree.cpp). O(K) with 6x6 and 6 x nf blocks, no general sparse LU; a
// tree of revolute joints about parallel axes (a planar mechanism) with 3x3 blocks.
// Trees only: closed loops and rolling contacts keep the reduced dense path.
#pragma once

#include <array>
#include <vector>

#include "runtime/program/program.h"

namespace kanesim::rt {

// Everything structural the recursion needs, fixed by the compiler (BuildTree).
struct TreeLayout {
  struct JointBlock {
    int nf = 0;                  // free speeds of the joint (0..6): columns of its tangent block S_L
    int f0 = 0;                  // free index of its first free speed (its free speeds are consecutive)
    int d0 = 0;                  // offset of its nf x nf block D_L^-1 in Workspace::tree_Dinv
    bool contiguous = true;      // all its speeds are free: S_L = H_W.middleCols(cols[0], nf)
    bool angular = false;        // nf = 1 on a revolute joint in tree direction: S_L = [0; h], half the products
    std::array<int, 6> cols{};   // full speed index of free speed k (k < nf)
  };
  std::vector<JointBlock> joints;  // K, in tree order
  std::vector<int> parent;         // K: p.joints[L].parent, packed for the passes
  std::vector<char> has_children;  // K: some joint has body L as its parent
  std::vector<char> first_share;   // K: L is its parent's last child in tree order, the first the backward
                                   //    pass reaches: it writes its share into the parent, the others add
  int d_size = 0;                  // sum of nf^2
  // Planar trees (SolveTreePlanar): every joint `angular` about axes parallel to one world
  // direction in every configuration (PlanarLayout's test, made on the constant axes).
  bool planar = false;
  Vec3 plane_n = Vec3::UnitZ(), plane_e1 = Vec3::UnitX(), plane_e2 = Vec3::UnitY();  // right-handed
  std::vector<double> plane_s;     // K: h_L = s_L n (s_L = +-1 for unit axes)
  std::vector<double> plane_Inn;   // K: n . I n of body L (central inertia), = axis^T I_BBcm_B axis
};

// A pivot of the mass matrix's factor (the tree's D_L, the dense Cholesky) below this
// fraction of its largest diagonal entry means M is singular to working precision (e.g. a
// massless, inertia-free link moved by a joint).
inline constexpr double kSingularPivot = 1e-13;
// Sets ws.error for a singular mass matrix; returns the solvers' -1.
int SingularMassMatrix(Workspace& ws);

// Compile time: the layout (Program::tree) for p.solver == SolverPath::Recursive.
void BuildTree(Program& p);
// Workspace creation: the per-body and per-joint arrays of the recursion.
void InitTreeWorkspace(const Program& p, Workspace& ws);
// Writes the free entries of ws.udot. Returns -1 on a singular mass matrix.
// SolveTreePlanar when p.tree->planar, else SolveTreeSpatial; the two solve the same
// equations (tests/runtime/tree_solver_test.cpp).
int SolveTree(const Program& p, Workspace& ws);
// The recursion with 6x6 spatial blocks: any open tree.
int SolveTreeSpatial(const Program& p, Workspace& ws);
// The recursion of a planar tree (p.tree->planar) with 3x3 blocks in the plane's
// coordinates (e1, e2, n).
int SolveTreePlanar(const Program& p, Workspace& ws);

}  // namespace kanesim::rt
