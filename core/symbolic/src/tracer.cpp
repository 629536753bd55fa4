#include "robodiff/symbolic/tracer.hpp"

#include <stdexcept>

namespace robodiff::symbolic {

VecX<Sym> Tracer::addInputs(const std::string& name, int size) {
  if (size < 0) throw std::invalid_argument("Tracer::addInputs: negative size for '" + name + "'");
  for (const InputBlock& b : blocks_)
    if (b.name == name) throw std::invalid_argument("Tracer::addInputs: a block named '" + name + "' exists");
  InputBlock block{name, graph_->inputCount(), static_cast<std::uint32_t>(size)};
  VecX<Sym> x(size);
  for (int i = 0; i < size; ++i) x[i] = Sym(*graph_, graph_->input(block.first + static_cast<std::uint32_t>(i)));
  blocks_.push_back(block);
  return x;
}

const InputBlock& Tracer::block(const std::string& name) const {
  for (const InputBlock& b : blocks_)
    if (b.name == name) return b;
  throw std::out_of_range("Tracer: no input block named '" + name + "'");
}

std::vector<std::uint32_t> Tracer::indices(const std::vector<std::string>& names) const {
  std::vector<std::uint32_t> out;
  for (const std::string& name : names) {
    const InputBlock& b = block(name);
    for (std::uint32_t i = 0; i < b.size; ++i) out.push_back(b.first + i);
  }
  return out;
}

std::string Tracer::inputName(std::uint32_t index) const {
  for (const InputBlock& b : blocks_)
    if (index >= b.first && index < b.first + b.size) return b.name + "[" + std::to_string(index - b.first) + "]";
  return "input[" + std::to_string(index) + "]";
}

}  // namespace robodiff::symbolic
