#include "robodiff/model/robot_generator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace robodiff {
namespace {

// ---------------------------------------------------------------------------------
// Tree specs

constexpr int kMaxJoints = kMaxGeneratedJoints;

struct Group {
  std::string label;
  int count = 1;
  int length = 0;
  std::vector<Group> children;
};

class SpecParser {
 public:
  explicit SpecParser(std::string spec) : spec_(std::move(spec)) {}

  std::vector<Group> parse() {
    std::vector<Group> groups = list();
    skipSpaces();
    if (pos_ != spec_.size()) fail(std::string("unexpected '") + spec_[pos_] + "'");
    return groups;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("tree spec \"" + spec_ + "\": " + what + " at position " +
                                std::to_string(pos_ + 1) +
                                " (expected e.g. \"4x6\", \"2x6,2x7\", \"leg:2x6,torso:2(arm:2x7)\","
                                " \"quadruped\" or \"humanoid\")");
  }

  void skipSpaces() {
    while (pos_ < spec_.size() && spec_[pos_] == ' ') ++pos_;
  }
  bool accept(char c) {
    skipSpaces();
    if (pos_ < spec_.size() && spec_[pos_] == c) return ++pos_, true;
    return false;
  }
  static bool isLetter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
  static bool isDigit(char c) { return c >= '0' && c <= '9'; }

  std::vector<Group> list() {
    std::vector<Group> groups{group()};
    while (accept(',')) groups.push_back(group());
    return groups;
  }

  // A positive whole number of at most kMaxJoints.
  int number(const char* what) {
    skipSpaces();
    if (pos_ >= spec_.size() || !isDigit(spec_[pos_])) fail(std::string("expected ") + what);
    long value = 0;
    while (pos_ < spec_.size() && isDigit(spec_[pos_])) {
      value = value * 10 + (spec_[pos_++] - '0');
      if (value > kMaxJoints) fail(std::string(what) + " above " + std::to_string(kMaxJoints));
    }
    if (value < 1) fail(std::string(what) + " must be at least 1");
    return static_cast<int>(value);
  }

  Group group() {
    Group g;
    skipSpaces();
    if (pos_ < spec_.size() && isLetter(spec_[pos_])) {
      size_t start = pos_;
      while (pos_ < spec_.size() && (isLetter(spec_[pos_]) || isDigit(spec_[pos_]) || spec_[pos_] == '_')) ++pos_;
      g.label = spec_.substr(start, pos_ - start);
      if (!accept(':')) fail("expected ':' after the label '" + g.label + "'");
    }
    g.length = number("a branch length or count");
    if (accept('x')) {
      g.count = g.length;
      g.length = number("a branch length");
    }
    if (accept('(')) {
      g.children = list();
      if (!accept(')')) fail("expected ')' or ','");
    }
    return g;
  }

  std::string spec_;
  size_t pos_ = 0;
};

std::string padded(int index, int siblings) {
  std::string digits = std::to_string(index);
  size_t width = std::to_string(std::max(siblings - 1, 0)).size();
  return std::string(width - std::min(width, digits.size()), '0') + digits;
}

// Names the branches of `groups`, which hang from the branch `parent` ("" for the base).
std::vector<TreeBranch> nameBranches(const std::vector<Group>& groups, const std::string& parent,
                                     std::set<std::string>& used, long& total) {
  int siblings = 0;
  for (const Group& g : groups) siblings += g.count;
  std::vector<TreeBranch> out;
  int index = 0;
  for (const Group& g : groups) {
    for (int i = 0; i < g.count; ++i, ++index) {
      TreeBranch b;
      if (!g.label.empty())
        b.name = g.count > 1 ? g.label + padded(i, g.count) : g.label;
      else
        b.name = (parent.empty() ? "branch" : parent + "_") + padded(index, siblings);
      if (!used.insert(b.name).second)
        throw std::invalid_argument("tree spec: the branch name '" + b.name +
                                    "' occurs twice (give the groups different labels)");
      b.length = g.length;
      total += g.length;
      if (total > kMaxJoints)
        throw std::invalid_argument("tree spec: more than " + std::to_string(kMaxJoints) + " joints");
      b.children = nameBranches(g.children, b.name, used, total);
      out.push_back(std::move(b));
    }
  }
  return out;
}

std::string presetSpec(const std::string& spec) {
  if (spec == "quadruped") return kQuadrupedTreeSpec;
  if (spec == "humanoid") return kHumanoidTreeSpec;
  return spec;
}

// ---------------------------------------------------------------------------------
// Random numbers that are the same on every machine

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, n), n > 0, without modulo bias.
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() -
                                std::numeric_limits<std::uint64_t>::max() % n;
    std::uint64_t r;
    do r = engine_();
    while (r >= limit);
    return r % n;
  }
  int between(int lo, int hi) { return lo + static_cast<int>(below(static_cast<std::uint64_t>(hi - lo) + 1)); }
  bool percent(int p) { return static_cast<int>(below(100)) < p; }

  // Uniform over the multiples of 2^-bits in [lo, hi]. Such numbers are exact in
  // double and sums and small products of them stay exact, so no rounding (and no
  // fused multiply-add) can make two machines disagree.
  double grid(double lo, double hi, int bits) {
    const auto a = static_cast<std::int64_t>(std::ceil(std::ldexp(lo, bits)));
    const auto b = static_cast<std::int64_t>(std::floor(std::ldexp(hi, bits)));
    return std::ldexp(static_cast<double>(a + static_cast<std::int64_t>(below(static_cast<std::uint64_t>(b - a) + 1))),
                      -bits);
  }

 private:
  std::mt19937_64 engine_;
};

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<Vec3, 3>;

constexpr double kPi = std::numbers::pi;
constexpr int kLengthBits = 16;  // grid of lengths: 2^-16 m ~ 15 um
constexpr int kAngleBits = 20;

struct Pose {
  Vec3 xyz{0, 0, 0}, rpy{0, 0, 0};
};

struct LinkInertia {
  double mass = 0;
  Pose origin;  // centre of mass, and the rotation of the tensor's frame
  Mat3 tensor{};
};

enum class MovingType { Revolute, Continuous, Prismatic };

// 17 significant digits: the text reads back as exactly the same double.
std::string num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

// ---------------------------------------------------------------------------------
// The generator

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}

  // `prismatic` and `continuous` joints are placed at random among all moving joints.
  std::string run(const std::string& robot_name, const std::string& comment,
                  const std::vector<TreeBranch>& branches, bool chain, int prismatic, int continuous) {
    const int n = countJoints(branches);
    types_.assign(n, MovingType::Revolute);
    for (int i = 0; i < prismatic + continuous; ++i)
      types_[i] = i < prismatic ? MovingType::Prismatic : MovingType::Continuous;
    for (int i = n - 1; i > 0; --i) std::swap(types_[i], types_[rng_.below(static_cast<std::uint64_t>(i) + 1)]);

    out_ << "<?xml version=\"1.0\"?>\n<!-- " << comment << " -->\n<robot name=\"" << robot_name << "\">\n";
    link("base_link", 1.0, 5.0);
    if (chain) {
      branch("", branches[0].length, {}, "base_link");
    } else {
      for (const TreeBranch& b : branches) treeBranch(b, "base_link");
    }
    out_ << "</robot>\n";
    return out_.str();
  }

 private:
  void treeBranch(const TreeBranch& b, const std::string& parent_link) {
    std::string end = branch(b.name + "_", b.length, b.children, parent_link);
    for (const TreeBranch& c : b.children) treeBranch(c, end);
  }

  // Writes one branch (names prefixed by `prefix`) hanging from `parent_link`; returns
  // its last moving link, where sub-branches attach.
  std::string branch(const std::string& prefix, int length, const std::vector<TreeBranch>& children,
                     const std::string& parent_link) {
    std::string parent = parent_link;
    for (int k = 1; k <= length; ++k) {
      std::string child = prefix + "link" + std::to_string(k);
      movingJoint(prefix + "joint" + std::to_string(k), parent, child);
      link(child, 0.2, 5.0);
      parent = child;
      if (k < length && rng_.percent(12)) {  // a spacer: a massive link on a fixed joint
        std::string spacer = prefix + "spacer" + std::to_string(k);
        fixedJoint(spacer + "_joint", parent, spacer);
        link(spacer, 0.2, 5.0);
        parent = spacer;
      }
    }
    if (children.empty()) {  // a tool (flange) at the end of every leaf branch
      fixedJoint(prefix + "tool_joint", parent, prefix + "tool");
      link(prefix + "tool", 0.2, 2.0);
    }
    return parent;
  }

  void name(const std::string& n) {
    if (!names_.insert(n).second)
      throw std::invalid_argument("robot generator: the name '" + n +
                                  "' occurs twice (choose other tree labels)");
  }

  static std::string vec(const Vec3& v) { return num(v[0]) + " " + num(v[1]) + " " + num(v[2]); }
  void origin(const Pose& p, const char* indent) {
    out_ << indent << "<origin xyz=\"" << vec(p.xyz) << "\" rpy=\"" << vec(p.rpy) << "\"/>\n";
  }

  // A joint origin: now and then no translation (coincident axes, as in a wrist);
  // otherwise a main offset along one axis and small ones along the others. Rotation:
  // none, quarter turns, or generic angles.
  Pose jointOrigin() {
    Pose p;
    if (!rng_.percent(10)) {
      for (double& c : p.xyz) c = rng_.grid(-0.04, 0.04, kLengthBits);
      int main_axis = rng_.between(0, 2);
      double length = rng_.grid(0.08, 0.35, kLengthBits);
      p.xyz[main_axis] = rng_.percent(50) ? length : -length;
    }
    int kind = rng_.between(0, 9);
    if (kind >= 3 && kind < 7) {
      static constexpr double kQuarterTurns[] = {0.0, kPi / 2, -kPi / 2, kPi};
      for (double& a : p.rpy) a = kQuarterTurns[rng_.below(4)];
    } else if (kind >= 7) {
      for (double& a : p.rpy) a = rng_.grid(-kPi, kPi, kAngleBits);
    }
    return p;
  }

  // x, y, z, a negative one of them, or an unaligned unit axis: a small integer
  // vector with at least two non-zero entries, divided by its (correctly rounded) norm.
  Vec3 axis() {
    int kind = rng_.between(0, 99);
    if (kind < 55) {
      Vec3 a{0, 0, 0};
      a[kind < 25 ? 2 : kind < 40 ? 0 : 1] = 1.0;
      return a;
    }
    if (kind < 75) {
      Vec3 a{0, 0, 0};
      a[rng_.between(0, 2)] = -1.0;
      return a;
    }
    for (;;) {
      Vec3 a{};
      int nonzero = 0;
      for (double& c : a) nonzero += (c = rng_.between(-4, 4)) != 0;
      if (nonzero < 2) continue;
      double norm = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);  // integers: exact sum
      return {a[0] / norm, a[1] / norm, a[2] / norm};
    }
  }

  void movingJoint(const std::string& joint_name, const std::string& parent, const std::string& child) {
    name(joint_name);
    MovingType type = types_.at(next_type_++);
    const char* type_name = type == MovingType::Prismatic ? "prismatic"
                            : type == MovingType::Continuous ? "continuous"
                                                             : "revolute";
    out_ << "  <joint name=\"" << joint_name << "\" type=\"" << type_name << "\">\n"
         << "    <parent link=\"" << parent << "\"/>\n"
         << "    <child link=\"" << child << "\"/>\n";
    origin(jointOrigin(), "    ");
    out_ << "    <axis xyz=\"" << vec(axis()) << "\"/>\n";
    // Each draw is its own statement, so the order of draws is plain to see.
    if (type == MovingType::Continuous) {
      const double effort = rng_.grid(5, 300, 4);
      const double velocity = rng_.grid(1, 10, 6);
      out_ << "    <limit effort=\"" << num(effort) << "\" velocity=\"" << num(velocity) << "\"/>\n";
    } else {
      const bool revolute = type == MovingType::Revolute;
      const double lower = revolute ? -rng_.grid(0.5, 3.1, kAngleBits) : -rng_.grid(0.05, 0.3, kLengthBits);
      const double upper = revolute ? rng_.grid(0.5, 3.1, kAngleBits) : rng_.grid(0.05, 0.5, kLengthBits);
      const double effort = revolute ? rng_.grid(5, 300, 4) : rng_.grid(20, 1000, 4);
      const double velocity = revolute ? rng_.grid(1, 10, 6) : rng_.grid(0.1, 2, 6);
      out_ << "    <limit lower=\"" << num(lower) << "\" upper=\"" << num(upper) << "\" effort=\""
           << num(effort) << "\" velocity=\"" << num(velocity) << "\"/>\n";
    }
    if (rng_.percent(30)) {
      const double damping = rng_.grid(0, 2, 8);
      const double friction = rng_.grid(0, 1, 8);
      out_ << "    <dynamics damping=\"" << num(damping) << "\" friction=\"" << num(friction) << "\"/>\n";
    }
    out_ << "  </joint>\n";
  }

  void fixedJoint(const std::string& joint_name, const std::string& parent, const std::string& child) {
    name(joint_name);
    out_ << "  <joint name=\"" << joint_name << "\" type=\"fixed\">\n"
         << "    <parent link=\"" << parent << "\"/>\n"
         << "    <child link=\"" << child << "\"/>\n";
    origin(jointOrigin(), "    ");
    out_ << "  </joint>\n";
  }

  // A valid rigid-body inertia. The principal moments come from the second moments
  // s_k = sum(m x_k^2) >= 0 of a body about its centre of mass (Ixx = s_y + s_z, ...),
  // which makes them positive and satisfy the triangle inequality. The principal
  // axes are turned by the origin's rpy, or by a rotation R = M / n built from an
  // integer quaternion (M integer, n its squared norm), or both: the tensor
  // R diag(I) R^T = (M diag(I) M^T) / n^2 is then an exact integer-weighted sum
  // rounded once by the division.
  LinkInertia inertia(double min_mass, double max_mass) {
    LinkInertia in;
    in.mass = rng_.grid(min_mass, max_mass, 10);
    for (double& c : in.origin.xyz) c = rng_.grid(-0.06, 0.06, kLengthBits);
    Vec3 s;
    for (double& c : s) c = rng_.grid(in.mass * 1e-4, in.mass * 8e-3, 32);
    const Vec3 principal{s[1] + s[2], s[0] + s[2], s[0] + s[1]};

    int mode = rng_.between(0, 19);  // 0-5: rpy, 6-12: tensor, 13-17: both, 18-19: aligned
    if (mode <= 5 || (mode >= 13 && mode <= 17))
      for (double& a : in.origin.rpy) a = rng_.grid(-kPi, kPi, kAngleBits);
    if (mode >= 6 && mode <= 17) {
      std::array<double, 4> q;
      do {
        for (double& c : q) c = rng_.between(-5, 5);
      } while (q[0] == 0 && q[1] == 0 && q[2] == 0 && q[3] == 0);
      const auto [a, b, c, d] = q;
      const double n = a * a + b * b + c * c + d * d;
      const Mat3 M{{{a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
                    {2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)},
                    {2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d}}};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          double sum = 0;
          for (int k = 0; k < 3; ++k) sum += M[i][k] * M[j][k] * principal[k];
          in.tensor[i][j] = sum / (n * n);
        }
    } else {
      for (int i = 0; i < 3; ++i) in.tensor[i] = {0, 0, 0}, in.tensor[i][i] = principal[i];
    }
    return in;
  }

  void link(const std::string& link_name, double min_mass, double max_mass) {
    name(link_name);
    LinkInertia in = inertia(min_mass, max_mass);
    const Mat3& t = in.tensor;
    out_ << "  <link name=\"" << link_name << "\">\n    <inertial>\n";
    origin(in.origin, "      ");
    out_ << "      <mass value=\"" << num(in.mass) << "\"/>\n"
         << "      <inertia ixx=\"" << num(t[0][0]) << "\" ixy=\"" << num(t[0][1]) << "\" ixz=\""
         << num(t[0][2]) << "\" iyy=\"" << num(t[1][1]) << "\" iyz=\"" << num(t[1][2]) << "\" izz=\""
         << num(t[2][2]) << "\"/>\n"
         << "    </inertial>\n  </link>\n";
  }

  Random rng_;
  std::vector<MovingType> types_;  // the type of each moving joint, in writing order
  size_t next_type_ = 0;
  std::set<std::string> names_;
  std::ostringstream out_;
};

void checkFraction(const char* what, double f) {
  if (!(f >= 0.0 && f <= 1.0)) {
    std::ostringstream s;
    s << "robot generator: " << what << " " << f << " is not in [0, 1]";
    throw std::invalid_argument(s.str());
  }
}

void checkRobotName(const std::string& name) {
  if (!isValidRobotName(name))
    throw std::invalid_argument("robot generator: robot name '" + name +
                                "' must be 1 to 200 letters, digits, '_', '.' or '-'");
}

}  // namespace

bool isValidRobotName(const std::string& name) {
  bool ok = !name.empty() && name.size() <= 200;
  for (char c : name)
    ok = ok && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                c == '.' || c == '-');
  return ok;
}

std::vector<TreeBranch> parseTreeSpec(const std::string& spec) {
  std::vector<Group> groups = SpecParser(presetSpec(spec)).parse();
  std::set<std::string> used;
  long total = 0;
  return nameBranches(groups, "", used, total);
}

int countJoints(const std::vector<TreeBranch>& branches) {
  int n = 0;
  for (const TreeBranch& b : branches) n += b.length + countJoints(b.children);
  return n;
}

std::string generateRobotUrdf(const GeneratorOptions& options) {
  const bool chain = options.kind == RobotKind::Chain;
  std::vector<TreeBranch> branches;
  std::string description;
  std::string default_name;
  if (chain) {
    if (options.joints < 1 || options.joints > kMaxJoints)
      throw std::invalid_argument("robot generator: a chain needs 1 to " + std::to_string(kMaxJoints) +
                                  " joints, not " + std::to_string(options.joints));
    branches.push_back({"", options.joints, {}});
    description = "a chain of " + std::to_string(options.joints) + " joints";
    default_name = "chain" + std::to_string(options.joints);
  } else {
    branches = parseTreeSpec(options.tree);
    description = "the tree \"" + options.tree + "\"";
    bool preset = presetSpec(options.tree) != options.tree;
    default_name = preset ? options.tree : "tree" + std::to_string(countJoints(branches));
  }
  checkFraction("prismatic fraction", options.prismatic_fraction);
  checkFraction("continuous fraction", options.continuous_fraction);
  if (options.prismatic_fraction + options.continuous_fraction > 1.0)
    throw std::invalid_argument("robot generator: prismatic fraction " + num(options.prismatic_fraction) +
                                " and continuous fraction " + num(options.continuous_fraction) +
                                " add up to more than 1");
  const std::string name = options.name.empty() ? default_name : options.name;
  checkRobotName(name);

  // Whole numbers of prismatic and continuous joints.
  const int n = countJoints(branches);
  const int prismatic = static_cast<int>(std::lround(options.prismatic_fraction * n));
  const int continuous = std::min(n - prismatic, static_cast<int>(std::lround(options.continuous_fraction * n)));

  const std::string comment = "Generated by the robodiff robot generator: " + description + ", seed " +
                              std::to_string(options.seed) + ", prismatic fraction " +
                              num(options.prismatic_fraction) + ", continuous fraction " +
                              num(options.continuous_fraction) +
                              ". Regenerate it rather than editing it.";
  return Generator(options.seed).run(name, comment, branches, chain, prismatic, continuous);
}

}  // namespace robodiff
