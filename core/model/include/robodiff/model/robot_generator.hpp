// Random but physically valid robots of any size and shape, written as URDF: the
// project's test and example robots, and the way to measure how every cost grows with
// the number of joints.
//
// What a generated robot holds:
// - a root link "base_link" with an inertia (it becomes the floating body when the
//   URDF is loaded with RootJoint::FreeFlyer; with RootJoint::Fixed it is dropped);
// - branches of moving joints (revolute by default; prismatic and continuous ones on
//   request), with varied axes (x, y, z, negative axes, unaligned unit axes), varied
//   origins (translations; rpy of zero, of multiples of pi/2, or generic) and sane
//   limits (lower < upper, positive effort and velocity);
// - on every link a random inertia: mass in [0.2, 5] kg (the base [1, 5] kg), centre
//   of mass off the origin, positive principal moments that satisfy the triangle
//   inequality, principal axes rotated by the inertial origin's rpy, by off-diagonal
//   tensor entries, or by both;
// - fixed joints, so that loading exercises the merging of links: a "tool" link at the
//   end of every branch that has no sub-branches, and now and then a "spacer" link
//   between two moving joints.
//
// The text depends only on the options: the same options give the same bytes on every
// machine. Random numbers come from std::mt19937_64 (whose sequence the standard fixes)
// through our own mappings, every drawn number lies on a binary grid so that all later
// arithmetic is exact (fused multiply-add or not), and no sin/cos is evaluated.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace robodiff {

enum class RobotKind { Chain, Tree };

// One branch of a tree: `length` moving joints in series; its children hang from its
// last link.
struct TreeBranch {
  std::string name;  // prefix of its joint and link names, e.g. "left_arm", "branch2"
  int length = 0;
  std::vector<TreeBranch> children;
};

// Tree specs. A spec lists the branches that hang from the base:
//
//   list   := group ("," group)*
//   group  := [label ":"] [count "x"] length ["(" list ")"]
//   label  := letter (letter | digit | "_")*
//
// "4x6" is four branches of six joints; "2x6,2x7" two of six and two of seven;
// "3(2x4)" a trunk of three joints whose last link carries two branches of four (each
// of the `count` branches of a group gets its own copy of the parenthesised list).
// Names: a labelled group names its branches label, or label0, label1, ... when
// count > 1; unlabelled branches are branch0, branch1, ... at the base and
// <parent>_0, <parent>_1, ... below a branch; indices run over all siblings, zero-padded
// when there are ten or more (so that urdfdom's name order is the spec's order).
// Names must be unique. Joints are <branch>_joint1..N, their links <branch>_link1..N.
//
// Presets, accepted in place of a spec:
inline constexpr const char* kQuadrupedTreeSpec =
    "front_left_leg:3,front_right_leg:3,hind_left_leg:3,hind_right_leg:3";  // "quadruped"
inline constexpr const char* kHumanoidTreeSpec =
    "left_leg:6,right_leg:6,torso:2(left_arm:7,right_arm:7,head:2)";  // "humanoid", 30 joints

// Parses a spec or a preset name; throws std::invalid_argument saying what is wrong
// and where.
std::vector<TreeBranch> parseTreeSpec(const std::string& spec);

// Number of moving joints in the branches, sub-branches included.
int countJoints(const std::vector<TreeBranch>& branches);

inline constexpr int kMaxGeneratedJoints = 10000;

// Robot names: 1 to 200 letters, digits, '_', '.' or '-' (safe in XML and file names).
bool isValidRobotName(const std::string& name);

struct GeneratorOptions {
  RobotKind kind = RobotKind::Chain;
  int joints = 6;                    // Chain: the number of moving joints (1 to kMaxGeneratedJoints)
  std::string tree;                  // Tree: a spec or preset (see above)
  std::uint64_t seed = 0;
  std::string name;                  // robot name; empty: "chain<N>", or the preset's
                                     // name, or "tree<N>"; see isValidRobotName
  double prismatic_fraction = 0.0;   // share of the moving joints that are prismatic
  double continuous_fraction = 0.0;  // share that are continuous (revolute, no limits)
};

// The URDF text. A chain is one unnamed branch: joint1..N, link1..N, "tool". Throws
// std::invalid_argument for bad options (joint count, fractions outside [0, 1] or
// summing above 1, a bad spec or name). The fractions are rounded to a whole number of
// joints, placed at random.
std::string generateRobotUrdf(const GeneratorOptions& options);

}  // namespace robodiff
