#pragma once
// Identified inertial parameters as URDF inertials, and the URDF rewritten with them.
//
// A body's standard parameters [m, mc, I_o] (joint frame, I_o about the frame's origin)
// become a URDF <inertial>: mass m, origin xyz = c = mc / m (rpy 0: the link frame's axes),
// and the inertia about the centre of mass, I_c = I_o + m [c]x [c]x (parallel-axis theorem).
//
// The regressor's bodies are composite: a joint's child link (its carrier) plus every link
// fixed to it. The written URDF puts the whole identified composite on the carrier link
// and sets the merged links' inertials to zero (mass 0, inertia 0), with a comment saying
// where their inertia went; loading the written URDF gives back exactly the identified
// parameters. Links fixed to the world (no moving joint above them) are left alone.
//
// Everything else in the file is kept byte for byte: the original text is parsed
// (TinyXML) only to find the <inertial> elements, which are replaced in the text.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/batch/physical_validity.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

struct BodyInertial {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      // centre of mass in the link frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about the centre of mass, link axes
};

// The inertial of one body's 10 standard parameters (mass <= 0: com 0, inertia I_o).
BodyInertial inertialFromParameters(const Eigen::Matrix<double, 10, 1>& p);

// Whether one body's parameters are physically consistent: batch/optimization's
// checkBodyValidity (mass > 0, the inertia about the centre of mass positive definite, its
// principal moments within the triangle inequalities), with rounding allowed: moments and
// triangle margins down to -1e-12 times the body's largest inertia entry count, so that a
// body on the boundary (a thin rod: principal moments 0, L, L) is consistent.
BodyValidity inertialValidity(const Eigen::Matrix<double, 10, 1>& p);

struct UrdfRewrite {
  std::string text;                  // the new URDF
  std::vector<std::string> written;  // links given the identified composite inertial
  std::vector<std::string> zeroed;   // merged links whose inertial was set to zero
};

// The URDF `urdf_text` (from which `model` was loaded) with the inertials of the standard
// parameter vector `parameters` (10 per joint). Throws IdentificationError naming the link
// when a body cannot be written as one the URDF loader accepts (a negative mass, a first
// moment without mass, an indefinite inertia about the centre of mass; a body only breaking
// the triangle inequality is written), or when the text cannot be parsed.
UrdfRewrite rewriteUrdfInertials(const std::string& urdf_text, const std::string& source, const Model& model,
                                 const Eigen::VectorXd& parameters);

}  // namespace robodiff::batch
