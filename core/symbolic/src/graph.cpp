#include "robodiff/symbolic/graph.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace robodiff::symbolic {
namespace {

std::uint64_t bitsOf(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// True when c is a power of two whose reciprocal is an exact normal double, so that
// x / c == x * (1 / c) bit for bit.
bool hasExactReciprocal(double c) {
  int exponent = 0;
  const double mantissa = std::frexp(c, &exponent);
  return std::fabs(mantissa) == 0.5 && exponent > -1020 && exponent < 1020;
}

}  // namespace

GraphTooLarge::GraphTooLarge(std::size_t limit)
    : std::runtime_error("expression graph too large: more than " + std::to_string(limit) +
                         " nodes (the configured node limit, Graph::setNodeLimit)"),
      limit_(limit) {}

// The value of op applied to constant arguments (what the generated C computes).
double evaluateOp(Op op, double a, double b, double c) {
  switch (op) {
    case Op::Neg: return -a;
    case Op::Sin: return std::sin(a);
    case Op::Cos: return std::cos(a);
    case Op::Tan: return std::tan(a);
    case Op::Asin: return std::asin(a);
    case Op::Acos: return std::acos(a);
    case Op::Atan: return std::atan(a);
    case Op::Exp: return std::exp(a);
    case Op::Log: return std::log(a);
    case Op::Sqrt: return std::sqrt(a);
    case Op::Tanh: return std::tanh(a);
    case Op::Abs: return std::fabs(a);
    case Op::Add: return a + b;
    case Op::Sub: return a - b;
    case Op::Mul: return a * b;
    case Op::Div: return a / b;
    case Op::Atan2: return std::atan2(a, b);
    case Op::Pow: return std::pow(a, b);
    case Op::Min: return std::fmin(a, b);
    case Op::Max: return std::fmax(a, b);
    case Op::SelectPositive: return a > 0 ? b : c;
    case Op::Constant:
    case Op::Input: break;
  }
  throw std::logic_error("evaluateOp: not an operation");
}

const char* toString(Op op) {
  static const char* names[] = {"const", "input", "neg",  "sin",  "cos",   "tan",   "asin", "acos",
                                "atan",  "exp",   "log",  "sqrt", "tanh",  "abs",   "add",  "sub",
                                "mul",   "div",   "atan2", "pow", "min",   "max",   "select_positive"};
  return names[static_cast<int>(op)];
}

int arity(Op op) {
  if (op == Op::Constant || op == Op::Input) return 0;
  if (op == Op::SelectPositive) return 3;
  return op >= Op::Add ? 2 : 1;
}

bool isCommutative(Op op) { return op == Op::Add || op == Op::Mul || op == Op::Min || op == Op::Max; }

std::size_t Graph::KeyHash::operator()(const Key& k) const {
  std::uint64_t h = static_cast<std::uint64_t>(k.op) * 0x9E3779B97F4A7C15ull;
  for (std::uint64_t x : {static_cast<std::uint64_t>(k.a), static_cast<std::uint64_t>(k.b),
                          static_cast<std::uint64_t>(k.c), k.bits}) {
    h ^= x + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
  }
  // Final avalanche (MurmurHash3's fmix64): the table indexes by the low bits.
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return static_cast<std::size_t>(h);
}

Graph::Graph() {
  constant(0.0);  // id 0
  constant(1.0);  // id 1
}

Graph::Key Graph::keyOf(const Node& n) {
  return {n.op, n.args[0], n.args[1], n.args[2],
          n.op == Op::Constant ? bitsOf(n.value) : static_cast<std::uint64_t>(n.index)};
}

void Graph::rehash(std::size_t slot_count) {
  slots_.assign(slot_count, kEmptySlot);
  const std::size_t mask = slot_count - 1;
  for (NodeId id = 0; id < nodes_.size(); ++id) {
    std::size_t s = KeyHash{}(keyOf(nodes_[id])) & mask;
    while (slots_[s] != kEmptySlot) s = (s + 1) & mask;
    slots_[s] = id;
  }
}

void Graph::setNodeLimit(std::size_t limit) {
  // Node ids are 32 bits, with the all-ones id reserved for empty slots.
  node_limit_ = std::min<std::size_t>(limit, kEmptySlot);
}

NodeId Graph::add(const Node& n) {
  if (2 * (nodes_.size() + 1) > slots_.size()) rehash(std::max<std::size_t>(64, 2 * slots_.size()));
  const Key key = keyOf(n);
  const std::size_t mask = slots_.size() - 1;
  std::size_t s = KeyHash{}(key) & mask;
  for (; slots_[s] != kEmptySlot; s = (s + 1) & mask)
    if (keyOf(nodes_[slots_[s]]) == key) return slots_[s];
  if (nodes_.size() >= node_limit_) throw GraphTooLarge(node_limit_);
  const NodeId id = static_cast<NodeId>(nodes_.size());
  nodes_.push_back(n);
  slots_[s] = id;
  if (n.op == Op::Input) input_count_ = std::max(input_count_, n.index + 1);
  return id;
}

NodeId Graph::constant(double value) {
  // -0.0 is stored as 0.0: the rules already treat both as zero (x * 0 = 0), and one
  // zero node is what makes "structurally zero" a plain id test (id == zero()).
  if (value == 0.0) value = 0.0;
  Node n;
  n.op = Op::Constant;
  n.value = value;
  return add(n);
}

NodeId Graph::input(std::uint32_t index) {
  Node n;
  n.op = Op::Input;
  n.index = index;
  return add(n);
}

NodeId Graph::unary(Op op, NodeId a) {
  if (arity(op) != 1) throw std::logic_error(std::string("unary: ") + toString(op) + " is not unary");
  const Node& na = nodes_[a];
  if (na.op == Op::Constant) return constant(evaluateOp(op, na.value, 0, 0));
  if (op == Op::Neg && na.op == Op::Neg) return na.args[0];  // -(-x) = x
  if (op == Op::Neg && na.op == Op::Sub) return binary(Op::Sub, na.args[1], na.args[0]);  // -(x - y) = y - x
  if (op == Op::Abs && na.op == Op::Abs) return a;                            // |(|x|)| = |x|
  if (op == Op::Abs && na.op == Op::Neg) return unary(Op::Abs, na.args[0]);  // |-x| = |x|
  Node n;
  n.op = op;
  n.args[0] = a;
  return add(n);
}

NodeId Graph::binary(Op op, NodeId a, NodeId b) {
  if (arity(op) != 2) throw std::logic_error(std::string("binary: ") + toString(op) + " is not binary");
  const Node& na = nodes_[a];
  const Node& nb = nodes_[b];
  if (na.op == Op::Constant && nb.op == Op::Constant) return constant(evaluateOp(op, na.value, nb.value, 0));
  switch (op) {
    case Op::Add:
      if (isConstant(a, 0)) return b;
      if (isConstant(b, 0)) return a;
      if (nb.op == Op::Neg) return binary(Op::Sub, a, nb.args[0]);  // a + (-y) = a - y
      if (na.op == Op::Neg) return binary(Op::Sub, b, na.args[0]);  // (-x) + b = b - x
      break;
    case Op::Sub:
      if (a == b) return zero();
      if (isConstant(b, 0)) return a;
      if (isConstant(a, 0)) return unary(Op::Neg, b);
      if (nb.op == Op::Neg) return binary(Op::Add, a, nb.args[0]);  // a - (-y) = a + y
      break;
    case Op::Mul:
      if (isConstant(a, 0) || isConstant(b, 0)) return zero();
      if (isConstant(a, 1)) return b;
      if (isConstant(b, 1)) return a;
      if (isConstant(a, -1)) return unary(Op::Neg, b);
      if (isConstant(b, -1)) return unary(Op::Neg, a);
      if (na.op == Op::Neg && nb.op == Op::Neg) return binary(Op::Mul, na.args[0], nb.args[0]);
      // Pull negations out, so that they fold into a consumer's add/sub.
      if (na.op == Op::Neg) return unary(Op::Neg, binary(Op::Mul, na.args[0], b));
      if (nb.op == Op::Neg) return unary(Op::Neg, binary(Op::Mul, a, nb.args[0]));
      break;
    case Op::Div:
      if (isConstant(a, 0)) return zero();
      if (isConstant(b, 1)) return a;
      if (isConstant(b, -1)) return unary(Op::Neg, a);
      if (a == b) return one();
      if (na.op == Op::Neg) return unary(Op::Neg, binary(Op::Div, na.args[0], b));
      if (nb.op == Op::Neg) return unary(Op::Neg, binary(Op::Div, a, nb.args[0]));
      // Division by a power of two is an exact multiplication (cheaper in generated code).
      if (nb.op == Op::Constant && hasExactReciprocal(nb.value)) return binary(Op::Mul, a, constant(1.0 / nb.value));
      break;
    case Op::Pow:
      if (isConstant(b, 0)) return one();
      if (isConstant(b, 1)) return a;
      if (isConstant(b, 2)) return binary(Op::Mul, a, a);
      break;
    case Op::Min:
    case Op::Max:
      if (a == b) return a;
      break;
    default:
      break;
  }
  if (isCommutative(op) && a > b) std::swap(a, b);
  Node n;
  n.op = op;
  n.args[0] = a;
  n.args[1] = b;
  return add(n);
}

NodeId Graph::selectPositive(NodeId condition, NodeId if_positive, NodeId otherwise) {
  const Node& nc = nodes_[condition];
  if (nc.op == Op::Constant) return nc.value > 0 ? if_positive : otherwise;
  if (if_positive == otherwise) return if_positive;
  Node n;
  n.op = Op::SelectPositive;
  n.args[0] = condition;
  n.args[1] = if_positive;
  n.args[2] = otherwise;
  return add(n);
}

std::vector<double> Graph::evaluate(const std::vector<NodeId>& outputs, const std::vector<double>& inputs) const {
  NodeId last = 0;
  for (NodeId o : outputs) last = std::max(last, o);
  std::vector<double> value(static_cast<std::size_t>(last) + 1);
  for (NodeId id = 0; id <= last; ++id) {
    const Node& n = nodes_[id];
    if (n.op == Op::Constant) value[id] = n.value;
    else if (n.op == Op::Input) {
      if (n.index >= inputs.size()) throw std::out_of_range("Graph::evaluate: input " + std::to_string(n.index) + " not given");
      value[id] = inputs[n.index];
    } else {
      value[id] = evaluateOp(n.op, value[n.args[0]], value[n.args[1]], value[n.args[2]]);
    }
  }
  std::vector<double> out;
  out.reserve(outputs.size());
  for (NodeId o : outputs) out.push_back(value[o]);
  return out;
}

}  // namespace robodiff::symbolic
