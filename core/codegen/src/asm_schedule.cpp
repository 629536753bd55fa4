#include "asm_schedule.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <queue>
#include <utility>
#include <vector>

namespace robodiff::codegen::detail {
namespace {

// The core's floating-point pipes as the model sees them (Zen 4 and Ice Lake alike): two
// that multiply, two that add, bitwise and shuffles anywhere, four issued a cycle; stores
// beside them.
enum class Pipe : std::uint8_t { Multiply, Add, Any, Store };
constexpr int kMultiplyPipes = 2, kAddPipes = 2, kIssueWidth = 4;
// How far ahead of the first operation not yet placed the schedule takes one: measured,
// 32 beat 16, 40, 48 and no bound (docs/assembly-backend.md, "Order").
constexpr std::uint32_t kWindow = 32;

Pipe pipeOf(MCode code) {
  switch (code) {
    case MCode::Mul: case MCode::Fma: case MCode::Div: case MCode::Sqrt: return Pipe::Multiply;
    case MCode::Add: case MCode::Sub: return Pipe::Add;
    case MCode::Store: case MCode::Store4: return Pipe::Store;
    default: return Pipe::Any;
  }
}

int latencyOf(MCode code) {
  switch (code) {
    case MCode::Add: case MCode::Sub: case MCode::Mul: return 3;
    case MCode::Fma: return 4;
    case MCode::Div: return 13;
    case MCode::Sqrt: return 20;
    case MCode::Pack2: case MCode::Dup: case MCode::High: case MCode::Low: case MCode::Pack4: return 2;
    case MCode::Store: case MCode::Store4: return 0;
    default: return 1;
  }
}

// Units of the schedule: an operation, or an output group's store with the packing of its
// elements (wide values, never spilled, are made just before their store).
class ListScheduler {
 public:
  explicit ListScheduler(const AsmProgram& program) : p_(program), n_(program.ops.size()) {}

  // The new order, or nothing where the chains are short against the multiplications
  // (the pipes bound the function then, and its order keeps fewer values live).
  std::optional<std::vector<std::uint32_t>> order() {
    if (!formUnits()) return std::nullopt;
    linkUnits();
    if (!latencyMatters()) return std::nullopt;
    std::vector<std::uint32_t> out;
    out.reserve(n_);
    placed_.assign(n_, false);
    for (std::uint32_t u = 0; u < n_; ++u)
      if (isUnit(u) && waiting_[u] == 0) pending_.push({0, u});
    for (int cycle = 0; out.size() < n_; ++cycle) {
      admitReady(cycle, out);
      issueCycle(cycle, out);
    }
    return out;
  }

 private:
  bool isUnit(std::uint32_t i) const { return unit_[i] == i; }
  bool isWide(std::uint32_t i) const { return p_.ops[i].dst != kNoValue && p_.wide[p_.ops[i].dst]; }

  // Each wide operation joins the unit of the operation reading its value; false where a
  // wide value is read by two units.
  bool formUnits() {
    std::vector<std::uint32_t> reader(p_.values(), kNoValue);
    unit_.resize(n_);
    packing_.resize(n_);
    for (std::uint32_t i = n_; i-- > 0;) {
      const MOp& op = p_.ops[i];
      unit_[i] = isWide(i) ? reader[op.dst] : i;
      if (unit_[i] == kNoValue) return false;
      if (unit_[i] != i) packing_[unit_[i]].insert(packing_[unit_[i]].begin(), i);
      for (std::uint32_t s : op.src) {
        if (s == kNoValue || !p_.wide[s]) continue;
        if (reader[s] != kNoValue && reader[s] != unit_[i]) return false;
        reader[s] = unit_[i];
      }
    }
    return true;
  }
  // Edges between units (each value's producing unit to its readers' units) and each
  // unit's height: its latency and the longest chain of latencies after it.
  void linkUnits() {
    std::vector<std::uint32_t> producer(p_.values(), kNoValue);
    users_.resize(n_);
    waiting_.assign(n_, 0);
    ready_at_.assign(n_, 0);
    for (std::uint32_t i = 0; i < n_; ++i) {
      const MOp& op = p_.ops[i];
      for (std::uint32_t s : op.src)
        if (s != kNoValue && producer[s] != kNoValue && unit_[producer[s]] != unit_[i]) {
          users_[unit_[producer[s]]].push_back(unit_[i]);
          ++waiting_[unit_[i]];
        }
      if (op.dst != kNoValue) producer[op.dst] = i;
      if (op.dst2 != kNoValue) producer[op.dst2] = i;
    }
    height_.assign(n_, 0);
    for (std::uint32_t u = n_; u-- > 0;) {
      if (!isUnit(u)) continue;
      int after = 0;
      for (std::uint32_t v : users_[u]) after = std::max(after, height_[v]);
      height_[u] = latencyOf(p_.ops[u].code) + after;
    }
  }
  // The longest chain at least a quarter of the time the multiplications take the pipes.
  bool latencyMatters() const {
    int longest = 0, multiplies = 0;
    for (std::uint32_t u = 0; u < n_; ++u) {
      if (!isUnit(u)) continue;
      longest = std::max(longest, height_[u]);
      multiplies += pipeOf(p_.ops[u].code) == Pipe::Multiply;
    }
    return 4 * kMultiplyPipes * longest >= multiplies;
  }

  // Units whose operands are ready by `cycle` become candidates; stores go at once.
  // Stores of no computed value (zeros, inputs) go at cycle 0 in the program's order,
  // before any computed value is ready: a group of four cleared whole stays before the
  // values stored into it.
  void admitReady(int cycle, std::vector<std::uint32_t>& out) {
    while (!pending_.empty() && pending_.top().first <= cycle) {
      const std::uint32_t u = pending_.top().second;
      pending_.pop();
      if (pipeOf(p_.ops[u].code) == Pipe::Store) issue(u, cycle, out);
      else available_.push_back(u);
    }
  }
  // As many candidates as the pipes take, the longest chain first; only units within
  // kWindow operations of the first unit not yet placed (whose operands are all placed),
  // so values live about as long as in the program's order.
  void issueCycle(int cycle, std::vector<std::uint32_t>& out) {
    int used[2] = {0, 0};
    for (int issued = 0; issued < kIssueWidth; ++issued) {
      std::size_t best = available_.size();
      for (std::size_t k = 0; k < available_.size(); ++k) {
        const std::uint32_t u = available_[k];
        const Pipe pipe = pipeOf(p_.ops[u].code);
        if (u > first_unplaced_ + kWindow) continue;
        if ((pipe == Pipe::Multiply && used[0] == kMultiplyPipes) || (pipe == Pipe::Add && used[1] == kAddPipes))
          continue;
        if (best == available_.size() || height_[u] > height_[available_[best]] ||
            (height_[u] == height_[available_[best]] && u < available_[best]))
          best = k;
      }
      if (best == available_.size()) return;
      const std::uint32_t u = available_[best];
      available_.erase(available_.begin() + static_cast<std::ptrdiff_t>(best));
      const Pipe pipe = pipeOf(p_.ops[u].code);
      if (pipe == Pipe::Multiply || pipe == Pipe::Add) ++used[pipe == Pipe::Add];
      issue(u, cycle, out);
    }
  }
  // Places unit u (its wide operations, in order, then u) and readies its users.
  void issue(std::uint32_t u, int cycle, std::vector<std::uint32_t>& out) {
    for (std::uint32_t i : packing_[u]) {
      out.push_back(i);
      placed_[i] = true;
    }
    out.push_back(u);
    placed_[u] = true;
    while (first_unplaced_ < n_ && (placed_[first_unplaced_] || !isUnit(first_unplaced_))) ++first_unplaced_;
    const int done = cycle + latencyOf(p_.ops[u].code);
    for (std::uint32_t v : users_[u]) {
      ready_at_[v] = std::max(ready_at_[v], done);
      if (--waiting_[v] == 0) pending_.push({ready_at_[v], v});
    }
  }

  const AsmProgram& p_;
  const std::uint32_t n_;
  std::vector<std::uint32_t> unit_;                 // per operation, its unit's last operation
  std::vector<std::vector<std::uint32_t>> packing_;  // per unit, its wide operations in order
  std::vector<std::vector<std::uint32_t>> users_;  // per unit, the units reading it
  std::vector<int> waiting_, ready_at_, height_;
  std::vector<bool> placed_;
  std::uint32_t first_unplaced_ = 0;
  using Timed = std::pair<int, std::uint32_t>;
  std::priority_queue<Timed, std::vector<Timed>, std::greater<>> pending_;  // by the cycle its operands are ready
  std::vector<std::uint32_t> available_;
};

}  // namespace

bool scheduleForLatency(AsmProgram& program) {
  for (const MOp& op : program.ops)
    if (op.code == MCode::KernelBegin) return false;
  const std::optional<std::vector<std::uint32_t>> order = ListScheduler(program).order();
  if (!order) return false;
  std::vector<MOp> ops;
  ops.reserve(order->size());
  for (std::uint32_t i : *order) ops.push_back(program.ops[i]);
  program.ops = std::move(ops);
  return true;
}

}  // namespace robodiff::codegen::detail
