// Lookup, the elaborator's first phase: names resolved in the class tree. The registry
// of classes by qualified name (the program's files, and the embedded library's units
// registered when a lookup first names them), Modelica's lookup of a class name from a
// scope (nested classes, imports, `within`, the library), annotations through extends,
// the model to elaborate and the user's imports.
#pragma once

#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

struct ClassInfo {
  const ast::ClassDef* cls;
  const ast::StoredDefinition* file;
  std::string qualified;
};

class ClassLookup {
 public:
  // Registers the program's files; `diags` receives a library unit's own diagnostics.
  ClassLookup(const Program& program, Diagnostics& diags);

  // The class `parts` names, looked up from class `from` (null: from the top level).
  const ast::ClassDef* FindClass(const std::vector<std::string>& parts, const ast::ClassDef* from) const;
  // The registry's entry for a qualified name; null when no class has it. Whatever part
  // of the library is registered, the answer is the one a registry of the whole library
  // would give.
  const ClassInfo* LookupClass(const std::string& q) const;
  // Every class's qualified name (the whole library registered first), for hints.
  std::vector<std::string> AllNames() const;
  // The qualified name of a registered class (its own name when not registered).
  std::string QualifiedName(const ast::ClassDef* c) const;
  // The modification `key` of cls's annotation, or of its bases' (breadth first).
  const ast::Modification* FindAnnotation(const ast::ClassDef* cls, const std::string& key) const;

  // The model named by `model`, else the last non-partial model of the user's file; null
  // after a diagnostic (or with no file).
  const ast::ClassDef* PickModel(const std::string& model);
  // Every import of the user's file must name something; false after a diagnostic.
  bool CheckImports(const ast::StoredDefinition& f);

 private:
  // FindClass's lookup itself: the scope's nested classes and imports, then the registry.
  const ast::ClassDef* Resolve(const std::vector<std::string>& parts, const ast::ClassDef* from) const;
  const ast::StoredDefinition* FileOf(const ast::ClassDef* c) const;
  void LoadWholeLibrary() const;
  void Register(const ast::ClassDef* c, const std::string& prefix, const ast::StoredDefinition* file) const;
  bool LoadLibraryClass(const std::string& q) const;
  void LoadUnit(int u) const;
  void CheckImport(const std::string& q, bool wildcard, Span span);

  const Program& program_;
  Diagnostics& diags_;
  const Library* library_;  // null when the library is in program_.files
  // mutable: a lookup (const) registers the library's classes it is the first to name.
  mutable std::vector<char> unit_loaded_;  // per library unit
  mutable std::map<std::string, ClassInfo> classes_;  // qualified name -> class
  mutable std::unordered_map<const ast::ClassDef*, const ast::StoredDefinition*> file_of_;
  mutable std::unordered_map<const ast::ClassDef*, std::string> qualified_of_;

  // FindClass's answers by (scope, name), each found once: a model's components name a few
  // classes many times over, and a lookup walks the scope's elements and the registry. An
  // answer never changes: the registry answers as if the whole library were registered.
  struct FoundKey {
    const ast::ClassDef* from;
    std::vector<std::string> parts;
  };
  struct FoundRef {  // a key to look up without copying the name
    const ast::ClassDef* from;
    const std::vector<std::string>& parts;
  };
  struct FoundHash {
    using is_transparent = void;
    size_t operator()(const FoundKey& k) const { return Of(k.from, k.parts); }
    size_t operator()(const FoundRef& k) const { return Of(k.from, k.parts); }
    static size_t Of(const ast::ClassDef* from, const std::vector<std::string>& parts);
  };
  struct FoundEq {
    using is_transparent = void;
    template <class A, class B>
    bool operator()(const A& a, const B& b) const {
      return a.from == b.from && a.parts == b.parts;
    }
  };
  mutable std::unordered_map<FoundKey, const ast::ClassDef*, FoundHash, FoundEq> found_;
};

}  // namespace kanesim::lang::elab
