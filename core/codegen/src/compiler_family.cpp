#include "compiler_family.hpp"

#include <regex>

namespace robodiff::codegen::detail {

bool isGnuGcc(const std::string& text) {
  return text.find("Free Software Foundation") != std::string::npos && text.find("clang") == std::string::npos;
}

bool isClang(const std::string& text) { return text.find("clang version") != std::string::npos; }

int majorVersion(const std::string& text) {
  static const std::regex version(R"((\d{1,4})\.\d+\.\d+)");  // at most 4 digits: no overflow
  const std::string first_line = text.substr(0, text.find('\n'));
  std::smatch m;
  return std::regex_search(first_line, m, version) ? std::stoi(m[1].str()) : 0;
}

}  // namespace robodiff::codegen::detail
