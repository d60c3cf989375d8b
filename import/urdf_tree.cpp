// The links and joints as one tree (urdf_model.h BuildTree): unique names, known links, one
// parent joint per link, one root, no cycle; the joints in depth-first order. Iterative throughout: a chain of 100 000 links
// costs no stack.
#include <string>
#include <unordered_map>

#include "import/urdf_model.h"

namespace kanesim::import {

namespace {

std::string At(int line) { return " (line " + std::to_string(line) + ")"; }

// Name -> index; a second element of one name is U405.
template <typename T>
std::unordered_map<std::string, int> IndexNames(const std::vector<T>& items, const char* what, const char* tag,
                                                Diags& diags) {
  std::unordered_map<std::string, int> index;
  for (int i = 0; i < static_cast<int>(items.size()); ++i) {
    auto [it, added] = index.emplace(items[i].name, i);
    if (!added)
      diags.Error(DiagCode::UrdfDuplicateName, items[i].line, tag,
                  std::string("a second ") + what + " named '" + items[i].name + "'; the first is at line " +
                      std::to_string(items[it->second].line),
                  std::string("every ") + what + " needs a name of its own");
  }
  return index;
}

bool OneCoordinate(JointType t) {
  return t == JointType::kRevolute || t == JointType::kContinuous || t == JointType::kPrismatic;
}

// Each <mimic joint> names another joint, and both have one coordinate (a coupling q = m q_l
// + c of JointCoupling); Joint::mimic_leader is set.
void CheckMimics(Robot* robot, const std::unordered_map<std::string, int>& joints, Diags& diags) {
  for (Joint& j : robot->joints) {
    if (!j.has_mimic) continue;
    auto it = joints.find(j.mimic_joint);
    if (it == joints.end()) {
      diags.Error(DiagCode::UrdfUnknownLink, j.line, "<mimic",
                  "joint '" + j.name + "' mimics joint '" + j.mimic_joint + "', which the file does not define",
                  "correct the name in <mimic joint=\"...\"/>");
      continue;
    }
    const Joint& leader = robot->joints[static_cast<std::size_t>(it->second)];
    if (&leader == &j || !OneCoordinate(j.type) || !OneCoordinate(leader.type)) {
      diags.Error(DiagCode::UrdfBadMimic, j.line, "<mimic",
                  "joint '" + j.name + "' cannot mimic '" + leader.name + "'" +
                      (&leader == &j ? ": itself" : ": a mimic couples two revolute, continuous or prismatic joints"),
                  "remove the <mimic> element, or name a one-coordinate joint");
      continue;
    }
    j.mimic_leader = it->second;
  }
}

}  // namespace

bool BuildTree(Robot* robot, Diags& diags) {
  if (robot->links.empty()) {
    diags.Error(DiagCode::UrdfNotUrdf, robot->line, "<robot", "the robot has no <link>");
    return false;
  }
  auto links = IndexNames(robot->links, "link", "<link", diags);
  const auto joints = IndexNames(robot->joints, "joint", "<joint", diags);
  CheckMimics(robot, joints, diags);
  const int nl = static_cast<int>(robot->links.size());
  robot->parent_joint.assign(static_cast<std::size_t>(nl), -1);
  std::vector<std::vector<int>> children(static_cast<std::size_t>(nl));  // joints out of each link
  for (int j = 0; j < static_cast<int>(robot->joints.size()); ++j) {
    const Joint& joint = robot->joints[static_cast<std::size_t>(j)];
    auto p = links.find(joint.parent), c = links.find(joint.child);
    bool known = true;
    for (auto [it, ref, tag] : {std::tuple{p, &joint.parent, "<parent"}, std::tuple{c, &joint.child, "<child"}}) {
      if (it != links.end()) continue;
      known = false;
      diags.Error(DiagCode::UrdfUnknownLink, joint.line, "<joint",
                  "joint '" + joint.name + "' names link '" + *ref + "', which the file does not define",
                  std::string("add <link name=\"") + *ref + "\"/> or correct the " + (tag + 1) + " link's name");
    }
    if (!known) continue;
    if (p->second == c->second) {
      diags.Error(DiagCode::UrdfNotATree, joint.line, "<joint",
                  "joint '" + joint.name + "' joins link '" + joint.parent + "' to itself");
      continue;
    }
    int& pj = robot->parent_joint[static_cast<std::size_t>(c->second)];
    if (pj >= 0) {
      const Joint& first = robot->joints[static_cast<std::size_t>(pj)];
      diags.Error(DiagCode::UrdfNotATree, joint.line, "<joint",
                  "link '" + joint.child + "' is the child of two joints: '" + first.name + "'" + At(first.line) +
                      " and '" + joint.name + "'",
                  "a URDF is a tree: close a loop in the .mech file with a joint marked cut = true");
      continue;
    }
    pj = j;
    children[static_cast<std::size_t>(p->second)].push_back(j);
  }
  if (diags.NumErrors() > 0) return false;

  std::vector<int> roots;
  for (int l = 0; l < nl; ++l)
    if (robot->parent_joint[static_cast<std::size_t>(l)] < 0) roots.push_back(l);
  if (roots.size() > 1) {
    std::string names;
    for (std::size_t i = 0; i < roots.size() && i < 5; ++i)
      names += (i ? ", '" : "'") + robot->links[static_cast<std::size_t>(roots[i])].name + "'" +
               At(robot->links[static_cast<std::size_t>(roots[i])].line);
    if (roots.size() > 5) names += " and " + std::to_string(roots.size() - 5) + " more";
    const Link& second = robot->links[static_cast<std::size_t>(roots[1])];
    diags.Error(DiagCode::UrdfNotATree, second.line, "<link",
                std::to_string(roots.size()) + " links have no parent joint: " + names,
                "every link but the root must be the child of a joint");
    return false;
  }
  // Depth first from the root, children in file order (a chain reads as one run of text),
  // with a stack of joints; a link not reached sits on a cycle (each has one parent).
  std::vector<bool> reached(static_cast<std::size_t>(nl), false);
  if (roots.size() == 1) {
    robot->root = roots[0];
    reached[static_cast<std::size_t>(roots[0])] = true;
    const auto& first = children[static_cast<std::size_t>(roots[0])];
    std::vector<int> stack(first.rbegin(), first.rend());
    while (!stack.empty()) {
      const int j = stack.back();
      stack.pop_back();
      robot->order.push_back(j);
      const int child = links[robot->joints[static_cast<std::size_t>(j)].child];
      reached[static_cast<std::size_t>(child)] = true;
      const auto& next = children[static_cast<std::size_t>(child)];
      stack.insert(stack.end(), next.rbegin(), next.rend());
    }
  }
  for (int l = 0; l < nl; ++l) {
    if (reached[static_cast<std::size_t>(l)]) continue;
    const Joint& j = robot->joints[static_cast<std::size_t>(robot->parent_joint[static_cast<std::size_t>(l)])];
    diags.Error(DiagCode::UrdfNotATree, j.line, "<joint",
                "the joints form a cycle through link '" + robot->links[static_cast<std::size_t>(l)].name +
                    "' (joint '" + j.name + "'): no link of it descends from a root",
                "a URDF is a tree: close a loop in the .mech file with a joint marked cut = true");
    return false;
  }
  return true;
}

}  // namespace kanesim::import
