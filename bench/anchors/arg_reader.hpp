// The anchors' programs read "--option [value]" arguments the same way: one option after
// another, its value taken on demand, a missing value named.
#pragma once

#include <stdexcept>
#include <string>

namespace anchors {

class ArgReader {
 public:
  ArgReader(int argc, char** argv) : argc_(argc), argv_(argv) {}

  // Moves to the next option; false past the last.
  bool next() { return ++index_ < argc_; }
  std::string option() const { return argv_[index_]; }
  // The current option's value (the following argument), consumed.
  std::string value() {
    if (index_ + 1 >= argc_) throw std::runtime_error("option " + option() + " needs a value");
    return argv_[++index_];
  }

 private:
  int argc_;
  char** argv_;
  int index_ = 0;
};

}  // namespace anchors
