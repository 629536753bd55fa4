// Identified inertials: conversion, consistency, and the URDF rewritten in place.
#include "robodiff/batch/urdf_inertials.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include <tinyxml.h>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/parameter_layout.hpp"
#include "robodiff/spatial/math.hpp"

namespace robodiff::batch {
namespace {

std::string number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

// What rounding may take off a principal moment or a triangle margin (kg m^2).
double roundingTolerance(const Eigen::Matrix<double, 10, 1>& p) {
  return p.allFinite() ? 1e-12 * p.tail<6>().cwiseAbs().maxCoeff() : 0.0;
}

// Whether the URDF loader takes a body that is not valid: it refuses a negative mass and an
// indefinite inertia, and a first moment needs a mass to become a centre of mass.
bool loaderAccepts(const Eigen::Matrix<double, 10, 1>& p, const BodyValidity& v) {
  return p.allFinite() && p[0] >= 0 && (p[0] > 0 || p.segment<3>(1).isZero(0.0)) &&
         v.principal_moments[0] >= -roundingTolerance(p);
}

// A replacement of text [offset, offset + length).
struct Edit {
  std::size_t offset = 0, length = 0;
  std::string text;
};

// Offsets of line starts, counting line breaks as TinyXML does ("\n", "\r", "\r\n", "\n\r").
std::vector<std::size_t> lineStarts(const std::string& text) {
  std::vector<std::size_t> starts{0};
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c != '\n' && c != '\r') continue;
    const char pair = c == '\n' ? '\r' : '\n';
    if (i + 1 < text.size() && text[i + 1] == pair) ++i;
    starts.push_back(i + 1);
  }
  return starts;
}

class Rewriter {
 public:
  Rewriter(const std::string& text, const std::string& source) : text_(text), source_(source), starts_(lineStarts(text)) {}

  [[noreturn]] void fail(const TiXmlNode* at, const std::string& what) const {
    throw IdentificationError(source_ + (at ? ":" + std::to_string(at->Row()) : std::string()) + ": " + what);
  }

  // The offset of an element's '<' in the text.
  std::size_t offsetOf(const TiXmlElement* e) const {
    const std::size_t row = static_cast<std::size_t>(e->Row()), col = static_cast<std::size_t>(e->Column());
    if (row < 1 || row > starts_.size() || col < 1) fail(e, "cannot locate <" + std::string(e->Value()) + ">");
    const std::size_t offset = starts_[row - 1] + col - 1;
    const std::string open = "<" + std::string(e->Value());
    if (text_.compare(offset, open.size(), open) != 0) fail(e, "cannot locate <" + std::string(e->Value()) + ">");
    return offset;
  }

  // The end of the start tag beginning at `offset` (just past its '>'), and whether it
  // closes itself ("/>"). Quoted attribute values may hold '>'.
  std::pair<std::size_t, bool> startTagEnd(std::size_t offset) const {
    char quote = 0;
    for (std::size_t i = offset; i < text_.size(); ++i) {
      const char c = text_[i];
      if (quote) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        return {i + 1, text_[i - 1] == '/'};
      }
    }
    throw IdentificationError(source_ + ": unterminated tag at offset " + std::to_string(offset));
  }

  // The offset of the closing tag "</name" after `from`, skipping comments and CDATA.
  std::size_t closingTag(std::size_t from, const std::string& name) const {
    const std::string close = "</" + name;
    for (std::size_t i = from; i < text_.size();) {
      const std::size_t next = text_.find('<', i);
      if (next == std::string::npos) break;
      if (text_.compare(next, 4, "<!--") == 0) {
        const std::size_t end = text_.find("-->", next + 4);
        if (end == std::string::npos) break;
        i = end + 3;
      } else if (text_.compare(next, 9, "<![CDATA[") == 0) {
        const std::size_t end = text_.find("]]>", next + 9);
        if (end == std::string::npos) break;
        i = end + 3;
      } else if (text_.compare(next, close.size(), close) == 0) {
        return next;
      } else {
        i = next + 1;
      }
    }
    throw IdentificationError(source_ + ": no </" + name + "> after offset " + std::to_string(from));
  }

  // [begin, end) of the whole element starting at `offset`.
  std::pair<std::size_t, std::size_t> elementSpan(std::size_t offset, const std::string& name) const {
    auto [tag_end, self_closing] = startTagEnd(offset);
    if (self_closing) return {offset, tag_end};
    const std::size_t close = closingTag(tag_end, name);
    return {offset, text_.find('>', close) + 1};
  }

  // The whitespace before `offset` on its line, when nothing else precedes it there.
  std::string indentAt(std::size_t offset) const {
    std::size_t start = offset;
    while (start > 0 && text_[start - 1] != '\n' && text_[start - 1] != '\r') --start;
    const std::string before = text_.substr(start, offset - start);
    return before.find_first_not_of(" \t") == std::string::npos ? before : std::string();
  }

  // The line break the file uses.
  std::string newline() const { return text_.find("\r\n") != std::string::npos ? "\r\n" : "\n"; }

  const std::string& text() const { return text_; }

 private:
  const std::string& text_;
  std::string source_;
  std::vector<std::size_t> starts_;
};

// An <inertial> element, its children indented by `indent` plus two spaces.
std::string inertialXml(const BodyInertial& b, const std::string& indent, const std::string& nl) {
  const Eigen::Matrix3d& I = b.inertia;
  const std::string inner = indent + "  ";
  return "<inertial>" + nl + inner + "<origin xyz=\"" + number(b.com.x()) + " " + number(b.com.y()) + " " +
         number(b.com.z()) + "\" rpy=\"0 0 0\"/>" + nl + inner + "<mass value=\"" + number(b.mass) + "\"/>" + nl +
         inner + "<inertia ixx=\"" + number(I(0, 0)) + "\" ixy=\"" + number(I(0, 1)) + "\" ixz=\"" + number(I(0, 2)) +
         "\" iyy=\"" + number(I(1, 1)) + "\" iyz=\"" + number(I(1, 2)) + "\" izz=\"" + number(I(2, 2)) + "\"/>" + nl +
         indent + "</inertial>";
}

}  // namespace

BodyInertial inertialFromParameters(const Eigen::Matrix<double, 10, 1>& p) {
  BodyInertial b;
  b.mass = p[0];
  Eigen::Matrix3d Io;
  Io << p[4], p[5], p[7], p[5], p[6], p[8], p[7], p[8], p[9];
  if (p[0] > 0) {
    b.com = p.segment<3>(1) / p[0];
    const Eigen::Matrix3d cx = skew<double>(b.com);
    b.inertia = Io + p[0] * cx * cx;
  } else {
    b.inertia = Io;
  }
  return b;
}

BodyValidity inertialValidity(const Eigen::Matrix<double, 10, 1>& p) {
  return checkBodyValidity(p, roundingTolerance(p));
}

UrdfRewrite rewriteUrdfInertials(const std::string& urdf_text, const std::string& source, const Model& model,
                                 const Eigen::VectorXd& parameters) {
  const ParameterLayout layout = parameterLayout(model);
  if (parameters.size() != layout.size())
    throw IdentificationError("rewriting " + source + ": " + std::to_string(parameters.size()) +
                              " parameters for a model with " + std::to_string(layout.size()));
  // What goes where: the composite on each carrier link, zero on the merged links.
  std::map<std::string, int> carrier;  // link -> joint
  std::map<std::string, std::string> merged_into;
  for (std::size_t j = 0; j < layout.bodies.size(); ++j) {
    carrier[layout.bodies[j].link] = static_cast<int>(j);
    for (const std::string& m : layout.bodies[j].merged_links) merged_into[m] = layout.bodies[j].link;
  }

  // The text is parsed without encoding handling, so that TinyXML's columns count bytes
  // (and a tab as one column), and after any UTF-8 byte-order mark.
  const std::size_t bom = urdf_text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  const std::string body = urdf_text.substr(bom);
  TiXmlDocument doc;
  doc.SetTabSize(1);
  doc.Parse(body.c_str(), nullptr, TIXML_ENCODING_LEGACY);
  if (doc.Error())
    throw IdentificationError(source + ":" + std::to_string(doc.ErrorRow()) + ": cannot parse the URDF: " +
                              doc.ErrorDesc());
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (!robot) throw IdentificationError(source + ": no <robot> element");
  Rewriter rw(body, source);
  const std::string nl = rw.newline();

  UrdfRewrite out;
  std::vector<Edit> edits;
  std::set<std::string> seen;
  for (const TiXmlElement* link = robot->FirstChildElement("link"); link; link = link->NextSiblingElement("link")) {
    const char* name_attr = link->Attribute("name");
    if (!name_attr) continue;
    const std::string name = name_attr;
    const TiXmlElement* inertial = link->FirstChildElement("inertial");
    if (auto c = carrier.find(name); c != carrier.end()) {
      seen.insert(name);
      const Eigen::Matrix<double, 10, 1> p = parameters.segment<10>(kParametersPerBody * c->second);
      const BodyValidity validity = inertialValidity(p);
      if (!validity.valid && !loaderAccepts(p, validity))
        rw.fail(link, "link '" + name + "': the identified inertial cannot be written: " + validity.message +
                          " (least squares does not enforce physical consistency; --physical does)");
      const BodyInertial b = inertialFromParameters(p);
      if (inertial) {
        const std::size_t at = rw.offsetOf(inertial);
        auto [begin, end] = rw.elementSpan(at, "inertial");
        edits.push_back({begin, end - begin, inertialXml(b, rw.indentAt(at), nl)});
      } else {  // no <inertial> yet: add one as the link's first child
        const std::size_t at = rw.offsetOf(link);
        const std::string indent = rw.indentAt(at);
        auto [tag_end, self_closing] = rw.startTagEnd(at);
        const std::string block = inertialXml(b, indent + "  ", nl);
        if (self_closing)
          edits.push_back({tag_end - 2, 2, ">" + nl + indent + "  " + block + nl + indent + "</link>"});
        else
          edits.push_back({tag_end, 0, nl + indent + "  " + block});
      }
      out.written.push_back(name);
    } else if (auto m = merged_into.find(name); m != merged_into.end() && inertial) {
      const std::size_t at = rw.offsetOf(inertial);
      auto [begin, end] = rw.elementSpan(at, "inertial");
      const std::string indent = rw.indentAt(at);
      edits.push_back({begin, end - begin,
                       "<!-- robodiff identify: merged into the identified inertial of link '" + m->second + "' -->" +
                           nl + indent + inertialXml(BodyInertial{}, indent, nl)});
      out.zeroed.push_back(name);
    }
  }
  for (const auto& [name, joint] : carrier)
    if (!seen.count(name)) throw IdentificationError(source + ": the URDF has no <link name=\"" + name + "\">");

  std::sort(edits.begin(), edits.end(), [](const Edit& a, const Edit& b) { return a.offset > b.offset; });
  std::string text = body;
  for (const Edit& e : edits) text.replace(e.offset, e.length, e.text);
  out.text = urdf_text.substr(0, bom) + text;
  return out;
}

}  // namespace robodiff::batch
