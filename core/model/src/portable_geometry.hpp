// The arithmetic that turns a URDF's numbers into the model's (rotations from rpy,
// placements composed across fixed joints, inertias rotated, moved and merged, axes
// normalised), written so that it gives the same bits for every -march and on every
// x86-64 host: plain scalar IEEE double code in portable_geometry.cpp, compiled with
// -ffp-contract=off (no fused multiply-add) and outside unity batches, with sin/cos
// from portable_trig.hpp. Eigen's expressions would vectorise, and hence round, in an
// order that depends on the instruction set. The model's identity (canonical.hpp)
// hashes these numbers.
#pragma once

#include "robodiff/spatial/inertia.hpp"
#include "robodiff/spatial/se3.hpp"

namespace robodiff::portable {

// Rz(yaw) * Ry(pitch) * Rx(roll): the URDF's fixed-axis roll-pitch-yaw rotation.
Mat3<double> rpyRotation(double roll, double pitch, double yaw);

// a * b: the placement aMc from aMb and bMc.
SE3<double> compose(const SE3<double>& a, const SE3<double>& b);

// r * i * r^T, exactly symmetric (the upper triangle is computed and mirrored).
Mat3<double> rotateInertia(const Mat3<double>& r, const Mat3<double>& i);

// A body's inertia given in frame b, expressed in frame a with aMb.
Inertia<double> transformInertia(const Inertia<double>& body, const SE3<double>& aMb);

// Rigid union of two bodies in the same frame (parallel-axis theorem), exactly
// symmetric (from the upper triangles); two massless bodies keep only the sum of their
// rotational inertias.
Inertia<double> mergeInertias(const Inertia<double>& a, const Inertia<double>& b);

// v / |v| (v unchanged when it is zero).
Vec3<double> normalized(const Vec3<double>& v);

}  // namespace robodiff::portable
