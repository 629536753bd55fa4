// A parser and validator of the Prometheus text exposition format (0.0.4), written from
// the format's description, for tests of what robodiffd's /metrics serves:
//  - lines are "# HELP name text", "# TYPE name type", other comments, blank, or samples
//    `name{label="value",...} value [timestamp]`;
//  - names and label names are well formed; label values use only the \\ \" \n escapes;
//  - a family's TYPE comes before its samples and once; its samples are contiguous and
//    named after it (histograms: name_bucket with an le label, name_sum, name_count);
//  - no series appears twice; counters are not negative;
//  - per histogram series: buckets ascending in le, counts non-decreasing, a le="+Inf"
//    bucket that equals _count, and a _sum.
#pragma once

#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace robodiff::testing {

struct PromSample {
  std::string name;
  std::map<std::string, std::string> labels;
  double value = 0;
};

struct PromFamily {
  std::string name, type = "untyped", help;
  std::vector<PromSample> samples;
};

struct PromText {
  std::vector<PromFamily> families;
  std::vector<std::string> errors;  // empty: the text is valid

  const PromFamily* family(std::string_view name) const {
    for (const PromFamily& f : families)
      if (f.name == name) return &f;
    return nullptr;
  }
  // The value of the sample `name` with exactly these labels.
  std::optional<double> value(std::string_view name, const std::map<std::string, std::string>& labels = {}) const {
    for (const PromFamily& f : families)
      for (const PromSample& s : f.samples)
        if (s.name == name && s.labels == labels) return s.value;
    return std::nullopt;
  }
  std::string errorText() const {
    std::string out;
    for (const std::string& e : errors) out += e + "\n";
    return out;
  }
};

namespace prom_detail {

inline bool nameChar(char c, bool first, bool colon) {
  const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || (colon && c == ':');
  return alpha || (!first && c >= '0' && c <= '9');
}
inline bool validName(std::string_view n, bool colon) {
  if (n.empty()) return false;
  for (std::size_t i = 0; i < n.size(); ++i)
    if (!nameChar(n[i], i == 0, colon)) return false;
  return true;
}
inline std::optional<double> parseValue(std::string_view v) {
  if (v == "+Inf" || v == "Inf") return HUGE_VAL;
  if (v == "-Inf") return -HUGE_VAL;
  if (v == "NaN") return std::nan("");
  if (v.empty()) return std::nullopt;
  const std::string s(v);
  char* end = nullptr;
  const double d = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return std::nullopt;
  return d;
}
// The series key of a sample without its le label (histogram grouping).
inline std::string seriesKey(const std::map<std::string, std::string>& labels, bool drop_le) {
  std::string key;
  for (const auto& [k, v] : labels)
    if (!(drop_le && k == "le")) key += k + "=" + v + ",";
  return key;
}

// Parses a sample line; false with why.
inline bool parseSample(std::string_view line, PromSample& s, std::string& why) {
  std::size_t i = 0;
  while (i < line.size() && line[i] != '{' && line[i] != ' ') ++i;
  s.name = std::string(line.substr(0, i));
  if (!validName(s.name, true)) return why = "bad metric name '" + s.name + "'", false;
  if (i < line.size() && line[i] == '{') {
    ++i;
    while (true) {
      if (i < line.size() && line[i] == '}') {
        ++i;
        break;
      }
      std::size_t eq = line.find('=', i);
      if (eq == std::string_view::npos) return why = "label without '='", false;
      const std::string label(line.substr(i, eq - i));
      if (!validName(label, false)) return why = "bad label name '" + label + "'", false;
      if (eq + 1 >= line.size() || line[eq + 1] != '"') return why = "label value not quoted", false;
      std::string value;
      std::size_t j = eq + 2;
      for (;; ++j) {
        if (j >= line.size()) return why = "unterminated label value", false;
        if (line[j] == '"') break;
        if (line[j] == '\\') {
          if (++j >= line.size()) return why = "dangling escape", false;
          if (line[j] == 'n') value += '\n';
          else if (line[j] == '\\' || line[j] == '"') value += line[j];
          else return why = std::string("bad escape \\") + line[j], false;
        } else {
          value += line[j];
        }
      }
      if (!s.labels.emplace(label, value).second) return why = "label '" + label + "' twice", false;
      i = j + 1;
      if (i < line.size() && line[i] == ',') ++i;
      else if (i < line.size() && line[i] == '}') continue;
      else return why = "expected ',' or '}' after a label", false;
    }
  }
  if (i >= line.size() || line[i] != ' ') return why = "no space before the value", false;
  std::string_view rest = line.substr(i + 1);
  const std::size_t sp = rest.find(' ');
  const std::string_view value = rest.substr(0, sp);
  const auto parsed = parseValue(value);
  if (!parsed) return why = "bad value '" + std::string(value) + "'", false;
  s.value = *parsed;
  if (sp != std::string_view::npos) {  // a timestamp: integer milliseconds
    const std::string_view ts = rest.substr(sp + 1);
    if (ts.empty() || ts.find_first_not_of("-0123456789") != std::string_view::npos)
      return why = "bad timestamp '" + std::string(ts) + "'", false;
  }
  return true;
}

inline void checkHistogram(const PromFamily& f, std::vector<std::string>& errors) {
  struct Series {
    std::vector<std::pair<double, double>> buckets;  // (le, count) in order
    std::optional<double> sum, count;
  };
  std::map<std::string, Series> series;
  for (const PromSample& s : f.samples) {
    Series& r = series[seriesKey(s.labels, true)];
    if (s.name == f.name + "_bucket") {
      const auto le = s.labels.find("le");
      if (le == s.labels.end()) {
        errors.push_back(f.name + ": a bucket without le");
        continue;
      }
      const auto bound = parseValue(le->second);
      if (!bound) errors.push_back(f.name + ": bad le '" + le->second + "'");
      else r.buckets.emplace_back(*bound, s.value);
    } else if (s.name == f.name + "_sum") {
      r.sum = s.value;
    } else if (s.name == f.name + "_count") {
      r.count = s.value;
    }
  }
  for (const auto& [key, r] : series) {
    const std::string where = f.name + "{" + key + "}";
    if (!r.sum) errors.push_back(where + ": no _sum");
    if (!r.count) errors.push_back(where + ": no _count");
    if (r.buckets.empty() || !std::isinf(r.buckets.back().first)) {
      errors.push_back(where + ": the last bucket is not le=\"+Inf\"");
      continue;
    }
    for (std::size_t i = 1; i < r.buckets.size(); ++i) {
      if (!(r.buckets[i].first > r.buckets[i - 1].first)) errors.push_back(where + ": le not ascending");
      if (r.buckets[i].second < r.buckets[i - 1].second) errors.push_back(where + ": bucket counts not cumulative");
    }
    if (r.count && r.buckets.back().second != *r.count)
      errors.push_back(where + ": le=\"+Inf\" bucket " + std::to_string(r.buckets.back().second) + " != _count " +
                       std::to_string(*r.count));
  }
}

}  // namespace prom_detail

inline PromText parsePrometheusText(std::string_view text) {
  using namespace prom_detail;
  PromText out;
  std::set<std::string> declared, seen_series;
  PromFamily* current = nullptr;
  auto familyOf = [&](const std::string& name) -> PromFamily& {
    if (current != nullptr && current->name == name) return *current;
    if (declared.count(name) != 0) out.errors.push_back("family " + name + " is not contiguous");
    declared.insert(name);
    out.families.push_back({});
    out.families.back().name = name;
    current = &out.families.back();
    return *current;
  };
  if (!text.empty() && text.back() != '\n') out.errors.push_back("the text does not end with a newline");
  std::size_t number = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    const std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++number;
    const std::string where = "line " + std::to_string(number) + " '" + std::string(line) + "': ";
    if (line.empty()) continue;
    if (line.starts_with("# HELP ") || line.starts_with("# TYPE ")) {
      const std::string_view rest = line.substr(7);
      const std::size_t sp = rest.find(' ');
      const std::string name(rest.substr(0, sp));
      const std::string arg = sp == std::string_view::npos ? "" : std::string(rest.substr(sp + 1));
      if (!validName(name, true)) {
        out.errors.push_back(where + "bad metric name");
        continue;
      }
      PromFamily& f = familyOf(name);
      if (line[2] == 'H') {
        if (!f.help.empty()) out.errors.push_back(where + "second HELP");
        for (std::size_t i = 0; i < arg.size(); ++i)
          if (arg[i] == '\\' && (i + 1 == arg.size() || (arg[i + 1] != '\\' && arg[i + 1] != 'n')))
            out.errors.push_back(where + "bad escape in HELP");
          else if (arg[i] == '\\') ++i;
        f.help = arg;
      } else {
        static const std::set<std::string> types = {"counter", "gauge", "histogram", "summary", "untyped"};
        if (types.count(arg) == 0) out.errors.push_back(where + "unknown type");
        if (!f.samples.empty()) out.errors.push_back(where + "TYPE after samples");
        f.type = arg;
      }
      continue;
    }
    if (line.front() == '#') continue;  // another comment
    PromSample s;
    std::string why;
    if (!parseSample(line, s, why)) {
      out.errors.push_back(where + why);
      continue;
    }
    // The family: the current one when the name is its own or (histogram/summary) a suffixed one.
    std::string base = s.name;
    if (current != nullptr && (current->type == "histogram" || current->type == "summary"))
      for (const char* suffix : {"_bucket", "_sum", "_count"})
        if (s.name == current->name + suffix) base = current->name;
    PromFamily& f = familyOf(base);
    if (f.type == "histogram" && s.name == f.name) out.errors.push_back(where + "histogram sample without a suffix");
    if (f.type == "counter" && !(s.value >= 0)) out.errors.push_back(where + "negative counter");
    if (!seen_series.insert(s.name + "{" + seriesKey(s.labels, false) + "}").second)
      out.errors.push_back(where + "series appears twice");
    f.samples.push_back(std::move(s));
  }
  for (const PromFamily& f : out.families)
    if (f.type == "histogram") checkHistogram(f, out.errors);
  return out;
}

}  // namespace robodiff::testing
