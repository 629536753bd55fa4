#include "robodiff/model/canonical.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <openssl/evp.h>

namespace robodiff {
namespace {

// Shortest round-trip spelling is not needed: %.17g is exact and deterministic.
void number(std::string& out, double x) {
  if (x == 0.0) x = 0.0;  // -0 and +0 are the same quantity
  char buf[40];
  if (std::isinf(x)) std::snprintf(buf, sizeof buf, x > 0 ? " inf" : " -inf");
  else std::snprintf(buf, sizeof buf, " %.17g", x);
  out += buf;
}

template <class Derived> void numbers(std::string& out, const Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) number(out, m(i, j));
}

void quoted(std::string& out, const std::string& s) {
  out += " \"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  out += '"';
}

void placement(std::string& out, const SE3<double>& m) {
  out += " R";
  numbers(out, m.rotation);
  out += " p";
  numbers(out, m.translation);
}

}  // namespace

std::string canonicalForm(const Model& model) {
  // Version 2: the numbers are computed portably (portable_geometry.hpp), the same on
  // every host; version 1 forms depended on -march and on the CPU.
  std::string out = "robodiff-model 2\n";
  out += model.root == RootJoint::FreeFlyer ? "root freeflyer\n" : "root fixed\n";
  out += "gravity";
  numbers(out, model.gravity);
  out += '\n';
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    out += "joint";
    quoted(out, joint.name);
    out += std::string(" ") + toString(joint.type) + (joint.continuous ? " continuous" : "");
    out += " parent " + std::to_string(joint.parent) + " axis";
    numbers(out, joint.axis);
    placement(out, joint.placement);
    out += " lower";
    numbers(out, joint.lower);
    out += " upper";
    numbers(out, joint.upper);
    out += " velocity";
    numbers(out, joint.velocity_limit);
    out += " effort";
    numbers(out, joint.effort_limit);
    out += " damping";
    numbers(out, joint.damping);
    out += " friction";
    numbers(out, joint.friction);
    const Inertia<double>& body = model.bodies[j];
    out += "\nbody mass";
    number(out, body.mass);
    out += " com";
    numbers(out, body.lever);
    out += " inertia";
    numbers(out, body.inertia);
    out += '\n';
  }
  for (const Frame& f : model.frames) {
    out += "frame";
    quoted(out, f.name);
    out += std::string(" ") + toString(f.type) + " parent " + std::to_string(f.parent_joint);
    placement(out, f.placement);
    out += '\n';
  }
  return out;
}

std::string sha256Hex(std::string_view bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 failed (OpenSSL EVP_Digest)");
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += hex[digest[i] >> 4];
    out += hex[digest[i] & 15];
  }
  return out;
}

std::string canonicalHash(const Model& model) { return sha256Hex(canonicalForm(model)); }

}  // namespace robodiff
