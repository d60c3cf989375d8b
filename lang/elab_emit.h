// Emit, the elaborator's last phase: the instance tree's primitives become the flat
// mechanism, one function per primitive (lang/elab_emit.cpp), shapes for drawing
// (lang/elab_shapes.cpp), the outputs, every parameter, and the experiment annotation.
// Primitives' fields are asked of the evaluator.
#pragma once

#include <vector>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

class Evaluator;
struct Connections;
struct PendingWhen;
struct InstanceTree;

// Shown every enabled variable, depth first, by Emit's walk over the tree (the unit
// check, lang/elab_units.h, rides on it instead of walking the tree again).
class VarVisitor {
 public:
  virtual void Visit(Node* var) = 0;

 protected:
  ~VarVisitor() = default;
};

// Writes m's bodies, joints (moved from the tree and completed), fixed frames, forces,
// contacts, shapes and outputs; frame state references retargeted to the flat frames.
void Emit(InstanceTree& tree, const Connections& sets, const std::vector<PendingWhen>& whens, Evaluator& eval,
          const SourcePlaces& places, Diagnostics& diags, flat::Mechanism* m, VarVisitor* visitor = nullptr);

// The when clauses (lang/elab_when.cpp): conditions as indicators, reinit targets and values,
// terminate's message, into m->whens.
void EmitWhens(const std::vector<PendingWhen>& whens, Evaluator& eval, const SourcePlaces& places,
               Diagnostics& diags, flat::Mechanism* m);

// The experiment annotation `ex` of model `top` (StartTime, StopTime, Tolerance,
// Interval), evaluated in the root's scope, into m->experiment.
void EmitExperiment(const ast::Modification& ex, const ast::ClassDef* top, Node* root, Evaluator& eval,
                    Diagnostics& diags, flat::Mechanism* m);
// The speeds annotation `sp` of the model: kind = "joint" | "diagonal", order = {"joint", ...}
// (string literals; the joints must exist), into m->experiment. After Emit (the joints).
void EmitSpeeds(const ast::Modification& sp, Diagnostics& diags, flat::Mechanism* m);

// A shape primitive recorded for drawing (elab_shapes.cpp); and, once the bodies are
// emitted, every shape linked to its body.
void EmitShape(Node* n, Evaluator& eval, const SourcePlaces& places, Diagnostics& diags, flat::Mechanism* m);
void LinkShapes(flat::Mechanism* m);

}  // namespace kanesim::lang::elab
