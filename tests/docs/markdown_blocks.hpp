// The fenced code blocks of a Markdown page that the docs tests act on: a block preceded
// by `<!-- runnable -->` is a shell block to run as written; one preceded by
// `<!-- file: NAME -->` is written to NAME before the page's runnable blocks run (so a
// page can show a source file and then the commands that build it).
#pragma once

#include <cstddef>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace robodiff::testing {

struct MarkedBlock {
  enum class Kind { Runnable, File } kind = Kind::Runnable;
  std::string file_name;  // Kind::File
  std::string text;       // the block's lines, without the fences
  std::size_t line = 0;   // 1-based line of the opening fence
};

inline std::string trimmed(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t\r") - begin + 1);
}

// Throws std::runtime_error naming the line when a marker is not followed by a fenced
// block (blank lines between them are allowed) or a block is never closed.
inline std::vector<MarkedBlock> markedBlocks(const std::string& markdown) {
  std::vector<std::string> lines;
  std::istringstream in(markdown);
  for (std::string l; std::getline(in, l);) lines.push_back(l);

  std::vector<MarkedBlock> blocks;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string marker = trimmed(lines[i]);
    MarkedBlock block;
    if (marker == "<!-- runnable -->") {
      block.kind = MarkedBlock::Kind::Runnable;
    } else if (marker.rfind("<!-- file:", 0) == 0 && marker.size() > 14 && marker.substr(marker.size() - 3) == "-->") {
      block.kind = MarkedBlock::Kind::File;
      block.file_name = trimmed(marker.substr(10, marker.size() - 13));
    } else {
      continue;
    }
    std::size_t open = i + 1;
    while (open < lines.size() && trimmed(lines[open]).empty()) ++open;
    if (open == lines.size() || trimmed(lines[open]).rfind("```", 0) != 0)
      throw std::runtime_error("line " + std::to_string(i + 1) + ": " + marker + " is not followed by a ``` block");
    std::size_t close = open + 1;
    while (close < lines.size() && trimmed(lines[close]) != "```") ++close;
    if (close == lines.size())
      throw std::runtime_error("line " + std::to_string(open + 1) + ": the ``` block is never closed");
    block.line = open + 1;
    for (std::size_t k = open + 1; k < close; ++k) block.text += lines[k] + "\n";
    blocks.push_back(block);
    i = close;
  }
  return blocks;
}

}  // namespace robodiff::testing
