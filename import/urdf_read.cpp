// URDF XML -> Robot (urdf_model.h). expat parses (import/xml_doc.h); this file reads the
// elements the importer uses (http://wiki.ros.org/urdf/XML) and locates every mistake at its line.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "import/urdf_model.h"
#include "import/xml_doc.h"

namespace kanesim::import {

namespace {

using XMLElement = xml::Element;

class Reader {
 public:
  explicit Reader(Diags& diags) : d_(diags) {}

  // One number from `s` (surrounding blanks allowed); false when malformed.
  static bool ParseNumber(std::string_view s, double* out) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\n' || s.front() == '\r'))
      s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\n' || s.back() == '\r'))
      s.remove_suffix(1);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
    return ec == std::errc() && p == s.data() + s.size();
  }

  // Numbers of attribute `attr` of `e` (blank-separated), exactly out.size() of them, each
  // finite and at most kMaxMagnitude; false (with an error) otherwise or when absent and required.
  bool Numbers(const XMLElement* e, const char* attr, double* out, int n, bool required, bool non_negative = false) {
    const char* v = e->Attribute(attr);
    if (!v) {
      if (required) MissingAttr(e, attr);
      return !required;
    }
    std::string_view s(v);
    int count = 0;
    std::size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\n' || s[i] == '\r')) ++i;
      if (i >= s.size()) break;
      std::size_t j = i;
      while (j < s.size() && !(s[j] == ' ' || s[j] == '\t' || s[j] == '\n' || s[j] == '\r')) ++j;
      double x = 0;
      if (count >= n || !ParseNumber(s.substr(i, j - i), &x)) return BadNumber(e, attr, v, n);
      // Below the normal range (0 < |x| < 2.2e-308) too: the language refuses such literals
      // (L004), so the written model would not load; no robot's SI value is that small.
      const bool subnormal = x != 0 && std::fabs(x) < std::numeric_limits<double>::min();
      if (!std::isfinite(x) || std::fabs(x) > kMaxMagnitude || (non_negative && x < 0) || subnormal) {
        d_.Error(DiagCode::UrdfBadNumber, e->GetLineNum(), std::string(attr) + "=",
                 std::string("<") + e->Name() + "> " + attr + "=\"" + Clip(v) + "\": " +
                     (non_negative && x < 0 ? "a negative value"
                      : subnormal           ? "a number below the normal range of doubles (2.2e-308)"
                                            : "not a finite number of at most 1e9 in magnitude"),
                 non_negative && x < 0 ? "masses, lengths and radii are not negative"
                 : subnormal           ? "write 0 for zero; URDF values are in SI units (m, kg, kg m^2, rad)"
                                       : "URDF values are in SI units (m, kg, kg m^2, rad)");
        return false;
      }
      out[count++] = x;
      i = j;
    }
    if (count != n) return BadNumber(e, attr, v, n);
    return true;
  }

  bool Pose(const XMLElement* parent, struct Pose* pose) {
    const XMLElement* o = parent->FirstChildElement("origin");
    if (!o) return true;
    bool ok = Numbers(o, "xyz", pose->xyz.data(), 3, false);  // both read: every mistake reported
    ok &= Numbers(o, "rpy", pose->rpy.data(), 3, false);
    return ok;
  }

  const char* Name(const XMLElement* e, const char* attr = "name") {
    const char* v = e->Attribute(attr);
    if (!v || !*v) {
      MissingAttr(e, attr);
      return nullptr;
    }
    return v;
  }

  void MissingAttr(const XMLElement* e, const char* attr) {
    d_.Error(DiagCode::UrdfMissing, e->GetLineNum(), std::string("<") + e->Name(),
             std::string("<") + e->Name() + "> needs a non-empty attribute '" + attr + "'");
  }

  static std::string Clip(const char* v) {
    std::string s(v);
    return s.size() > 40 ? s.substr(0, 40) + "..." : s;
  }

  bool BadNumber(const XMLElement* e, const char* attr, const char* v, int n) {
    d_.Error(DiagCode::UrdfBadNumber, e->GetLineNum(), std::string(attr) + "=",
             std::string("<") + e->Name() + "> " + attr + "=\"" + Clip(v) + "\" is not " +
                 (n == 1 ? "a number" : std::to_string(n) + " numbers separated by blanks"),
             n == 3 ? "for example " + std::string(attr) + "=\"0 0 0.1\"" : "");
    return false;
  }

  bool Inertial(const XMLElement* e, struct Inertial* in) {
    bool ok = Pose(e, &in->origin);
    const XMLElement* m = e->FirstChildElement("mass");
    if (!m) {
      d_.Error(DiagCode::UrdfMissing, e->GetLineNum(), "<inertial", "<inertial> needs a <mass value=...>");
      return false;
    }
    ok &= Numbers(m, "value", &in->mass, 1, true, true);
    if (const XMLElement* i = e->FirstChildElement("inertia")) {
      double* f[6] = {&in->ixx, &in->ixy, &in->ixz, &in->iyy, &in->iyz, &in->izz};
      const char* names[6] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
      for (int k = 0; k < 6; ++k) ok &= Numbers(i, names[k], f[k], 1, false);
    }
    return ok;
  }

  bool Geometry(const XMLElement* g, Visual* v) {
    if (const XMLElement* b = g->FirstChildElement("box")) {
      v->shape = Shape::kBox;
      return Numbers(b, "size", v->size.data(), 3, true, true);
    }
    if (const XMLElement* c = g->FirstChildElement("cylinder")) {
      v->shape = Shape::kCylinder;
      bool ok = Numbers(c, "radius", &v->radius, 1, true, true);
      ok &= Numbers(c, "length", &v->length, 1, true, true);
      return ok;
    }
    if (const XMLElement* s = g->FirstChildElement("sphere")) {
      v->shape = Shape::kSphere;
      return Numbers(s, "radius", &v->radius, 1, true, true);
    }
    if (const XMLElement* m = g->FirstChildElement("mesh")) {
      v->shape = Shape::kMesh;
      const char* file = Name(m, "filename");
      if (!file) return false;
      v->mesh = file;
      return Numbers(m, "scale", v->scale.data(), 3, false);  // negative: mirrored
    }
    d_.Error(DiagCode::UrdfMissing, g->GetLineNum(), "<geometry",
             "<geometry> needs one of <box>, <cylinder>, <sphere> or <mesh>");
    return false;
  }

  // "#rrggbb" of a <color rgba="r g b a">, "" when absent or malformed (a note then).
  std::string Color(const XMLElement* material) {
    const XMLElement* c = material ? material->FirstChildElement("color") : nullptr;
    double rgba[4];
    if (!c || !Numbers(c, "rgba", rgba, 4, false)) return "";
    if (!c->Attribute("rgba")) return "";
    char buf[8];
    auto byte = [](double x) { return static_cast<int>(std::lround(std::fmin(1.0, std::fmax(0.0, x)) * 255)); };
    std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(rgba[0]), byte(rgba[1]), byte(rgba[2]));
    return buf;
  }

  bool Visual(const XMLElement* e, struct Visual* v) {
    v->line = e->GetLineNum();
    bool ok = Pose(e, &v->origin);
    const XMLElement* g = e->FirstChildElement("geometry");
    if (!g) {
      d_.Error(DiagCode::UrdfMissing, e->GetLineNum(), "<visual", "<visual> needs a <geometry>");
      return false;
    }
    ok &= Geometry(g, v);
    if (const XMLElement* m = e->FirstChildElement("material")) {
      v->color = Color(m);
      const char* name = m->Attribute("name");
      if (v->color.empty() && name && materials_.count(name)) v->color = materials_[name];
    }
    return ok;
  }

  bool Link(const XMLElement* e, struct Link* link) {
    link->line = e->GetLineNum();
    const char* name = Name(e);
    if (!name) return false;
    link->name = name;
    bool ok = true;
    if (const XMLElement* in = e->FirstChildElement("inertial")) {
      link->has_inertial = true;
      ok &= Inertial(in, &link->inertial);
    }
    for (const XMLElement* v = e->FirstChildElement("visual"); v; v = v->NextSiblingElement("visual")) {
      link->visuals.emplace_back();
      ok &= Visual(v, &link->visuals.back());
    }
    for (const XMLElement* c = e->FirstChildElement("collision"); c; c = c->NextSiblingElement("collision"))
      ++link->num_collisions;
    return ok;
  }

  bool Type(const XMLElement* e, JointType* t) {
    static const std::map<std::string, JointType> kTypes = {
        {"revolute", JointType::kRevolute}, {"continuous", JointType::kContinuous},
        {"prismatic", JointType::kPrismatic}, {"fixed", JointType::kFixed},
        {"floating", JointType::kFloating}, {"planar", JointType::kPlanar}};
    const char* v = Name(e, "type");
    if (!v) return false;
    auto it = kTypes.find(v);
    if (it == kTypes.end()) {
      d_.Error(DiagCode::UrdfBadJointType, e->GetLineNum(), "type=",
               std::string("joint type '") + Clip(v) + "' is not a URDF joint type",
               "revolute, continuous, prismatic, fixed, floating or planar");
      return false;
    }
    *t = it->second;
    return true;
  }

  bool LinkRef(const XMLElement* e, const char* tag, std::string* out) {
    const XMLElement* c = e->FirstChildElement(tag);
    if (!c) {
      d_.Error(DiagCode::UrdfMissing, e->GetLineNum(), "<joint",
               std::string("<joint> needs a <") + tag + " link=\"...\"/>");
      return false;
    }
    const char* v = Name(c, "link");
    if (v) *out = v;
    return v != nullptr;
  }

  bool Joint(const XMLElement* e, struct Joint* j) {
    j->line = e->GetLineNum();
    const char* name = Name(e);
    if (name) j->name = name;
    bool ok = name && Type(e, &j->type);
    ok &= LinkRef(e, "parent", &j->parent);
    ok &= LinkRef(e, "child", &j->child);
    ok &= Pose(e, &j->origin);
    if (const XMLElement* a = e->FirstChildElement("axis")) {
      ok &= Numbers(a, "xyz", j->axis.data(), 3, false);
      // Fixed and floating joints have no axis; some files give theirs as zero.
      const bool uses_axis = j->type != JointType::kFixed && j->type != JointType::kFloating;
      if (ok && uses_axis && j->axis == Vec3{0, 0, 0}) {
        d_.Error(DiagCode::UrdfBadNumber, a->GetLineNum(), "xyz=", "<axis xyz=\"0 0 0\"> has no direction",
                 "give the joint axis as a non-zero vector, e.g. xyz=\"0 0 1\"");
        ok = false;
      }
    }
    if (const XMLElement* l = e->FirstChildElement("limit")) {
      j->has_limit = true;
      ok &= Numbers(l, "lower", &j->lower, 1, false);
      ok &= Numbers(l, "upper", &j->upper, 1, false);
      ok &= Numbers(l, "effort", &j->effort, 1, false);
      ok &= Numbers(l, "velocity", &j->velocity, 1, false);
    }
    if (const XMLElement* dyn = e->FirstChildElement("dynamics")) {
      ok &= Numbers(dyn, "damping", &j->damping, 1, false, true);
      ok &= Numbers(dyn, "friction", &j->friction, 1, false, true);
    }
    if (const XMLElement* m = e->FirstChildElement("mimic")) {
      j->has_mimic = true;
      const char* leader = Name(m, "joint");
      if (leader) j->mimic_joint = leader;
      ok &= leader != nullptr;
      ok &= Numbers(m, "multiplier", &j->multiplier, 1, false);
      ok &= Numbers(m, "offset", &j->offset, 1, false);
    }
    return ok;
  }

  void Materials(const XMLElement* robot) {
    for (const XMLElement* m = robot->FirstChildElement("material"); m; m = m->NextSiblingElement("material")) {
      const char* name = m->Attribute("name");
      std::string c = Color(m);
      if (name && !c.empty()) materials_[name] = c;
    }
  }

 private:
  Diags& d_;
  std::map<std::string, std::string> materials_;
};

// The line of the first "<!ENTITY" in text, 0 when there is none.
int EntityLine(std::string_view text) {
  std::size_t at = text.find("<!ENTITY");
  if (at == std::string_view::npos) return 0;
  int line = 1;
  for (std::size_t i = 0; i < at; ++i) line += text[i] == '\n';
  return line;
}

}  // namespace

bool ReadUrdf(std::string_view text, Robot* robot, Diags& diags) {
  // A file that declares entities expects them expanded (the "billion laughs" is one), so it
  // is refused rather than read differently; the parser refuses any the text search misses.
  xml::Document doc;
  const int entity_line = EntityLine(text);
  const bool parsed = !entity_line && doc.Parse(text);
  if (entity_line || doc.DeclaresEntities()) {
    diags.Error(DiagCode::UrdfEntities, entity_line ? entity_line : std::max(1, doc.ErrorLine()), "<!ENTITY",
                "the file declares XML entities, which are not expanded", "write the values out; URDF files need no DTD");
    return false;
  }
  if (!parsed) {
    diags.Error(DiagCode::UrdfBadXml, std::max(1, doc.ErrorLine()), doc.ErrorNeedle(), doc.ErrorText(),
                "check the element on this line and the lines just before it");
    return false;
  }
  const XMLElement* root = doc.Root();
  if (!root || std::string_view(root->Name()) != "robot") {
    diags.Error(DiagCode::UrdfNotUrdf, root ? root->GetLineNum() : 1, root ? "<" : "",
                std::string("the root element is <") + (root ? root->Name() : "") + ">, not <robot>",
                "a URDF file holds one <robot name=\"...\"> element (a xacro file must be expanded first)");
    return false;
  }
  Reader reader(diags);
  robot->line = root->GetLineNum();
  const char* name = reader.Name(root);
  robot->name = name ? name : "robot";
  reader.Materials(root);
  int count = 0;
  for (const XMLElement* e = root->FirstChildElement(); e; e = e->NextSiblingElement()) {
    std::string_view tag = e->Name();
    if (tag != "link" && tag != "joint") continue;
    if (++count > kMaxElements) {
      diags.Error(DiagCode::UrdfTooLarge, e->GetLineNum(), "<",
                  "more than " + std::to_string(kMaxElements) + " links and joints", "split the robot or check the file");
      return false;
    }
    if (tag == "link") {
      robot->links.emplace_back();
      reader.Link(e, &robot->links.back());
    } else {
      robot->joints.emplace_back();
      reader.Joint(e, &robot->joints.back());
    }
  }
  return diags.NumErrors() == 0;
}

}  // namespace kanesim::import
