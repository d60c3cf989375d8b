// Connect, the elaborator's phase after instantiation. Its first step walks every
// instance's equations: `x = expr` binds a variable (or one element), for- and
// if-equations are unrolled (their ranges and conditions asked of the evaluator), and
// connect() pairs frames and flanges. Its second step turns those pairs into identities:
// each connect() set of frames becomes one flat frame, each set of flanges one group.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

class Evaluator;
struct InstanceTree;

// A when clause found by the walk, evaluated by Emit (lang/elab_when.cpp) once the joints
// are known: its instance and the for-loop iterators around it.
struct PendingWhen {
  Node* scope = nullptr;
  const ast::Equation* eq = nullptr;
  std::shared_ptr<const Iters> iters;
};

// connect() pairs, by provisional frame ids and flange ids (Node::prim_index), and the
// when clauses.
struct Links {
  std::vector<std::pair<int, int>> frames;
  std::vector<std::pair<int, int>> flanges;
  std::vector<PendingWhen> whens;
};

// The connect() sets.
struct Connections {
  std::vector<int> frame;           // provisional frame id -> flat frame id (index into m->frames)
  std::vector<int> frame_set_size;  // provisional frame id -> the number of frames in its set
  std::vector<int> flange_set;      // flange id -> its set (the id of one flange in it)
};

// Binds the equations of every enabled instance under `root`; returns connect()'s pairs.
Links BindEquations(Node* root, Evaluator& eval, Diagnostics& diags);

// The sets of `links`; writes one flat frame per set of frames to m->frames (named after
// its first frame, with every member's path as an alias).
Connections Connect(const InstanceTree& tree, const Links& links, const SourcePlaces& places, flat::Mechanism* m);

}  // namespace kanesim::lang::elab
