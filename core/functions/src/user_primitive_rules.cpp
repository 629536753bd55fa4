#include "user_primitive_rules.hpp"

#include "robodiff/dynamics/aba_derivatives.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/dynamics/lie_group.hpp"
#include "robodiff/dynamics/minv.hpp"
#include "robodiff/dynamics/rnea_derivatives.hpp"
#include "robodiff/dynamics/shape_distance.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/substitute.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::detail {

using symbolic::Graph;
using symbolic::NodeId;
using symbolic::Sym;

MatX<Sym> sparseProduct(const MatX<Sym>& a, const MatX<Sym>& b) {
  MatX<Sym> out = MatX<Sym>::Zero(a.rows(), b.cols());
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index k = 0; k < a.cols(); ++k) {
      if (isZero(a(i, k))) continue;
      for (Eigen::Index j = 0; j < b.cols(); ++j) {
        if (isZero(b(k, j))) continue;
        out(i, j) = isZero(out(i, j)) ? Sym(a(i, k) * b(k, j)) : Sym(out(i, j) + a(i, k) * b(k, j));
      }
    }
  return out;
}

namespace {

// to += m, skipping m's structural zeros.
void addSparse(MatX<Sym>& to, const MatX<Sym>& m) {
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j)
      if (!isZero(m(i, j))) to(i, j) = isZero(to(i, j)) ? m(i, j) : Sym(to(i, j) + m(i, j));
}

}  // namespace

MatX<Sym> solveWithMassFactors(const Model& model, const MatX<Sym>& LD, const MatX<Sym>& B) {
  const std::vector<int> lambda = dofParents(model);
  const int n = model.nv;
  const MatX<Sym> N = inverseUnitFactor(lambda, LD);  // L^-1
  std::vector<Sym> inverse_diagonal;
  for (int i = 0; i < n; ++i) inverse_diagonal.push_back(Sym(1.0) / LD(i, i));
  MatX<Sym> X(n, B.cols());
  std::vector<Sym> z(static_cast<std::size_t>(n));
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    for (int i = 0; i < n; ++i) z[i] = B(i, c);
    for (int i = n - 1; i >= 0; --i)  // L^T y = b: y is nonzero on b's rows and their ancestors
      for (int j = lambda[i]; j >= 0; j = lambda[j])
        if (!isZero(z[i])) z[j] = z[j] - LD(i, j) * z[i];
    for (int i = 0; i < n; ++i) z[i] = z[i] * inverse_diagonal[i];
    // x = L^-1 z = N z: row r reads only the ancestors where z is nonzero, so a row on
    // another branch than b's rows costs the depth of their common ancestors.
    for (int r = 0; r < n; ++r) {
      Sym x = z[r];
      for (int k = lambda[r]; k >= 0; k = lambda[k])
        if (!isZero(z[k])) x = isZero(x) ? Sym(N(r, k) * z[k]) : Sym(x + N(r, k) * z[k]);
      X(r, c) = x;
    }
  }
  return X;
}

namespace {


Eigen::Index tangentColumnsOf(const PrimitiveCall& call) {
  for (const Value<Sym>* a : call.args)
    if (a->has_tangent) return a->d.cols();
  return 0;
}

// value's entries (row-major) as a Value with a tangent of `columns` zero columns.
Value<Sym> withTangent(const MatX<Sym>& m, Eigen::Index tangent_rows, Eigen::Index columns) {
  Value<Sym> out;
  out.m = m;
  out.has_tangent = true;
  out.d = MatX<Sym>::Zero(tangent_rows, columns);
  return out;
}

// d += partial x (argument k's tangent), when argument k has one.
void chain(MatX<Sym>& d, const MatX<Sym>& partial, const Value<Sym>& arg) {
  if (!arg.has_tangent) return;
  d += sparseProduct(partial, arg.d);
}

// The generic rule: the primitive traced in a scratch graph on fresh inputs plus a
// displacement (in the tangent space for configurations), differentiated there, copied into the
// function's graph with the inputs replaced by the arguments.
Value<Sym> scratchRule(const PrimitiveCall& call, bool configuration_result) {
  const PrimitiveContext& c = call.context;
  const Model& model = c.model;
  Graph scratch;
  if (c.node_limit) scratch.setNodeLimit(c.node_limit);
  symbolic::Tracer tracer(scratch);
  std::vector<NodeId> input_map;  // scratch input index -> node of the function's graph
  std::vector<VecX<Sym>> plain(call.vectors.size()), moved(call.vectors.size());
  std::vector<std::uint32_t> wrt;
  std::vector<std::pair<std::size_t, Eigen::Index>> blocks;  // (argument, tangent rows) in wrt order
  for (std::size_t k = 0; k < call.vectors.size(); ++k) {
    if (call.strings[k].size()) continue;
    const Value<Sym>& arg = *call.args[k];
    const std::string name = "p" + std::to_string(k);
    plain[k] = tracer.addInputs(name, static_cast<int>(call.vectors[k].size()));
    for (Eigen::Index i = 0; i < call.vectors[k].size(); ++i) input_map.push_back(call.vectors[k][i].nodeIn(*c.graph));
    moved[k] = plain[k];
    if (!arg.has_tangent) continue;
    // Differentiated w.r.t. a displacement d of the argument at d = 0 (a configuration
    // moved in its tangent space): the value at the plain arguments stays the reference
    // point a configuration result's tangent is measured from.
    const bool on_manifold = arg.configuration && hasFreeFlyer(model);
    const int width = on_manifold ? model.nv : static_cast<int>(call.vectors[k].size());
    const std::string displacement = "d" + std::to_string(k);
    const VecX<Sym> d = tracer.addInputs(displacement, width);
    for (int i = 0; i < width; ++i) input_map.push_back(c.graph->zero());
    moved[k] = on_manifold ? symbolic::integrateSecondOrder(model, plain[k], d) : VecX<Sym>(plain[k] + d);
    const std::vector<std::uint32_t> idx = tracer.indices({displacement});
    wrt.insert(wrt.end(), idx.begin(), idx.end());
    blocks.emplace_back(k, width);
  }
  const MatX<Sym> value = call.value(plain, call.strings);
  // A configuration's tangent: the difference from the value, to first order.
  const MatX<Sym> moved_value = call.value(moved, call.strings);
  const VecX<Sym> tangent_coordinates =
      configuration_result
          ? differenceConfiguration<Sym>(model, Eigen::Map<const VecX<Sym>>(value.data(), value.size()),
                                         Eigen::Map<const VecX<Sym>>(moved_value.data(), moved_value.size()))
          : VecX<Sym>();
  std::vector<NodeId> value_nodes, moved_nodes;
  for (Eigen::Index r = 0; r < value.rows(); ++r)
    for (Eigen::Index col = 0; col < value.cols(); ++col) {
      value_nodes.push_back(value(r, col).nodeIn(scratch));
      if (!configuration_result) moved_nodes.push_back(moved_value(r, col).nodeIn(scratch));
    }
  if (configuration_result)
    for (Eigen::Index i = 0; i < tangent_coordinates.size(); ++i) moved_nodes.push_back(tangent_coordinates[i].nodeIn(scratch));
  const symbolic::Jacobian J = symbolic::jacobian(scratch, moved_nodes, wrt);
  std::vector<NodeId> wanted = value_nodes;
  wanted.insert(wanted.end(), J.entries.begin(), J.entries.end());
  const std::vector<NodeId> copied = symbolic::copyCone(scratch, wanted, *c.graph, input_map);

  const Eigen::Index rows = static_cast<Eigen::Index>(moved_nodes.size());
  Value<Sym> out = withTangent(MatX<Sym>(value.rows(), value.cols()), rows, tangentColumnsOf(call));
  for (Eigen::Index k = 0; k < value.size(); ++k) out.m(k / value.cols(), k % value.cols()) = Sym(*c.graph, copied[k]);
  Eigen::Index offset = 0;
  for (const auto& [k, width] : blocks) {
    MatX<Sym> partial(rows, width);
    for (Eigen::Index r = 0; r < rows; ++r)
      for (Eigen::Index i = 0; i < width; ++i)
        partial(r, i) = Sym(*c.graph, copied[value.size() + r * J.cols + offset + i]);
    chain(out.d, partial, *call.args[k]);
    offset += width;
  }
  out.configuration = configuration_result;
  return out;
}

// rnea: tau and its three partials from one analytic sweep.
Value<Sym> rneaRule(const PrimitiveCall& call) {
  const Model& model = call.context.model;
  Data<Sym> data(model);
  MatX<Sym> dq, dv, da;
  computeRneaDerivatives(model, data, call.vectors[0], call.vectors[1], call.vectors[2], dq, dv, da);
  Value<Sym> out = withTangent(data.tau, model.nv, tangentColumnsOf(call));
  chain(out.d, dq, *call.args[0]);
  chain(out.d, dv, *call.args[1]);
  chain(out.d, da, *call.args[2]);
  return out;
}

// Adds tau's tangent `dtau` to `rhs`, the columns with one entry (a torque input's own
// tangent block) to `selected` instead; whether any went there.
bool splitTorqueTangent(const MatX<Sym>& dtau, MatX<Sym>& rhs, MatX<Sym>& selected) {
  bool any_selected = false;
  for (Eigen::Index c = 0; c < dtau.cols(); ++c) {
    Eigen::Index entries = 0;
    for (Eigen::Index r = 0; r < dtau.rows(); ++r) entries += isZero(dtau(r, c)) ? 0 : 1;
    (entries == 1 ? selected : rhs).col(c) += dtau.col(c);
    any_selected = any_selected || entries == 1;
  }
  return any_selected;
}

// aba: ddq = M^-1 (tau - nle); its tangent M^-1 (d tau - R_q dq - R_v dv), R the RNEA
// partials at a = ddq, by solves with M's tree factors; ddq, R and the factors from one
// sweep (dynamics/aba_derivatives.hpp; R goes unused without q or v tangents). tau's
// single-entry tangent columns take M^-1's columns instead, each symmetric pair computed
// once (inverseFromFactors), where solving would compute M^-1(r, c) and M^-1(c, r) apart.
Value<Sym> abaRule(const PrimitiveCall& call) {
  const Model& model = call.context.model;
  Data<Sym> data(model);
  const AbaDerivativeTerms<Sym> t =
      computeAbaDerivativeTerms(model, data, call.vectors[0], call.vectors[1], call.vectors[2]);
  Value<Sym> out = withTangent(t.ddq, model.nv, tangentColumnsOf(call));
  MatX<Sym> rhs = MatX<Sym>::Zero(model.nv, out.d.cols());
  chain(rhs, MatX<Sym>(-t.dtau_dq), *call.args[0]);
  chain(rhs, MatX<Sym>(-t.dtau_dv), *call.args[1]);
  MatX<Sym> selected = MatX<Sym>::Zero(model.nv, out.d.cols());
  const bool any_selected = call.args[2]->has_tangent && splitTorqueTangent(call.args[2]->d, rhs, selected);
  out.d = solveWithMassFactors(model, t.mass_factors, rhs);
  if (any_selected) addSparse(out.d, sparseProduct(inverseFromFactors(dofParents(model), t.mass_factors), selected));
  return out;
}

// distance: d = normal . (d c_a - d c_b) with the nearest points fixed on their bodies; a
// point p on a frame with origin o moves with J_lin - [p - o]x J_ang (world-aligned).
Value<Sym> distanceRule(const PrimitiveCall& call) {
  const PrimitiveContext& c = call.context;
  const Model& model = c.model;
  const UserShape& sa = c.function.shapes.at(call.strings[1]);
  const UserShape& sb = c.function.shapes.at(call.strings[2]);
  Data<Sym> data(model);
  computeJointJacobians(model, data, call.vectors[0]);
  const int fa = resolveFrameName(model, sa.frame, 1), fb = resolveFrameName(model, sb.frame, 1);
  auto placement = [&](int f) { return f < 0 ? SE3<Sym>() : framePlacement(model, data, f); };
  auto shape = [](const UserShape& s) {
    return s.kind == UserShape::Kind::Sphere ? Shape::sphere(s.a, s.radius) : Shape::capsule(s.a, s.b, s.radius);
  };
  const SE3<Sym> oMa = placement(fa), oMb = placement(fb);
  const ShapeDistance<Sym> r = shapeDistance(shape(sa), oMa, shape(sb), oMb);
  MatX<Sym> value(1, 1);
  value(0, 0) = r.distance;
  Value<Sym> out = withTangent(value, 1, tangentColumnsOf(call));
  // The row n^T J_point of each nearest point, then their difference chained with q's tangent.
  auto pointRow = [&](int f, const SE3<Sym>& oMf, const Vec3<Sym>& p) {
    MatX<Sym> row = MatX<Sym>::Zero(1, model.nv);
    if (f < 0) return row;
    const Matrix6X<Sym> J = frameJacobian(model, data, f, ReferenceFrame::LocalWorldAligned);
    const Vec3<Sym> lever_cross_n = (p - oMf.translation).cross(r.normal);
    for (int col = 0; col < model.nv; ++col)
      row(0, col) = r.normal.dot(J.col(col).head<3>()) + lever_cross_n.dot(J.col(col).tail<3>());
    return row;
  };
  chain(out.d, MatX<Sym>(pointRow(fa, oMa, r.point_a) - pointRow(fb, oMb, r.point_b)), *call.args[0]);
  return out;
}

}  // namespace

Value<Sym> tracePrimitive(const PrimitiveCall& call) {
  const bool configuration_result = call.name == "integrate";
  bool tangent = false;
  for (const Value<Sym>* a : call.args) tangent = tangent || a->has_tangent;
  if (!tangent) {
    Value<Sym> out;
    out.m = call.value(call.vectors, call.strings);
    out.configuration = configuration_result;
    return out;
  }
  if (call.context.primitive_rules) {
    if (call.name == "rnea") return rneaRule(call);
    if (call.name == "aba") return abaRule(call);
    if (call.name == "distance") return distanceRule(call);
  }
  return scratchRule(call, configuration_result);
}

}  // namespace robodiff::detail
