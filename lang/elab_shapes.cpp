// Shapes: what a stdlib part looks like, recorded for drawing (flat::Shape). A class
// annotated __kanesim(primitive = "shape", kind = K) names its sizes by parameters (the
// table below) and contains a Body named `body` that carries its mass properties.
#include "lang/elab_emit.h"

#include <cctype>
#include <map>

#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

namespace {

struct ShapeRow {
  const char* kind;               // the annotation's kind
  flat::ShapeKind shape;
  const char* size[3];            // parameters giving flat::Shape::size (null: none)
};

const ShapeRow kShapeRows[] = {
    {"rod", flat::ShapeKind::Rod, {"L", nullptr, nullptr}},
    {"box", flat::ShapeKind::Box, {"lx", "ly", "lz"}},
    {"cylinder", flat::ShapeKind::Cylinder, {"length", "radius", nullptr}},
    {"sphere", flat::ShapeKind::Sphere, {"radius", nullptr, nullptr}},
    {"mesh", flat::ShapeKind::Mesh, {"scale", nullptr, nullptr}},
    // BodyShape: a Body with given mass properties drawn as a mesh (no `volume` parameter:
    // the mesh is read for drawing only, cli/scene.cpp LoadVisualMesh).
    {"visual_mesh", flat::ShapeKind::Mesh, {"scale", nullptr, nullptr}},
};

// The colour names a shape's `color` accepts, as sRGB.
const std::pair<const char*, const char*> kColorNames[] = {
    {"red", "#cc3322"},    {"green", "#339944"}, {"blue", "#3366cc"},  {"yellow", "#e6c619"},
    {"orange", "#e67e22"}, {"purple", "#8e44ad"}, {"cyan", "#1fa2b5"},  {"grey", "#8c8c91"},
    {"gray", "#8c8c91"},   {"steel", "#a9b0b8"},  {"black", "#1a1a1a"}, {"white", "#f2f2f2"},
};

// "#rrggbb" (any case) or a name, as lower-case "#rrggbb"; "" when it is neither.
std::string NormalColor(const std::string& c) {
  for (const auto& [name, hex] : kColorNames)
    if (c == name) return hex;
  if (c.size() != 7 || c[0] != '#') return "";
  std::string out = "#";
  for (size_t i = 1; i < 7; ++i) {
    const char h = static_cast<char>(std::tolower(static_cast<unsigned char>(c[i])));
    if (!std::isxdigit(static_cast<unsigned char>(h))) return "";
    out += h;
  }
  return out;
}

}  // namespace

void EmitShape(Node* n, Evaluator& eval, const SourcePlaces& places, Diagnostics& diags, flat::Mechanism* m) {
  const ShapeRow* row = nullptr;
  for (const ShapeRow& r : kShapeRows)
    if (n->prim_kind == r.kind) row = &r;
  if (!row) {
    diags.Error(DiagCode::BadPrimitive, n->cls ? n->cls->name_span : Span{},
                "unknown shape kind '" + n->prim_kind + "'");
    return;
  }
  flat::Shape s;
  s.name = n->Path();
  s.kind = row->shape;
  s.loc = places.Loc(n->decl ? n->decl->name_span : Span{});
  for (int i = 0; i < 3; ++i) {
    if (!row->size[i]) continue;
    Node* c = n->Child(row->size[i]);
    if (!c || c->kind != Node::kVar) {
      diags.Error(DiagCode::BadPrimitive, n->cls ? n->cls->name_span : Span{},
                   "shape '" + n->Path() + "' lacks '" + row->size[i] + "'");
      return;
    }
    Value v = eval.GetVar(c, c->decl ? c->decl->name_span : Span{});
    if (!v.valid || v.type == VType::String || v.elements.size() != 1) return;
    s.size[static_cast<size_t>(i)] = v.elements[0];
  }
  if (s.kind == flat::ShapeKind::Mesh) {
    Node* f = n->Child("file");
    if (!f || f->kind != Node::kVar) return;
    Value v = eval.GetVar(f, Span{});
    if (!v.valid || v.type != VType::String || v.strings.size() != 1) return;
    if (v.strings[0].empty() && n->prim_kind == "visual_mesh") return;  // a BodyShape without a file: its inertia box
    Span origin = f->decl ? f->decl->name_span : Span{};
    const ModValue* b = f->Modifiers().value ? &*f->Modifiers().value : f->eq_binding ? &*f->eq_binding : nullptr;
    if (b) origin = b->expr ? eval.ValueOrigin(*b->expr, Ctx{b->scope, b->iters.get()}) : b->span;
    s.mesh_file = eval.MeshPath(v.strings[0], origin);
  }
  if (Node* c = n->Child("color"); c && c->kind == Node::kVar) {
    Value v = eval.GetVar(c, Span{});
    if (v.valid && v.type == VType::String && v.strings.size() == 1 && !v.strings[0].empty()) {
      s.color = NormalColor(v.strings[0]);
      if (s.color.empty()) {
        const Span at = c->Modifiers().value ? c->Modifiers().value->span : c->decl ? c->decl->name_span : Span{};
        std::vector<std::string> names;
        for (const auto& [name, hex] : kColorNames) names.push_back(name);
        auto& d = diags.Error(DiagCode::BadValue, at, "'" + v.strings[0] + "' is not a colour");
        const std::string best = ClosestName(v.strings[0], names);
        d.hint = "write \"#rrggbb\" or one of red, green, blue, yellow, orange, purple, cyan, grey, steel, black, "
                 "white" + (best.empty() ? std::string() : " (did you mean \"" + best + "\"?)");
      }
    }
  }
  if (Node* vis = n->Child("visual"); vis && vis->kind == Node::kVar) {
    Value v = eval.GetVar(vis, Span{});
    double x = 1;
    if (v.valid && v.type == VType::Boolean &&
        eval.Structural(v, vis->decl ? vis->decl->name_span : Span{}, &x, "visual"))
      s.visual = x != 0;
  }
  m->shapes.push_back(std::move(s));
}

void LinkShapes(flat::Mechanism* m) {
  if (m->shapes.empty()) return;
  std::map<std::string, int> body_of;
  for (size_t i = 0; i < m->bodies.size(); ++i) body_of[m->bodies[i].name] = static_cast<int>(i);
  for (flat::Shape& s : m->shapes) {
    auto it = body_of.find(s.name + ".body");
    if (it != body_of.end()) s.body = it->second;
  }
}

}  // namespace kanesim::lang::elab
