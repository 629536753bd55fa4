#include "robodiff/model/urdf_limits.hpp"

#include <algorithm>
#include <string_view>

#include "robodiff/model/model_error.hpp"

namespace robodiff {
namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// One pass over the text with an explicit depth counter: no recursion, no allocation
// beyond error messages.
class LimitScanner {
 public:
  LimitScanner(std::string_view xml, const UrdfLimits& limits, const std::string& source)
      : xml_(xml), limits_(limits), source_(source) {}

  void run() {
    if (xml_.size() > limits_.max_bytes)
      tooLarge("the URDF is " + std::to_string(xml_.size()) + " bytes", "max_bytes", xml_.size(),
               limits_.max_bytes);
    while (pos_ < xml_.size()) {
      std::size_t open = xml_.find('<', pos_);
      if (open == std::string_view::npos) break;
      pos_ = open;
      // Where the parsers disagree on where a construct ends (TinyXML ends "<?..." and
      // "<!..." at the first '>', TinyXML2 "<?..." at "?>"), the scan takes the end
      // that exposes more tags: it may count too many elements, never too few.
      if (startsWith("<!--")) skipPast("-->", 4);
      else if (startsWith("<![CDATA[")) skipPast("]]>", 9);
      else if (startsWith("<?") || startsWith("<!")) skipPast(">", 2);
      else if (startsWith("</")) endTag();
      else startTag();
    }
    checkCount("the URDF nests elements " + std::to_string(max_depth_) + " deep", "max_depth", max_depth_,
               limits_.max_depth);
    checkCount("the URDF has " + std::to_string(elements_) + " elements", "max_elements", elements_,
               limits_.max_elements);
    checkCount("the URDF has " + std::to_string(links_) + " links", "max_links", links_, limits_.max_links);
    checkCount("the URDF has " + std::to_string(joints_) + " joints", "max_joints", joints_, limits_.max_joints);
  }

 private:
  [[noreturn]] void tooLarge(const std::string& what, const char* limit_name, std::uint64_t value,
                             std::uint64_t limit) const {
    throw ModelTooLarge(source_ + ": " + what + "; the limit is " + limit_name + " = " + std::to_string(limit),
                        limit_name, value, limit);
  }

  void checkCount(const std::string& what, const char* limit_name, std::uint64_t value, std::uint64_t limit) const {
    if (value > limit) tooLarge(what, limit_name, value, limit);
  }

  // A name or value longer than its limit: reported with its line and first characters.
  void checkLength(std::size_t at, std::string_view text, const std::string& what, const char* limit_name,
                   std::uint64_t limit) const {
    if (text.size() <= limit) return;
    const auto line = 1 + std::count(xml_.begin(), xml_.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    const std::string shown(text.substr(0, 40));
    tooLarge("line " + std::to_string(line) + ": " + what + " of " + std::to_string(text.size()) +
                 " characters (\"" + shown + "...\")",
             limit_name, text.size(), limit);
  }

  bool startsWith(std::string_view prefix) const { return xml_.substr(pos_, prefix.size()) == prefix; }

  void skipPast(std::string_view terminator, std::size_t opener_length) {
    std::size_t end = xml_.find(terminator, pos_ + opener_length);
    pos_ = end == std::string_view::npos ? xml_.size() : end + terminator.size();
  }

  void endTag() {
    if (depth_ > 0) --depth_;
    std::size_t close = xml_.find('>', pos_);
    pos_ = close == std::string_view::npos ? xml_.size() : close + 1;
  }

  std::size_t skipSpace(std::size_t p) const {
    while (p < xml_.size() && isSpace(xml_[p])) ++p;
    return p;
  }

  std::size_t nameEnd(std::size_t p) const {
    while (p < xml_.size() && !isSpace(xml_[p]) && xml_[p] != '/' && xml_[p] != '>' && xml_[p] != '=' &&
           xml_[p] != '<')
      ++p;
    return p;
  }

  void countElement(std::string_view name, bool opens) {
    const std::uint64_t level = depth_ + 1;
    ++elements_;
    max_depth_ = std::max(max_depth_, level);
    if (level == 2 && name == "link") ++links_;
    if (level == 2 && name == "joint") ++joints_;
    if (opens) ++depth_;
  }

  void startTag() {
    const std::size_t name_begin = pos_ + 1;
    const std::size_t name_end = nameEnd(name_begin);
    if (name_end == name_begin) {  // a stray '<': the parser reports it
      ++pos_;
      return;
    }
    const std::string_view name = xml_.substr(name_begin, name_end - name_begin);
    checkLength(pos_, name, "an element name", "max_name_length", limits_.max_name_length);
    std::size_t p = name_end;
    while (true) {
      p = skipSpace(p);
      if (p >= xml_.size() || xml_[p] == '<') break;  // unterminated tag: the parser reports it
      if (xml_[p] == '>') {
        countElement(name, true);
        pos_ = p + 1;
        return;
      }
      if (xml_[p] == '/' && p + 1 < xml_.size() && xml_[p + 1] == '>') {
        countElement(name, false);
        pos_ = p + 2;
        return;
      }
      const std::size_t attribute_end = nameEnd(p);
      if (attribute_end == p) {  // a stray '/' or '='
        ++p;
        continue;
      }
      p = attribute(p, attribute_end);
      if (p == std::string_view::npos) break;
    }
    countElement(name, true);  // not closed by "/>": counted as open, as a parser may take it
    pos_ = std::min(p, xml_.size());
  }

  // Checks one attribute; returns where the tag continues (npos: unterminated value).
  std::size_t attribute(std::size_t begin, std::size_t end) {
    const std::string_view attribute_name = xml_.substr(begin, end - begin);
    checkLength(begin, attribute_name, "an attribute name", "max_name_length", limits_.max_name_length);
    std::size_t p = skipSpace(end);
    if (p >= xml_.size() || xml_[p] != '=') return p;
    p = skipSpace(p + 1);
    if (p >= xml_.size() || (xml_[p] != '"' && xml_[p] != '\'')) return p;
    const std::size_t close = xml_.find(xml_[p], p + 1);
    if (close == std::string_view::npos) return close;
    const std::string_view value = xml_.substr(p + 1, close - p - 1);
    const bool names_something = attribute_name == "name" || attribute_name == "link" || attribute_name == "joint";
    if (names_something)
      checkLength(begin, value, "a name", "max_name_length", limits_.max_name_length);
    else
      checkLength(begin, value, "an attribute value", "max_attribute_length", limits_.max_attribute_length);
    return close + 1;
  }

  std::string_view xml_;
  const UrdfLimits& limits_;
  const std::string& source_;
  std::size_t pos_ = 0;
  std::uint64_t depth_ = 0, max_depth_ = 0, elements_ = 0, links_ = 0, joints_ = 0;
};

}  // namespace

void checkUrdfLimits(const std::string& xml, const UrdfLimits& limits, const std::string& source) {
  LimitScanner(xml, limits, source).run();
}

}  // namespace robodiff
