#include "urdf_validation.hpp"

#include <cmath>
#include <cstdlib>
#include <locale>
#include <map>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <tinyxml.h>

#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::detail {
namespace {

// Relative slack of the triangle inequality on principal moments: CAD exports of real
// robots break it by a few per cent (Talos's gripper motor by 2.6%); beyond 5% no body.
constexpr double kTriangleTolerance = 0.05;

class Validator {
 public:
  Validator(std::string source, bool triangle_inequality)
      : source_(std::move(source)), triangle_inequality_(triangle_inequality) {}

  std::string where(const TiXmlNode* at) const {
    std::ostringstream s;
    s << source_;
    if (at) s << ":" << at->Row();
    return s.str() + ": ";
  }

  [[noreturn]] void fail(const TiXmlNode* at, const std::string& what) const {
    throw ModelError(where(at) + what);
  }

  // A number that describes no physical body (mass, inertia).
  [[noreturn]] void unphysical(const TiXmlNode* at, const std::string& what) const {
    throw PhysicallyInvalidModel(where(at) + what);
  }

  // "joint 'name'" / "link 'name'" for messages.
  static std::string describe(const TiXmlElement* e) {
    const char* name = e->Attribute("name");
    return std::string(e->Value()) + " '" + (name ? name : "?") + "'";
  }

  // Parses attribute `attr` of `e` as exactly `count` finite numbers. A missing
  // attribute gives `fallback` (or an error when there is none).
  std::vector<double> numbers(const TiXmlElement* owner, const TiXmlElement* e, const char* attr,
                              size_t count, const std::vector<double>* fallback = nullptr) const {
    const char* text = e->Attribute(attr);
    if (!text) {
      if (fallback) return *fallback;
      fail(e, describe(owner) + ": <" + e->Value() + "> has no '" + attr + "' attribute");
    }
    std::vector<double> out;
    std::istringstream in(text);
    std::string token;
    while (in >> token) {
      // Read the token as urdfdom does (C locale, the whole token: no hex floats, no
      // "nan"/"inf"), so that what passes here also parses there, whatever the locale.
      std::istringstream number(token);
      number.imbue(std::locale::classic());
      double v = 0;
      number >> v;
      if (number.fail() || !number.eof()) {
        char* end = nullptr;
        double w = std::strtod(token.c_str(), &end);
        bool non_finite = end != token.c_str() && *end == '\0' && !std::isfinite(w);
        fail(e, describe(owner) + ": <" + e->Value() + " " + attr + "=\"" + text + "\">: '" + token +
                    (non_finite ? "' is not a finite number" : "' is not a number"));
      }
      out.push_back(v);
    }
    if (out.size() != count)
      fail(e, describe(owner) + ": <" + e->Value() + " " + attr + "=\"" + text + "\">: expected " +
                  std::to_string(count) + " number(s), found " + std::to_string(out.size()));
    return out;
  }

  // Checks the <origin> of `parent` (read as urdfdom does: its first one) and returns
  // its rpy angles, zero when there is none.
  std::array<double, 3> checkOrigin(const TiXmlElement* owner, const TiXmlElement* parent) const {
    static const std::vector<double> zero3{0, 0, 0};
    const TiXmlElement* o = parent->FirstChildElement("origin");
    if (!o) return {0, 0, 0};
    numbers(owner, o, "xyz", 3, &zero3);
    const std::vector<double> rpy = numbers(owner, o, "rpy", 3, &zero3);
    return {rpy[0], rpy[1], rpy[2]};
  }

  void checkLink(const TiXmlElement* link) {
    const TiXmlElement* inertial = link->FirstChildElement("inertial");
    if (!inertial) return;
    rotations_.inertial_rpy[link->Attribute("name")] = checkOrigin(link, inertial);
    const TiXmlElement* mass = inertial->FirstChildElement("mass");
    if (!mass) fail(inertial, describe(link) + ": <inertial> has no <mass>");
    double m = numbers(link, mass, "value", 1)[0];
    if (m < 0) unphysical(mass, describe(link) + ": negative mass " + mass->Attribute("value"));
    const TiXmlElement* inertia = inertial->FirstChildElement("inertia");
    if (!inertia) fail(inertial, describe(link) + ": <inertial> has no <inertia>");
    const char* keys[] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
    double v[6];
    for (int k = 0; k < 6; ++k) v[k] = numbers(link, inertia, keys[k], 1)[0];
    Eigen::Matrix3d I;
    I << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d moments = eig.eigenvalues();  // ascending
    double smallest = moments[0];
    double scale = std::max(1.0, I.cwiseAbs().maxCoeff());
    if (smallest < -1e-12 * scale) {
      std::ostringstream s;
      s << describe(link) << ": inertia (ixx=" << v[0] << " ixy=" << v[1] << " ixz=" << v[2]
        << " iyy=" << v[3] << " iyz=" << v[4] << " izz=" << v[5]
        << ") is not positive semi-definite (smallest eigenvalue " << smallest << ")";
      unphysical(inertia, s.str());
    }
    // No body has one principal moment above the sum of the other two (equality: a
    // plate); the tolerance admits rounded and CAD-exported values.
    if (triangle_inequality_ && moments[0] + moments[1] < moments[2] * (1 - kTriangleTolerance)) {
      std::ostringstream s;
      s << describe(link) << ": inertia violates the triangle inequality (principal moments " << moments[0]
        << ", " << moments[1] << ", " << moments[2] << ": " << moments[2] << " is more than " << moments[0]
        << " + " << moments[1] << ")";
      unphysical(inertia, s.str());
    }
  }

  void checkJoint(const TiXmlElement* joint) {
    const char* type = joint->Attribute("type");
    const std::string what = describe(joint);
    if (!type) fail(joint, what + ": no 'type' attribute");
    const std::string t = type;
    if (t == "floating" || t == "planar")
      fail(joint, what + ": joint type '" + t + "' is not supported inside the tree "
                  "(a free-flyer is only available as the root, with the floating-base option)");
    if (t != "revolute" && t != "continuous" && t != "prismatic" && t != "fixed")
      fail(joint, what + ": unknown joint type '" + t + "'");
    // A mimic tag on a fixed joint has nothing to mimic (URDFs such as Talos carry them).
    const TiXmlElement* mimic = t == "fixed" ? nullptr : joint->FirstChildElement("mimic");
    if (mimic) {
      const char* other = mimic->Attribute("joint");
      fail(mimic, what + ": <mimic joint=\"" + (other ? other : "?") + "\"> is not supported");
    }
    for (const char* role : {"parent", "child"}) {
      const TiXmlElement* e = joint->FirstChildElement(role);
      if (!e || !e->Attribute("link"))
        fail(joint, what + ": missing <" + role + " link=\"...\">");
    }
    rotations_.joint_rpy[joint->Attribute("name")] = checkOrigin(joint, joint);
    if (t == "fixed") return;
    if (const TiXmlElement* axis = joint->FirstChildElement("axis")) {
      auto a = numbers(joint, axis, "xyz", 3);
      if (std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) < 1e-12)
        fail(axis, what + ": zero axis <axis xyz=\"" + axis->Attribute("xyz") + "\">");
    }
    const TiXmlElement* limit = joint->FirstChildElement("limit");
    if (!limit && t != "continuous")
      fail(joint, what + ": a " + t + " joint needs a <limit> element");
    if (limit) {
      static const std::vector<double> zero{0};
      double lower = numbers(joint, limit, "lower", 1, &zero)[0];
      double upper = numbers(joint, limit, "upper", 1, &zero)[0];
      // urdfdom requires effort and velocity on every <limit>, continuous joints included.
      double effort = numbers(joint, limit, "effort", 1)[0];
      double velocity = numbers(joint, limit, "velocity", 1)[0];
      auto text = [&](const char* attr) {
        const char* value = limit->Attribute(attr);
        return std::string(value ? value : "0");
      };
      if (t != "continuous" && lower > upper)
        fail(limit, what + ": <limit> lower " + text("lower") + " is above upper " + text("upper"));
      if (effort < 0) fail(limit, what + ": <limit> negative effort " + text("effort"));
      if (velocity < 0) fail(limit, what + ": <limit> negative velocity " + text("velocity"));
    }
    if (const TiXmlElement* dyn = joint->FirstChildElement("dynamics")) {
      static const std::vector<double> zero{0};
      if (!dyn->Attribute("damping") && !dyn->Attribute("friction"))  // urdfdom rejects it
        fail(dyn, what + ": <dynamics> has neither 'damping' nor 'friction'");
      numbers(joint, dyn, "damping", 1, &zero);
      numbers(joint, dyn, "friction", 1, &zero);
    }
  }

  UrdfRotations run(const std::string& xml) {
    TiXmlDocument doc;
    doc.Parse(xml.c_str(), nullptr, TIXML_ENCODING_UTF8);
    if (doc.Error()) {
      std::ostringstream s;
      s << source_;
      if (doc.ErrorRow() > 0) s << ":" << doc.ErrorRow() << ":" << doc.ErrorCol();  // 0: no location
      s << ": malformed XML: " << doc.ErrorDesc();
      throw ModelError(s.str());
    }
    const TiXmlElement* robot = doc.RootElement();
    if (!robot) throw ModelError(source_ + ": empty document, no <robot> element");
    if (std::string(robot->Value()) != "robot")
      fail(robot, std::string("the root element is <") + robot->Value() + ">, expected <robot>");

    std::map<std::string, const TiXmlElement*> links;
    for (const TiXmlElement* l = robot->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
      const char* name = l->Attribute("name");
      if (!name || !*name) fail(l, "a <link> without a name");
      if (!links.emplace(name, l).second) fail(l, "duplicate link name '" + std::string(name) + "'");
      checkLink(l);
    }
    if (links.empty()) fail(robot, "the robot has no <link>");

    std::map<std::string, std::string> parent_of;  // child link -> joint name
    std::set<std::string> joint_names;
    std::map<std::string, std::vector<std::string>> children;
    for (const TiXmlElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
      const char* name = j->Attribute("name");
      if (!name || !*name) fail(j, "a <joint> without a name");
      if (!joint_names.insert(name).second) fail(j, "duplicate joint name '" + std::string(name) + "'");
      checkJoint(j);
      std::string parent = j->FirstChildElement("parent")->Attribute("link");
      std::string child = j->FirstChildElement("child")->Attribute("link");
      if (!links.count(parent)) fail(j, describe(j) + ": parent link '" + parent + "' is not defined");
      if (!links.count(child)) fail(j, describe(j) + ": child link '" + child + "' is not defined");
      if (parent == child) fail(j, describe(j) + ": link '" + child + "' is its own parent");
      auto [it, fresh] = parent_of.emplace(child, name);
      if (!fresh)
        fail(j, describe(j) + ": link '" + child + "' is already the child of joint '" + it->second + "'");
      children[parent].push_back(child);
    }

    std::vector<std::string> roots;
    for (const auto& [name, _] : links)
      if (!parent_of.count(name)) roots.push_back(name);
    if (roots.empty()) fail(robot, "no root link: every link is the child of a joint (a cycle)");
    if (roots.size() > 1) {
      std::string list;
      for (const auto& r : roots) list += (list.empty() ? "'" : ", '") + r + "'";
      fail(robot, "several root links (" + list + "): a URDF must form one tree");
    }
    // Every link reachable from the root (else a cycle hangs off the tree).
    std::set<std::string> seen{roots[0]};
    std::vector<std::string> stack{roots[0]};
    while (!stack.empty()) {
      std::string l = stack.back();
      stack.pop_back();
      for (const auto& c : children[l])
        if (seen.insert(c).second) stack.push_back(c);
    }
    if (seen.size() != links.size()) {
      for (const auto& [name, element] : links)
        if (!seen.count(name)) fail(element, "link '" + name + "' is not reachable from root '" + roots[0] +
                                                 "' (its joints form a cycle)");
    }
    return std::move(rotations_);
  }

 private:
  std::string source_;
  bool triangle_inequality_;
  UrdfRotations rotations_;
};

}  // namespace

UrdfRotations validateUrdfXml(const std::string& xml, const std::string& source, bool triangle_inequality) {
  return Validator(source, triangle_inequality).run(xml);
}

}  // namespace robodiff::detail
