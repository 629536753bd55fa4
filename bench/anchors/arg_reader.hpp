// What the anchors' programs share around their work: reading "--option [value]"
// arguments (one option after another, its value taken on demand, a missing value named)
// and turning an exception into an error line and exit status 2.
#pragma once

#include <cstdio>
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

// A program's main: `run`'s exit status, or 2 with "<program>: error: <what>" on stderr.
template <class Run>
int guardedMain(const char* program, Run run) {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  }
}

}  // namespace anchors
