#include "user_primitives.hpp"

#include "robodiff/dynamics/all.hpp"
#include "robodiff/dynamics/lie_group.hpp"
#include "robodiff/dynamics/shape_distance.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/language/suggest.hpp"
#include "user_primitive_rules.hpp"

namespace robodiff::detail {

using symbolic::Sym;

const std::vector<PrimitiveSignature>& primitiveSignatures() {
  using A = ArgKind;
  static const std::vector<PrimitiveSignature> all = {
      {"rnea", {A::Configuration, A::Velocity, A::Velocity}, "nv: joint torques for (q, v, a)"},
      {"aba", {A::Configuration, A::Velocity, A::Velocity}, "nv: joint accelerations for (q, v, tau)"},
      {"crba", {A::Configuration}, "nv x nv: the mass matrix M(q)"},
      {"minv", {A::Configuration}, "nv x nv: M(q)^-1"},
      {"nle", {A::Configuration, A::Velocity}, "nv: C(q, v) v + g(q)"},
      {"gravity", {A::Configuration}, "nv: g(q)"},
      {"regressor", {A::Configuration, A::Velocity, A::Velocity}, "nv x 10 njoints: the joint-torque regressor"},
      {"com", {A::Configuration}, "3: the centre of mass in the world"},
      {"com_jacobian", {A::Configuration}, "3 x nv: d com / d q"},
      {"frame_position", {A::Configuration, A::Frame}, "3: a frame's origin in the world"},
      {"frame_rotation", {A::Configuration, A::Frame}, "3 x 3: a frame's orientation in the world"},
      {"frame_placement", {A::Configuration, A::Frame}, "3 x 4: [R | p] of a frame in the world"},
      {"frame_jacobian", {A::Configuration, A::Frame, A::Reference}, "6 x nv: a frame's Jacobian"},
      {"frame_velocity", {A::Configuration, A::Velocity, A::Frame, A::Reference}, "6: a frame's velocity [linear; angular]"},
      {"kinetic_energy", {A::Configuration, A::Velocity}, "scalar: v^T M(q) v / 2"},
      {"potential_energy", {A::Configuration}, "scalar: -m g . com(q)"},
      {"integrate", {A::Configuration, A::Velocity}, "configuration: q (+) dq"},
      {"difference", {A::Configuration, A::Configuration}, "nv: the dq with q0 (+) dq = q1"},
      {"distance", {A::Configuration, A::Shape, A::Shape}, "scalar: signed distance between two shapes"},
  };
  return all;
}

const PrimitiveSignature* findPrimitive(const std::string& name) {
  for (const PrimitiveSignature& s : primitiveSignatures())
    if (name == s.name) return &s;
  return nullptr;
}

int resolveFrameName(const Model& model, const std::string& name, int column) {
  if (const std::optional<int> f = model.findFrame(name)) return *f;
  if (name == "world") return -1;
  std::vector<std::string> names = {"world"};
  for (const Frame& f : model.frames) names.push_back(f.name);
  throw EvalError(column, language::quote(name) + " is not a frame of " + (model.name.empty() ? std::string("the model") : language::boundedText(model.name)) +
                              language::didYouMean(name, names));
}

namespace {


const char* argKindText(ArgKind k) {
  switch (k) {
    case ArgKind::Configuration: return "a configuration";
    case ArgKind::Velocity: return "a vector of nv";
    case ArgKind::Frame: return "a frame name in quotes";
    case ArgKind::Reference: return "'LOCAL', 'WORLD' or 'LOCAL_WORLD_ALIGNED'";
    case ArgKind::Shape: return "a shape name in quotes";
  }
  return "?";
}

// Checks the arguments against the signature: count, strings where names go, sizes.
template <class S>
void checkArguments(const PrimitiveContext& c, const PrimitiveSignature& sig, const std::vector<PrimitiveArg<S>>& args,
                    int column) {
  const std::size_t optional = !sig.args.empty() && sig.args.back() == ArgKind::Reference ? 1 : 0;
  if (args.size() > sig.args.size() || args.size() + optional < sig.args.size())
    throw EvalError(column, std::string(sig.name) + "() takes " + std::to_string(sig.args.size() - optional) +
                                (optional ? " or " + std::to_string(sig.args.size()) : "") + " arguments, got " +
                                std::to_string(args.size()));
  const Model& m = c.model;
  for (std::size_t k = 0; k < args.size(); ++k) {
    const ArgKind kind = sig.args[k];
    const PrimitiveArg<S>& a = args[k];
    const bool wants_string = kind == ArgKind::Frame || kind == ArgKind::Reference || kind == ArgKind::Shape;
    const std::string where = std::string(sig.name) + "() argument " + std::to_string(k + 1);
    if (wants_string != a.is_string)
      throw EvalError(a.column, where + " must be " + argKindText(kind) + (a.is_string ? ", not a string" : ""));
    if (kind == ArgKind::Frame) resolveFrameName(m, a.text, a.column);
    if (kind == ArgKind::Shape && !c.function.shapes.count(a.text)) {
      std::vector<std::string> names;
      for (const auto& [name, _] : c.function.shapes) names.push_back(name);
      throw EvalError(a.column, language::quote(a.text) + " is not a shape of the spec's \"shapes\"" +
                                    (names.empty() ? std::string(" (it has none)") : language::didYouMean(a.text, names)));
    }
    if (kind == ArgKind::Reference) {
      try {
        parseReferenceFrame(a.text);
      } catch (const std::invalid_argument&) {
        throw EvalError(a.column, where + ": " + language::quote(a.text) + " is not LOCAL, WORLD or LOCAL_WORLD_ALIGNED");
      }
    }
    if (kind == ArgKind::Velocity && (a.value.configuration || a.value.cols() != 1 || a.value.rows() != m.nv))
      throw EvalError(a.column, where + " must be a vector of nv = " + std::to_string(m.nv) + ", got " + shapeOf(a.value));
    if (kind == ArgKind::Configuration) {
      const bool coordinates = !a.value.configuration && a.value.cols() == 1 && a.value.rows() == m.nq;
      if (!a.value.configuration && !(coordinates && !hasFreeFlyer(m)))
        throw EvalError(a.column, where + " must be a configuration (an input declared \"configuration\" or integrate(...))" +
                                      (hasFreeFlyer(m) ? "" : " or a vector of nq = " + std::to_string(m.nq)) + ", got " +
                                      shapeOf(a.value));
    }
  }
}

template <class S> VecX<S> vectorOf(const Value<S>& v) { return Eigen::Map<const VecX<S>>(v.m.data(), v.m.size()); }

Shape shapeOf(const UserShape& s) {
  Shape out;
  out.kind = s.kind == UserShape::Kind::Sphere ? Shape::Kind::Sphere : Shape::Kind::Capsule;
  out.a = s.a;
  out.b = s.b;
  out.radius = s.radius;
  return out;
}

template <class S> SE3<S> placementOf(const Model& model, Data<S>& data, int frame) {
  return frame < 0 ? SE3<S>() : framePlacement(model, data, frame);
}

// d com / d q: each body's centre of mass moves with the world-frame columns of the
// joints above it (v + w x p), weighted by its share of the mass.
template <class S> MatX<S> comJacobianValue(const Model& m, Data<S>& data, const VecX<S>& q) {
  computeJointJacobians(m, data, q);
  double total = 0;
  for (int j = 0; j < m.njoints(); ++j) total += m.bodies[j].mass;
  MatX<S> J = MatX<S>::Zero(3, m.nv);
  for (int j = 0; j < m.njoints(); ++j) {
    const auto& body = asScalar<S>(m.bodies[j]);
    const Vec3<S> p = data.oMi[j].act(body.lever);
    const S share = body.mass / S(total);
    for (int k = j; k >= 0; k = m.joints[k].parent)
      for (int c = m.joints[k].idx_v; c < m.joints[k].idx_v + m.joints[k].nv; ++c) {
        const Vec3<S> lin = data.J.col(c).template head<3>(), ang = data.J.col(c).template tail<3>();
        J.col(c) += share * (lin + ang.cross(p));
      }
  }
  return J;
}

}  // namespace

// The value of a primitive at vector arguments `v` (configurations as coordinates) and
// string arguments `s` (empty where the argument is a vector).
template <class S>
MatX<S> primitiveValue(const PrimitiveContext& c, const std::string& name, const std::vector<VecX<S>>& v,
                       const std::vector<std::string>& s) {
  const Model& m = c.model;
  Data<S> data(m);
  auto reference = [&](std::size_t k) { return k < s.size() && !s[k].empty() ? parseReferenceFrame(s[k]) : ReferenceFrame::LocalWorldAligned; };
  if (name == "rnea") return rnea(m, data, v[0], v[1], v[2]);
  if (name == "aba")
    return c.aba_by_factors ? forwardDynamicsByFactors(m, data, v[0], v[1], v[2]) : aba(m, data, v[0], v[1], v[2]);
  if (name == "crba") return crba(m, data, v[0]);
  if (name == "minv") return computeMinverse(m, data, v[0]);
  if (name == "nle") return nonLinearEffects(m, data, v[0], v[1]);
  if (name == "gravity") return computeGeneralizedGravity(m, data, v[0]);
  if (name == "regressor") return jointTorqueRegressor(m, data, v[0], v[1], v[2]);
  if (name == "com") return centerOfMass(m, data, v[0]);
  if (name == "kinetic_energy") {
    const MatX<S>& M = crba(m, data, v[0]);
    MatX<S> e(1, 1);
    e(0, 0) = S(0.5) * v[1].dot(M * v[1]);
    return e;
  }
  if (name == "potential_energy") {
    const Vec3<S> com = centerOfMass(m, data, v[0]);
    MatX<S> e(1, 1);
    e(0, 0) = -data.mass * (S(m.gravity[0]) * com[0] + S(m.gravity[1]) * com[1] + S(m.gravity[2]) * com[2]);
    return e;
  }
  if (name == "com_jacobian") return comJacobianValue(m, data, v[0]);
  if (name == "integrate") return integrateConfiguration(m, v[0], v[1]);
  if (name == "difference") return differenceConfiguration(m, v[0], v[1]);
  // The world frame does not move: its Jacobian and velocity are zero.
  if (name == "frame_jacobian") {
    const int f = resolveFrameName(m, s[1], 1);
    return f < 0 ? MatX<S>(MatX<S>::Zero(6, m.nv)) : MatX<S>(computeFrameJacobian(m, data, v[0], f, reference(2)));
  }
  if (name == "frame_velocity") {
    const int f = resolveFrameName(m, s[2], 1);
    if (f < 0) return MatX<S>::Zero(6, 1);
    const Matrix6X<S> J = computeFrameJacobian(m, data, v[0], f, reference(3));
    return J * v[1];
  }
  if (name == "distance") {
    const UserShape& a = c.function.shapes.at(s[1]);
    const UserShape& b = c.function.shapes.at(s[2]);
    forwardKinematics(m, data, v[0]);
    const int fa = resolveFrameName(m, a.frame, 1), fb = resolveFrameName(m, b.frame, 1);
    MatX<S> d(1, 1);
    d(0, 0) = shapeDistance(shapeOf(a), placementOf(m, data, fa), shapeOf(b), placementOf(m, data, fb)).distance;
    return d;
  }
  if (name == "frame_position") {
    const int f = resolveFrameName(m, s[1], 1);
    return f < 0 ? MatX<S>(MatX<S>::Zero(3, 1)) : MatX<S>(framePosition<S>(m, v[0], f));
  }
  // frame_rotation, frame_placement.
  forwardKinematics(m, data, v[0]);
  const SE3<S> oMf = placementOf(m, data, resolveFrameName(m, s[1], 1));
  if (name == "frame_rotation") return oMf.rotation;
  MatX<S> out(3, 4);
  out.template leftCols<3>() = oMf.rotation;
  out.col(3) = oMf.translation;
  return out;
}

template <class S>
void splitArguments(const std::vector<PrimitiveArg<S>>& args, std::vector<VecX<S>>& v, std::vector<std::string>& s) {
  for (const PrimitiveArg<S>& a : args) {
    v.push_back(a.is_string ? VecX<S>() : vectorOf(a.value));
    s.push_back(a.is_string ? a.text : std::string());
  }
}

Value<double> callPrimitive(const PrimitiveContext& context, const PrimitiveSignature& signature,
                            const std::vector<PrimitiveArg<double>>& args, int column) {
  checkArguments(context, signature, args, column);
  std::vector<VecX<double>> v;
  std::vector<std::string> s;
  splitArguments(args, v, s);
  Value<double> out;
  out.m = primitiveValue<double>(context, signature.name, v, s);
  out.configuration = std::string(signature.name) == "integrate";
  return out;
}

Value<Sym> callPrimitive(const PrimitiveContext& context, const PrimitiveSignature& signature,
                         const std::vector<PrimitiveArg<Sym>>& args, int column) {
  checkArguments(context, signature, args, column);
  std::vector<VecX<Sym>> v;
  std::vector<std::string> s;
  splitArguments(args, v, s);
  std::vector<const Value<Sym>*> values;
  for (const PrimitiveArg<Sym>& a : args) values.push_back(&a.value);
  const std::string name = signature.name;
  PrimitiveCall call{context, name, v, s, values, {}};
  call.value = [&context, name](const std::vector<VecX<Sym>>& x, const std::vector<std::string>& strings) {
    return primitiveValue<Sym>(context, name, x, strings);
  };
  return tracePrimitive(call);
}

template MatX<double> primitiveValue<double>(const PrimitiveContext&, const std::string&, const std::vector<VecX<double>>&,
                                             const std::vector<std::string>&);

}  // namespace robodiff::detail
