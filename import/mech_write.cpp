// Robot (a checked tree) -> .mech text. One component per URDF element, named as in the URDF:
//   link   -> Body NAME(m, r_CM, I) at the link frame; a massless link -> Frame NAME
//   joint  -> FixedRPY / FixedTranslation NAME_origin (its <origin>), then the joint NAME;
//             a fixed joint is the FixedRPY / FixedTranslation NAME itself (the child link's
//             frame is then fixed in the parent's body: massless links merge into it)
//   visual -> Box / Cylinder / Sphere / BodyShape LINK_visual (m = 0: looks only)
// The inertia is rotated here, exactly as URDF defines it: I_L = R_LC I_C R_LCᵀ with R_LC
// from the <inertial><origin rpy>, the centre of mass at its xyz (docs/import.md).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>
#include <unordered_map>

#include "import/diagnostics.h"
#include "import/import.h"
#include "import/urdf_model.h"

namespace kanesim::import {

namespace {

namespace fs = std::filesystem;
using Mat3 = std::array<std::array<double, 3>, 3>;

// The shortest text that reads back as the same double. A computed value below the normal
// range (an inertia rotated by a tiny angle: 1e-300 kg m^2 times sin 1e-10) is written as 0,
// an absolute change below 2.3e-308: the language refuses such literals (L004).
std::string Num(double x) {
  if (std::fabs(x) < std::numeric_limits<double>::min()) return "0";  // also -0
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

// Whether a byte may stand in .mech text as it is: printable ASCII. Control characters (a
// newline would end a // comment and make the rest code) and bytes of other encodings (the
// language refuses invalid UTF-8 and text-reordering characters in strings) may not.
bool PlainByte(char c) { return static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f; }

// A URDF string as a comment or description shows it: other bytes as '?', at most 120 characters.
std::string Shown(const std::string& s) {
  std::string out = s.size() > 120 ? s.substr(0, 117) + "..." : s;
  for (char& c : out)
    if (!PlainByte(c)) c = '?';
  return out;
}

std::string Vec(const Vec3& v) { return "{" + Num(v[0]) + ", " + Num(v[1]) + ", " + Num(v[2]) + "}"; }

std::string Matrix(const Mat3& m) {
  std::string s = "[";
  for (int i = 0; i < 3; ++i)
    s += Num(m[i][0]) + ", " + Num(m[i][1]) + ", " + Num(m[i][2]) + (i < 2 ? "; " : "]");
  return s;
}

std::string Quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += PlainByte(c) ? c : '?';
  }
  return out + "\"";
}

// R = Rz(yaw) Ry(pitch) Rx(roll) (URDF; the same product as stdlib FixedRPY).
Mat3 RotationRpy(const Vec3& rpy) {
  const double cr = std::cos(rpy[0]), sr = std::sin(rpy[0]), cp = std::cos(rpy[1]), sp = std::sin(rpy[1]),
               cy = std::cos(rpy[2]), sy = std::sin(rpy[2]);
  return {{{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
           {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
           {-sp, cp * sr, cp * cr}}};
}

// I_L = R I_C Rᵀ, then made exactly symmetric (the two triangles differ in rounding only).
Mat3 RotatedInertia(const Inertial& in) {
  const Mat3 ic = {{{in.ixx, in.ixy, in.ixz}, {in.ixy, in.iyy, in.iyz}, {in.ixz, in.iyz, in.izz}}};
  if (in.origin.rpy == Vec3{0, 0, 0}) return ic;
  const Mat3 r = RotationRpy(in.origin.rpy);
  Mat3 ri{}, out{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) ri[i][j] += r[i][k] * ic[k][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) out[i][j] += ri[i][k] * r[j][k];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < i; ++j) out[i][j] = out[j][i] = 0.5 * (out[i][j] + out[j][i]);
  return out;
}

// A unit vector perpendicular to n (the Planar joint's in-plane x): the coordinate axis
// least aligned with n, less its component along n.
Vec3 Perpendicular(const Vec3& n) {
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(n[i]) < std::fabs(n[k])) k = i;
  Vec3 e{0, 0, 0};
  e[k] = 1;
  const double d = n[k] / (len * len);
  for (int i = 0; i < 3; ++i) e[i] -= d * n[i];
  const double el = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  for (double& x : e) x /= el;
  return e;
}

const std::set<std::string>& Reserved() {
  static const std::set<std::string> kReserved = {
      // keywords (lang/lexer.h) and built-in names
      "algorithm", "and", "annotation", "block", "class", "connect", "connector", "constant", "discrete", "each",
      "else", "elseif", "encapsulated", "end", "equation", "extends", "false", "final", "for", "function", "if",
      "import", "in", "initial", "inner", "input", "loop", "model", "not", "or", "outer", "output", "package",
      "parameter", "partial", "protected", "public", "record", "redeclare", "replaceable", "then", "true", "type",
      "when", "while", "within", "pi", "time", "der", "Real", "Integer", "Boolean", "String", "Kanesim",
      // the standard library's classes the model names
      "World", "Body", "Frame", "FixedRPY", "FixedTranslation", "Revolute", "Prismatic", "Planar", "FreeMotion",
      "Box", "Cylinder", "Sphere", "BodyShape", "JointCoupling"};
  return kReserved;
}

class Writer {
 public:
  Writer(const Robot& robot, const Options& options, const std::string& path, Diags& diags)
      : r_(robot), o_(options), path_(path), d_(diags) {}

  Result Write() {
    Result out;
    used_.insert("world");
    out.model_name = Unique(r_.name, nullptr);
    link_frame_.assign(r_.links.size(), "");
    joint_name_.assign(r_.joints.size(), "");
    decl_ << "  World world(g = {0, 0, -9.81}) \"URDF: z up, standard gravity\";\n";
    for (const Joint& j : r_.joints) coupled_ = coupled_ || (o_.mimic && j.has_mimic);
    if (coupled_) MimicGroups();
    Root();
    for (int j : r_.order) JointAndChild(j);
    if (o_.mimic) Mimics();
    Notes();
    std::ostringstream text;
    text << "// Imported by `kanesim import` from " << Shown(fs::path(path_).filename().string()) << " (URDF robot '"
         << Shown(r_.name) << "'). docs/import.md says how each element maps.\n";
    for (const std::string& line : header_) text << "// " << line << "\n";
    text << "model " << out.model_name << " " << Quoted("URDF robot '" + Shown(r_.name) + "'") << "\n"
         << decl_.str() << "equation\n"
         << eq_.str() << "end " << out.model_name << ";\n";
    out.mech = text.str();
    for (std::size_t l = 0; l < r_.links.size(); ++l) out.link_frames.emplace_back(r_.links[l].name, link_frame_[l]);
    for (std::size_t j = 0; j < r_.joints.size(); ++j) out.joints.emplace_back(r_.joints[j].name, joint_name_[j]);
    out.ok = true;
    return out;
  }

 private:
  // A valid, unused identifier from a URDF name; the declaration gets `*comment` saying so
  // when it differs.
  std::string Unique(const std::string& urdf, std::string* comment) {
    std::string s;
    for (char c : urdf) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '_') ? c : '_';
    if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) s = "_" + s;
    if (s.size() > 200) s.resize(200);
    if (Reserved().count(s)) s += "_";
    std::string base = s;
    for (int k = 2; used_.count(s); ++k) s = base + "_" + std::to_string(k);
    used_.insert(s);
    if (comment && s != urdf) *comment = " (URDF name '" + Shown(urdf) + "')";
    return s;
  }

  // A component declaration with its description string.
  void Declare(const std::string& type, const std::string& name, const std::string& mods, const std::string& what) {
    decl_ << "  " << type << " " << name;
    if (!mods.empty()) decl_ << "(" << mods << ")";
    decl_ << " " << Quoted(what) << ";\n";
  }

  void Connect(const std::string& a, const std::string& b) { eq_ << "  connect(" << a << ", " << b << ");\n"; }

  std::string Where(int line) const { return Shown(fs::path(path_).filename().string()) + ":" + std::to_string(line); }

  // A link: its Body (or Frame when massless) and its visuals; its frame is then known.
  // A link: its Body (or Frame when massless) and its visuals; its frame is then known. A
  // link with <visual>s is a BodyShape, drawn by them instead of its inertia box: the mesh
  // itself when it is the one visual, at the link frame; whether a mesh was found changes no name.
  void LinkComponents(int l, const std::string& frame_from) {
    const Link& link = r_.links[static_cast<std::size_t>(l)];
    std::string renamed;
    const bool massive = link.has_inertial && link.inertial.mass > 0;
    std::vector<std::string> files(link.visuals.size());
    for (std::size_t k = 0; k < link.visuals.size(); ++k)
      if (link.visuals[k].shape == Shape::kMesh) files[k] = MeshFile(link.visuals[k]);
    const Visual* one = link.visuals.size() == 1 ? &link.visuals[0] : nullptr;
    const bool merged = massive && one && one->shape == Shape::kMesh && !files[0].empty() &&
                        one->origin.IsIdentity() && UniformScale(*one);
    if (!massive && frame_from == "world.frame_b") {
      link_frame_[static_cast<std::size_t>(l)] = frame_from;  // the world itself
      decl_ << "  // link '" << Shown(link.name) << "' (" << Where(link.line) << "): the world frame\n";
    } else if (massive) {
      const std::string name = Unique(link.name, &renamed);
      const Inertial& in = link.inertial;
      decl_ << "  // link '" << Shown(link.name) << "' (" << Where(link.line) << ")" << renamed << "\n";
      std::string mods =
          "m = " + Num(in.mass) + ", r_CM = " + Vec(in.origin.xyz) + ",\n       I = " + Matrix(RotatedInertia(in));
      if (merged)
        mods += ",\n       file = " + Quoted(files[0]) + ", scale = " + Num(one->scale[0]) +
                (one->color.empty() ? "" : ", color = " + Quoted(one->color));
      else if (!link.visuals.empty())
        mods += ", visual = false";
      Declare(link.visuals.empty() ? "Body" : "BodyShape", name, mods,
              "link '" + Shown(link.name) + "'" + (!merged && !link.visuals.empty() ? ", drawn by its visuals" : ""));
      link_frame_[static_cast<std::size_t>(l)] = name + ".frame_a";
      Connect(frame_from, name + ".frame_a");
    } else {
      const std::string name = Unique(link.name, &renamed);
      decl_ << "  // link '" << Shown(link.name) << "' (" << Where(link.line) << ")" << renamed
            << ": massless, a frame of its parent's body\n";
      Declare("Frame", name, "", "link '" + Shown(link.name) + "' (no mass)");
      link_frame_[static_cast<std::size_t>(l)] = name;
      Connect(frame_from, name);
    }
    if (!merged)
      for (std::size_t k = 0; k < link.visuals.size(); ++k) VisualComponents(link, link.visuals[k], l, files[k]);
    collisions_ += link.num_collisions;
  }

  static bool UniformScale(const Visual& v) {
    return v.scale[0] > 0 && v.scale[1] == v.scale[0] && v.scale[2] == v.scale[0];
  }

  // The file a mesh visual names, as the .mech file will name it; "" (with a note) when no
  // search path holds it.
  std::string MeshFile(const Visual& v) {
    std::string file = ResolveMesh(v.mesh);
    if (!file.empty() && !std::all_of(file.begin(), file.end(), PlainByte)) {
      d_.Note(v.line, "mesh '" + Shown(file) + "' has a name of other than printable ASCII characters: left out");
      ++missing_meshes_;
      return "";
    }
    if (file.empty()) {
      ++missing_meshes_;
      d_.Note(v.line, "mesh '" + Shown(v.mesh) + "' not found: the visual is left out (the dynamics do not need it)",
              "<mesh");
      return "";
    }
    if (!UniformScale(v))
      d_.Note(v.line, "mesh scale " + Vec(v.scale) + " is not uniform and positive: drawn at " +
                          Num(std::fabs(v.scale[0])) + " in every direction, unmirrored");
    if (o_.mesh_base_dir.empty()) return file;
    std::error_code ec;
    const fs::path abs = fs::absolute(file, ec);
    fs::path rel = fs::relative(abs, fs::absolute(o_.mesh_base_dir, ec), ec);
    // Relative to the .mech file's folder, unless that climbs further than the absolute name.
    if (!ec && !rel.empty()) file = rel.string().size() <= abs.string().size() ? rel.string() : abs.string();
    return file;
  }

  void Root() {
    if (!o_.floating) {
      LinkComponents(r_.root, "world.frame_b");
      return;
    }
    const std::string name = Unique("root_joint", nullptr);
    decl_ << "  // --floating: the root link moves freely (q = {x, y, z, quaternion w, x, y, z})\n";
    Declare("FreeMotion", name, "", "free base");
    Connect("world.frame_b", name + ".frame_a");
    LinkComponents(r_.root, name + ".frame_b");
  }

  // A fixed frame `name` from `from`: FixedRPY, or FixedTranslation when it turns nothing.
  std::string FixedFrame(const std::string& name, const Pose& p, const std::string& from, const std::string& what) {
    if (p.rpy == Vec3{0, 0, 0})
      Declare("FixedTranslation", name, "r = " + Vec(p.xyz), what);
    else
      Declare("FixedRPY", name, "r = " + Vec(p.xyz) + ", rpy = " + Vec(p.rpy), what);
    Connect(from, name + ".frame_a");
    return name + ".frame_b";
  }

  static bool OneCoordinate(const Joint& j) {
    return j.type == JointType::kRevolute || j.type == JointType::kContinuous || j.type == JointType::kPrismatic;
  }
  // A <mimic> follower whose friction its root's exact friction holds (MimicGroups).
  bool Reflected(const Joint& j) const {
    return coupled_ && root_[static_cast<std::size_t>(&j - r_.joints.data())] >= 0;
  }

  // A joint's <limit> as a range that can stop it: a revolute or prismatic joint's.
  static bool Limited(const Joint& j) {
    return j.has_limit && (j.type == JointType::kRevolute || j.type == JointType::kPrismatic);
  }

  // <mimic> chains: each coupled joint's root leader R and q = a q_R + b. A group's limits
  // all become end stops of R, the intersection of their ranges mapped to q_R: stops on the
  // follower too would be rows dependent on the leader's where the ranges agree (the impulse
  // that holds both is not unique), and the follower keeps q = a q_R + b within its range.
  void MimicGroups() {
    const std::size_t n = r_.joints.size();
    root_.assign(n, -1);
    for (std::size_t j = 0; j < n; ++j) {
      double a = 1, b = 0;
      int at = static_cast<int>(j);
      for (std::size_t steps = 0; steps <= n && r_.joints[static_cast<std::size_t>(at)].has_mimic; ++steps) {
        const Joint& x = r_.joints[static_cast<std::size_t>(at)];
        b += a * x.offset, a *= x.multiplier;  // q = a (m q_l + c) + b
        at = x.mimic_leader;
      }
      if (r_.joints[static_cast<std::size_t>(at)].has_mimic) continue;  // a cycle: the compiler says so
      if (at == static_cast<int>(j)) continue;
      root_[j] = at;
      const Joint& x = r_.joints[j];
      // Its constant friction reflected onto the root: tau_f dq_f = (a tau_f) dq_R with
      // |tau_f| <= c_f, and sign(u_f) = sign(a u_R) while they slide together.
      if (x.friction != 0 && OneCoordinate(x)) friction_[at] += std::abs(a) * x.friction;
      if (!Limited(x) || !o_.stops || a == 0 || !(x.lower < x.upper)) continue;
      double lo = (x.lower - b) / a, hi = (x.upper - b) / a;
      if (lo > hi) std::swap(lo, hi);
      Range& g = group_[at];
      if (g.members == 0 && Limited(r_.joints[static_cast<std::size_t>(at)]) &&
          r_.joints[static_cast<std::size_t>(at)].lower < r_.joints[static_cast<std::size_t>(at)].upper) {
        g.lower = r_.joints[static_cast<std::size_t>(at)].lower, g.upper = r_.joints[static_cast<std::size_t>(at)].upper;
        g.members = 1;
      }
      g.lower = g.members == 0 ? lo : std::max(g.lower, lo);
      g.upper = g.members == 0 ? hi : std::min(g.upper, hi);
      ++g.members;
    }
  }

  // The range the joint's end stops hold, if it has stops: its own <limit> or, for a <mimic>
  // root, its group's (MimicGroups).
  bool StopRange(const Joint& j, double* lower, double* upper) const {
    if (!o_.stops || (j.type != JointType::kRevolute && j.type != JointType::kContinuous && j.type != JointType::kPrismatic))
      return false;
    const int ji = static_cast<int>(&j - r_.joints.data());
    if (coupled_ && root_[static_cast<std::size_t>(ji)] >= 0) return false;  // a follower: its root holds it
    if (auto g = group_.find(ji); g != group_.end()) {
      *lower = g->second.lower, *upper = g->second.upper;
      return *lower < *upper;
    }
    *lower = j.lower, *upper = j.upper;
    return Limited(j) && j.lower < j.upper;
  }
  bool Stops(const Joint& j) const {
    double lo = 0, hi = 0;
    return StopRange(j, &lo, &hi);
  }

  // The <limit> in the joint's comment, and what became of it (counted for the notes).
  std::string Limits(const Joint& j) {
    if (!j.has_limit) return "";
    std::string fate = "recorded";
    if (j.type == JointType::kRevolute || j.type == JointType::kPrismatic) {
      const int ji = static_cast<int>(&j - r_.joints.data());
      const int root = coupled_ ? root_[static_cast<std::size_t>(ji)] : -1;
      if (!o_.stops) fate = "recorded: --limits ignore", ++limits_;
      else if (!(j.lower < j.upper)) fate = "recorded: lower >= upper is no range", ++empty_ranges_;
      else if (root >= 0 && Stops(r_.joints[static_cast<std::size_t>(root)]))
        fate = "held by the end stops of '" + Shown(r_.joints[static_cast<std::size_t>(root)].name) + "' through the <mimic>", ++stops_;
      else if (Stops(j)) fate = group_.count(ji) ? "the end stops q_min, q_max, with its <mimic> followers'" : "the end stops q_min, q_max", ++stops_;
      else fate = "recorded: the <mimic> group's ranges have no common part", ++empty_ranges_;
    }
    return "; limit lower " + Num(j.lower) + " upper " + Num(j.upper) + " effort " + Num(j.effort) + " velocity " +
           Num(j.velocity) + " (" + fate + ")";
  }

  // The joint's end stops as modifiers; a start of q = 0 outside them moves onto the nearer
  // limit (the simulator refuses a start past a stop), with a note.
  std::string StopModifiers(const Joint& j) {
    double lower = 0, upper = 0;
    if (!StopRange(j, &lower, &upper)) return "";
    std::string mods = ", q_min = " + Num(lower) + ", q_max = " + Num(upper);
    if (0 < lower || 0 > upper) {
      const double start = 0 < lower ? lower : upper;
      mods += ", q(start = " + Num(start) + ")";
      d_.Note(j.line, "joint '" + Shown(j.name) + "': q = 0 is outside its " +
                          (group_.count(static_cast<int>(&j - r_.joints.data())) ? "<mimic> group's <limit>s " : "<limit> ") +
                          "[" + Num(lower) + ", " + Num(upper) + "]: it starts at " + Num(start) + ", on the nearer stop",
              "<limit");
    }
    return mods;
  }

  void JointAndChild(int ji) {
    const Joint& j = r_.joints[static_cast<std::size_t>(ji)];
    static const char* kTypeNames[] = {"revolute", "continuous", "prismatic", "fixed", "floating", "planar"};
    std::string renamed;
    const std::string parent = link_frame_[static_cast<std::size_t>(LinkIndex(j.parent))];
    const int child = LinkIndex(j.child);
    if (j.type == JointType::kFixed) {
      const std::string name = Unique(j.name, &renamed);
      decl_ << "  // joint '" << Shown(j.name) << "' (" << Where(j.line) << "): fixed" << renamed << IgnoredMimic(j)
            << "\n";
      joint_name_[static_cast<std::size_t>(ji)] = name;
      LinkComponents(child, FixedFrame(name, j.origin, parent, "joint '" + Shown(j.name) + "' (fixed)"));
      return;
    }
    std::string from = parent;
    const std::string name = Unique(j.name, &renamed);
    decl_ << "  // joint '" << Shown(j.name) << "' (" << Where(j.line) << "): " << kTypeNames[static_cast<int>(j.type)]
          << renamed << Limits(j) << ReflectedFriction(j) << IgnoredMimic(j) << "\n";
    if (!j.origin.IsIdentity()) from = FixedFrame(Unique(j.name + "_origin", nullptr), j.origin, parent, "joint '" + j.name + "' <origin>");
    joint_name_[static_cast<std::size_t>(ji)] = name;
    switch (j.type) {
      case JointType::kRevolute:
      case JointType::kContinuous:
        Declare("Revolute", name, "axis = " + Vec(j.axis) + StopModifiers(j) + FrictionModifiers(j),
                "joint '" + Shown(j.name) + "'");
        break;
      case JointType::kPrismatic:
        Declare("Prismatic", name, "axis = " + Vec(j.axis) + StopModifiers(j) + FrictionModifiers(j),
                "joint '" + Shown(j.name) + "'");
        break;
      case JointType::kFloating: Declare("FreeMotion", name, "", "joint '" + Shown(j.name) + "'"); break;
      case JointType::kPlanar:
        Declare("Planar", name, "n = " + Vec(j.axis) + ", axis_x = " + Vec(Perpendicular(j.axis)),
                "joint '" + Shown(j.name) + "' (plane normal to its axis)");
        break;
      case JointType::kFixed: break;
    }
    Connect(from, name + ".frame_a");
    Dynamics(j, name);
    LinkComponents(child, name + ".frame_b");
  }

  std::string IgnoredMimic(const Joint& j) {
    if (!j.mimic_ignored) return "";
    ++mimics_ignored_;
    return "; <mimic joint=\"" + Shown(j.mimic_joint) + "\"> ignored (a fixed joint has no coordinate to couple)";
  }

  // <mimic joint multiplier offset> as an exact coupling, q = multiplier q_leader + offset
  // (stdlib JointCoupling): written once every joint has its name (the leader may come later
  // in the tree's order).
  void Mimics() {
    bool any = false;
    for (std::size_t ji = 0; ji < r_.joints.size(); ++ji) {
      const Joint& j = r_.joints[ji];
      if (!j.has_mimic) continue;
      const int li = j.mimic_leader;
      const std::string& follower = joint_name_[ji];
      const std::string& leader = joint_name_[static_cast<std::size_t>(li)];
      const std::string name = Unique(j.name + "_mimic", nullptr);
      if (!any) eq_ << "  // <mimic> joints: kept exactly (JointCoupling; the follower's coordinate is dependent)\n";
      any = true;
      decl_ << "  // <mimic joint=\"" << Shown(j.mimic_joint) << "\"> of joint '" << Shown(j.name) << "' (" << Where(j.line)
            << "): " << follower << ".q = " << Num(j.multiplier) << " * " << leader << ".q + " << Num(j.offset) << "\n";
      Declare("JointCoupling", name, "ratio = " + Num(j.multiplier) + ", offset = " + Num(j.offset),
              "joint '" + Shown(j.name) + "' mimics '" + Shown(j.mimic_joint) + "'");
      Connect(leader + ".drive", name + ".flange_a");
      Connect(follower + ".drive", name + ".flange_b");
    }
  }

  // <dynamics friction> (a constant torque or force) as the joint's exact Coulomb friction
  // (stick-slip as events, docs/stdlib.md "Revolute"); a <mimic> group's all on its root,
  // the followers' reflected through the coupling (MimicGroups): stuck joints whose motions
  // the coupling makes dependent would have no unique friction forces.
  double ExactFriction(const Joint& j) const {
    if (Reflected(j)) return 0.0;
    const auto g = friction_.find(static_cast<int>(&j - r_.joints.data()));
    return j.friction + (g == friction_.end() ? 0.0 : g->second);
  }
  std::string FrictionModifiers(const Joint& j) const {
    const double c = ExactFriction(j);
    if (c == 0) return "";
    return std::string(j.type == JointType::kPrismatic ? ", friction_force = " : ", friction_torque = ") + Num(c) +
           ", friction_exact = true";
  }
  // The comment of a follower whose friction its root holds.
  std::string ReflectedFriction(const Joint& j) const {
    if (j.friction == 0 || !Reflected(j)) return "";
    return "; <dynamics friction " + Num(j.friction) + "> on the exact friction of '" +
           Shown(r_.joints[static_cast<std::size_t>(root_[static_cast<std::size_t>(&j - r_.joints.data())])].name) +
           "' through the <mimic>";
  }

  // <dynamics damping> as the joint's force law (viscous damping).
  void Dynamics(const Joint& j, const std::string& name) {
    if (j.damping == 0 && j.friction == 0) return;
    if (!OneCoordinate(j)) {
      d_.Note(j.line, "<dynamics> of the " + std::string(j.type == JointType::kPlanar ? "planar" : "floating") +
                          " joint '" + Shown(j.name) + "' is not imported (only one-coordinate joints take it)");
      return;
    }
    if (j.damping == 0) return;
    eq_ << "  " << name << ".tau = -(" << Num(j.damping) << " * " << name << ".u);  // <dynamics damping> of joint '"
        << Shown(j.name) << "'\n";
  }

  int LinkIndex(const std::string& name) {
    if (link_index_.empty())
      for (std::size_t l = 0; l < r_.links.size(); ++l) link_index_.emplace(r_.links[l].name, static_cast<int>(l));
    return link_index_.at(name);  // BuildTree checked every name
  }

  // The mesh file a <mesh filename> names, "" when it is not found.
  std::string ResolveMesh(const std::string& name) const {
    std::vector<std::string> dirs = o_.package_paths;
    if (o_.use_ros_package_path)
      if (const char* env = std::getenv("ROS_PACKAGE_PATH")) {
        std::string s = env;
        for (std::size_t at = 0; at <= s.size();) {
          std::size_t end = s.find(':', at);
          if (end == std::string::npos) end = s.size();
          if (end > at) dirs.push_back(s.substr(at, end - at));
          at = end + 1;
        }
      }
    std::error_code ec;
    auto exists = [&](const fs::path& p) { return fs::is_regular_file(p, ec); };
    const std::string pkg = "package://", file = "file://";
    if (name.rfind(pkg, 0) == 0) {
      const std::string rest = name.substr(pkg.size());
      const std::size_t slash = rest.find('/');
      const std::string package = rest.substr(0, slash), inner = slash == std::string::npos ? "" : rest.substr(slash + 1);
      for (const std::string& d : dirs) {
        if (exists(fs::path(d) / package / inner)) return (fs::path(d) / package / inner).string();
        if (fs::path(d).filename() == package && exists(fs::path(d) / inner)) return (fs::path(d) / inner).string();
      }
      return "";
    }
    fs::path p = name.rfind(file, 0) == 0 ? fs::path(name.substr(file.size())) : fs::path(name);
    if (p.is_relative()) p = fs::path(path_).parent_path() / p;
    return exists(p) ? p.string() : "";
  }

  void VisualComponents(const Link& link, const Visual& v, int l, const std::string& file) {
    std::string frame = link_frame_[static_cast<std::size_t>(l)];
    const std::string what = "visual of link '" + Shown(link.name) + "' (" + Where(v.line) + ")";
    if (v.shape == Shape::kMesh && file.empty()) {
      decl_ << "  // " << what << ": mesh '" << Shown(v.mesh) << "' not found, left out\n";
      return;
    }
    const std::string base = Unique(link.name + "_visual", nullptr);
    std::string color = v.color.empty() ? "" : ", color = " + Quoted(v.color);
    if (!v.origin.IsIdentity()) frame = FixedFrame(base + "_origin", v.origin, frame, what + " <origin>");
    // The stdlib's Box and Cylinder run along their frame's x from x = 0; URDF's are centred,
    // the cylinder along z.
    if (v.shape == Shape::kBox) {
      frame = FixedFrame(base + "_corner", Pose{{-v.size[0] / 2, 0, 0}, {0, 0, 0}}, frame, "the box's end face");
      Declare("Box", base,
              "lx = " + Num(v.size[0]) + ", ly = " + Num(v.size[1]) + ", lz = " + Num(v.size[2]) + ", m = 0" + color,
              what);
    } else if (v.shape == Shape::kCylinder) {
      frame = FixedFrame(base + "_end", Pose{{0, 0, -v.length / 2}, {0, -M_PI / 2, 0}}, frame,
                         "the cylinder's end face, x along URDF's z");
      Declare("Cylinder", base, "length = " + Num(v.length) + ", radius = " + Num(v.radius) + ", m = 0" + color, what);
    } else if (v.shape == Shape::kSphere) {
      Declare("Sphere", base, "radius = " + Num(v.radius) + ", m = 0" + color, what);
    } else {
      Declare("BodyShape", base, "m = 0, file = " + Quoted(file) + ", scale = " + Num(std::fabs(v.scale[0])) + color,
              what);
    }
    Connect(frame, base + ".frame_a");
  }

  void Notes() {
    if (collisions_ > 0) {
      header_.push_back(std::to_string(collisions_) + " <collision> elements ignored (no contacts are computed from them)");
      d_.Note(0, header_.back());
    }
    if (stops_ > 0) header_.push_back(std::to_string(stops_) + " joint <limit>s as end stops (q_min, q_max; restitution 0)");
    if (limits_ > 0) {
      header_.push_back(std::to_string(limits_) + " joint <limit>s recorded in comments, not end stops (" +
                        "--limits ignore)");
      d_.Note(0, header_.back());
    }
    if (empty_ranges_ > 0) {
      header_.push_back(std::to_string(empty_ranges_) + " joint <limit>s with lower >= upper recorded in comments (no range to stop at)");
      d_.Note(0, header_.back());
    }
    if (mimics_ignored_ > 0) {
      header_.push_back(std::to_string(mimics_ignored_) +
                        " <mimic> elements on or of fixed joints ignored (a fixed joint has no coordinate to couple)");
      d_.Note(0, header_.back());
    }
    if (missing_meshes_ > 0)
      header_.push_back(std::to_string(missing_meshes_) + " visual meshes not found (--package-path, ROS_PACKAGE_PATH): left out");
  }

  const Robot& r_;
  const Options& o_;
  std::string path_;
  Diags& d_;
  std::ostringstream decl_, eq_;
  std::set<std::string> used_;
  std::vector<std::string> link_frame_, joint_name_, header_;
  std::unordered_map<std::string, int> link_index_;
  int collisions_ = 0, missing_meshes_ = 0, limits_ = 0, stops_ = 0, empty_ranges_ = 0, mimics_ignored_ = 0;
  bool coupled_ = false;  // the model has JointCouplings (kept <mimic>s)
  struct Range {
    double lower = 0, upper = 0;
    int members = 0;  // limits intersected
  };
  std::vector<int> root_;                  // per joint: its <mimic> root leader, or -1 (MimicGroups)
  std::unordered_map<int, Range> group_;  // per root with limits in its group: their common range in q_root
  std::unordered_map<int, double> friction_;  // per root: its followers' friction reflected onto it
};

}  // namespace

Result UrdfToMech(const std::string& path, std::string_view text, const Options& options) {
  Diags diags;
  Robot robot;
  Result result;
  if (text.size() > kMaxUrdfBytes) {
    diags.Error(DiagCode::UrdfTooLarge, 0, "", "the file is larger than 64 MiB", "a URDF of a robot is a few MB at most");
  } else if (ReadUrdf(text, &robot, diags) && BuildTree(&robot, diags)) {
    result = Writer(robot, options, path, diags).Write();
  }
  result.num_errors = diags.NumErrors();
  result.ok = result.num_errors == 0 && result.ok;
  if (!result.ok) result.mech.clear();
  // A refused oversized file is named, not shown (its one message is about the whole file).
  const RenderedMessages rendered = RenderMessages(diags, path, text.size() > kMaxUrdfBytes ? std::string_view() : text);
  result.diagnostics = rendered.errors + (options.notes ? rendered.notes : "");
  if (result.num_errors > 0)
    result.diagnostics += std::to_string(result.num_errors) + " error" + (result.num_errors == 1 ? "" : "s") + "\n";
  return result;
}

std::string TooLargeMessage(const std::string& path, std::uintmax_t bytes) {
  return Shown(path) + ": error[" + flat::DiagCodeString(DiagCode::UrdfTooLarge) + "]: the file is " +
         std::to_string(bytes) + " bytes, more than the " +
         std::to_string(kMaxUrdfBytes) + " a URDF may have\n";
}

bool IsUrdfPath(std::string_view path) {
  if (path.size() < 5) return false;
  std::string ext(path.substr(path.size() - 5));
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".urdf";
}

}  // namespace kanesim::import
