// Modifiers, the phase that turns modifications into modification environments (Modelica
// 3.5 §7.2): built from the syntax with the scope and loop iterators they are evaluated
// in, merged with the outer one winning (`final` refuses outer modification), and sliced
// per element for arrays of components unless `each` is given. Mistakes are reported to
// `diags`; slicing evaluates array values through the evaluator.
#pragma once

#include <memory>
#include <string>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

class Evaluator;

// The modification `m` (null: none) written in `scope` under `iters`.
Mod BuildMod(const ast::Modification* m, Node* scope, const std::shared_ptr<const Iters>& iters,
             Diagnostics& diags);
// What a merge's messages name: a node's path, a dotted class name or a text, made only
// when a message needs it (a merge per instance would otherwise build a path each).
class MergeWhat {
 public:
  MergeWhat(const Node* node) : node_(node) {}                         // NOLINT: implicit by design
  MergeWhat(const std::vector<std::string>* parts) : parts_(parts) {}  // NOLINT
  MergeWhat(const std::string& text) : text_(&text) {}                 // NOLINT
  std::string Str() const;

 private:
  const Node* node_ = nullptr;
  const std::vector<std::string>* parts_ = nullptr;
  const std::string* text_ = nullptr;
};

// `inner` merged into `outer`, outer winning; `what` names the element for messages. The
// second form gives up `inner`: its values move instead of being copied.
void MergeMods(Mod& outer, const Mod& inner, MergeWhat what, Diagnostics& diags);
void MergeMods(Mod& outer, Mod&& inner, MergeWhat what, Diagnostics& diags);
// The second form for a modifier BuildMod made, which lists each of its keys once in
// `order` at every level by construction: the same result, without walking it to check.
void MergeBuiltMod(Mod& outer, Mod&& built, MergeWhat what, Diagnostics& diags);
// Element `index` (0-based) of an array of `count` components' modifier.
Mod SliceMod(const Mod& mod, int index, int count, Evaluator& eval, Diagnostics& diags);
// Evaluates the non-`each` values of an array component's modifier once, checking their
// leading size, so that slicing per element neither re-evaluates nor repeats errors.
void PreEvaluateMod(Mod& mod, int count, Evaluator& eval, Diagnostics& diags);

}  // namespace kanesim::lang::elab
