#include "output/bench_report.hpp"

#include <cmath>
#include <cstdio>
#include <map>

namespace robodiff::cli::bench {

namespace {

using nlohmann::json;

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// Three significant digits without an exponent.
std::string significant(double v) {
  if (!std::isfinite(v)) return "-";
  const double a = std::fabs(v);
  if (a >= 100) return format("%.0f", v);
  if (a >= 10) return format("%.1f", v);
  if (a >= 1) return format("%.2f", v);
  if (a >= 0.1) return format("%.3f", v);
  return format("%.4f", v);
}

std::string bytesText(double b) {
  if (b >= 1024.0 * 1024 * 1024) return format("%.2f GiB", b / (1024.0 * 1024 * 1024));
  if (b >= 1024.0 * 1024) return significant(b / (1024.0 * 1024)) + " MiB";
  if (b >= 1024.0) return significant(b / 1024.0) + " KiB";
  return format("%.0f B", b);
}

std::string unitText(Unit u) {
  switch (u) {
    case Unit::Microseconds:
      return "µs";
    case Unit::Seconds:
      return "s";
    case Unit::Bytes:
      return "bytes";
    case Unit::Count:
      return "";
  }
  return "";
}

std::string valueText(const Row& r) {
  switch (r.unit) {
    case Unit::Microseconds:
      return significant(r.value);
    case Unit::Seconds:
      return r.value < 0.001 ? format("%.4f", r.value) : format("%.3f", r.value);
    case Unit::Bytes:
      return bytesText(r.value);
    case Unit::Count:
      return format("%.0f", r.value);
  }
  return "";
}

// What the other rows call a row in their ratio column.
std::string shortName(const std::vector<Row>& rows, const std::string& name) {
  for (const Row& r : rows)
    if (r.name == name) return r.short_label.empty() ? r.label : r.short_label;
  return name;
}

std::string ratiosText(const std::vector<Row>& rows, const Row& r) {
  std::string s;
  for (const Ratio& q : r.ratios) {
    if (!s.empty()) s += "; ";
    s += significant(q.value) + "x " + shortName(rows, q.to);
  }
  return s;
}

// Display width of UTF-8 text (one column per code point).
std::size_t width(const std::string& s) {
  std::size_t n = 0;
  for (unsigned char c : s) n += (c & 0xC0) != 0x80;
  return n;
}

using Cells = std::vector<std::vector<std::string>>;  // [0] is the header

void printAligned(std::ostream& out, const Cells& cells, const std::vector<bool>& right_aligned) {
  std::vector<std::size_t> w(cells[0].size(), 0);
  for (const auto& row : cells)
    for (std::size_t c = 0; c < row.size(); ++c) w[c] = std::max(w[c], width(row[c]));
  auto line = [&](const std::vector<std::string>& row) {
    std::string s;
    for (std::size_t c = 0; c < row.size(); ++c) {
      const std::string pad(w[c] - width(row[c]), ' ');
      s += c ? "  " : "";
      s += right_aligned[c] ? pad + row[c] : row[c] + (c + 1 < row.size() ? pad : "");
    }
    while (!s.empty() && s.back() == ' ') s.pop_back();
    out << s << "\n";
  };
  line(cells[0]);
  std::size_t total = 0;
  for (std::size_t c = 0; c < w.size(); ++c) total += w[c] + (c ? 2 : 0);
  out << std::string(total, '-') << "\n";
  for (std::size_t r = 1; r < cells.size(); ++r) line(cells[r]);
}

void printMarkdownTable(std::ostream& out, const Cells& cells, const std::vector<bool>& right_aligned) {
  auto line = [&](const std::vector<std::string>& row) {
    out << "|";
    for (const std::string& c : row) out << " " << (c.empty() ? " " : c) << " |";
    out << "\n";
  };
  line(cells[0]);
  out << "|";
  for (bool r : right_aligned) out << (r ? "---:|" : "---|");
  out << "\n";
  for (std::size_t r = 1; r < cells.size(); ++r) line(cells[r]);
}

Cells evaluationCells(const Report& rep) {
  Cells cells = {{"row", "value", "unit", "ratio", "target", "anchor (other projects)", "status"}};
  for (const Row& r : rep.evaluation)
    cells.push_back({r.label, valueText(r), unitText(r.unit), ratiosText(rep.evaluation, r),
                     r.target ? r.target->text : "", r.anchor, r.status()});
  return cells;
}
const std::vector<bool> kEvaluationRight = {false, true, false, false, false, false, false};

const std::vector<std::pair<std::string, std::string>> kGenerationColumns = {
    {"trace", "trace s"},
    {"differentiate", "differentiate s"},
    {"assemble", "assemble s"},
    {"emit", "emit s"},
    {"compile", "compile s"},
    {"total", "total s"},
    {"compiler_peak_memory", "compiler peak"},
    {"process_peak_memory", "robodiff peak"},
    {"operations", "operations"},
    {"parts", "parts"},
    {"source", "C source"},
    {"library", "library"},
};

Cells generationCells(const Report& rep) {
  Cells cells;
  std::vector<std::string> header = {"function"};
  for (const auto& [field, title] : kGenerationColumns) header.push_back(title);
  for (const char* h : {"target", "anchor (other projects)", "status"}) header.push_back(h);
  cells.push_back(header);
  for (const std::string& fn : rep.generation_functions) {
    std::map<std::string, const Row*> by_field;
    for (const Row& r : rep.generation)
      if (r.group == fn) by_field[r.field] = &r;
    std::vector<std::string> row = {fn};
    std::string targets, anchor, status;
    for (const auto& [field, title] : kGenerationColumns) {
      auto it = by_field.find(field);
      row.push_back(it == by_field.end() ? "-" : valueText(*it->second));
    }
    bool memory_target = false;
    for (const auto& [field, r] : by_field) {
      if (r->target && (field == "compiler_peak_memory" || field == "process_peak_memory"))
        memory_target = true;  // the same for every build: one entry below
      else if (r->target)
        targets += (targets.empty() ? "" : "; ") + field + " " + r->target->text;
      if (!r->anchor.empty()) anchor += (anchor.empty() ? "" : "; ") + r->anchor;
      const std::string s = r->status();
      if (s == "MISS" || (s == "PASS" && status.empty())) status = s;
    }
    if (memory_target) targets += std::string(targets.empty() ? "" : "; ") + "peaks < 1 GiB";
    row.push_back(targets);
    row.push_back(anchor);
    row.push_back(status);
    cells.push_back(row);
  }
  return cells;
}

std::vector<bool> generationRight() {
  std::vector<bool> r = {false};
  for (std::size_t k = 0; k < kGenerationColumns.size(); ++k) r.push_back(true);
  r.insert(r.end(), {false, false, false});
  return r;
}

std::string baseText(const Report& rep) { return rep.floating_base ? "floating base" : "fixed base"; }

const char* kRatioNote = "ratio: this row's time / the named row's time, measured in the same run";
const char* kGenerationNote =
    "Generation is cold (no cache): trace, differentiate, assemble the graph, emit C, compile; total is the wall "
    "clock of all of it. Peaks: largest resident set of one compiler process tree, and of this robodiff process "
    "so far (target for both: < 1 GiB for every build).";

}  // namespace

const Ratio* Row::ratio(const std::string& to) const {
  for (const Ratio& r : ratios)
    if (r.to == to) return &r;
  return nullptr;
}

std::string Row::status() const {
  if (!target) return "";
  double v = value;
  if (!target->ratio_to.empty()) {
    const Ratio* r = ratio(target->ratio_to);
    if (!r) return "";
    v = r->value;
  }
  return std::isfinite(v) && v <= target->limit ? "PASS" : "MISS";
}

void Report::printText(std::ostream& out) const {
  out << "robodiff bench: " << robot << " (" << urdf << "), " << baseText(*this) << ", nq = " << nq << ", nv = " << nv
      << "\n";
  out << "machine: " << machine << "\ngenerated code: " << code_flags << "\ntiming: " << timing << "\n";
  if (!anchor_source.empty()) out << "anchors: " << anchor_source << "\n";
  out << "\nEvaluation (" << kRatioNote << ")\n\n";
  printAligned(out, evaluationCells(*this), kEvaluationRight);
  out << "\nGeneration\n\n";
  printAligned(out, generationCells(*this), generationRight());
  out << "\n" << kGenerationNote << "\n";
}

void Report::printMarkdown(std::ostream& out) const {
  out << "### " << robot << " (" << baseText(*this) << ", nq = " << nq << ", nv = " << nv << ")\n\n";
  out << "Machine: " << machine << ". Generated code: " << code_flags << ". Timing: " << timing << ".";
  if (!anchor_source.empty()) out << " Anchors: " << anchor_source << ".";
  out << "\n\n";
  out << "Evaluation (" << kRatioNote << "):\n\n";
  printMarkdownTable(out, evaluationCells(*this), kEvaluationRight);
  out << "\nGeneration:\n\n";
  printMarkdownTable(out, generationCells(*this), generationRight());
  out << "\n" << kGenerationNote << "\n\n";
}

json Report::toJson() const {
  auto rowJson = [](const Row& r) {
    json j = {{"name", r.name}, {"label", r.label}};
    switch (r.unit) {
      case Unit::Microseconds:
        j["us_per_call"] = r.value;
        break;
      case Unit::Seconds:
        j["seconds"] = r.value;
        break;
      case Unit::Bytes:
        j["bytes"] = r.value;
        break;
      case Unit::Count:
        j["count"] = r.value;
        break;
    }
    if (!r.ratios.empty()) {
      json ratios = json::object();
      for (const Ratio& q : r.ratios) ratios[q.to] = q.value;
      j["ratios"] = ratios;
    }
    if (r.target) {
      j["target"] = {{"limit", r.target->limit},
                     {"of", r.target->ratio_to.empty() ? "value" : "ratio to " + r.target->ratio_to},
                     {"text", r.target->text}};
      j["status"] = r.status();
    }
    if (!r.anchor.empty()) j["anchor"] = r.anchor;
    return j;
  };
  json rows = json::array();
  for (const Row& r : evaluation) rows.push_back(rowJson(r));
  for (const Row& r : generation) rows.push_back(rowJson(r));
  return {{"robot", robot},     {"urdf", urdf},     {"floating_base", floating_base},
          {"nq", nq},           {"nv", nv},         {"machine", machine},
          {"code", code_flags}, {"timing", timing}, {"anchors", anchor_source},
          {"checks", checks},   {"rows", rows}};
}

}  // namespace robodiff::cli::bench
