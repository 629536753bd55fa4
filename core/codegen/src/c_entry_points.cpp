#include "c_entry_points.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace robodiff::codegen::detail {

std::string cString(const std::string& s) {
  std::string r = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      r += '\\';
      r += static_cast<char>(c);
    } else if (c < 0x20 || c >= 0x7f || c == '?') {  // '?' avoids trigraphs
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\%03o", c);
      r += buf;
    } else {
      r += static_cast<char>(c);
    }
  }
  return r + "\"";
}

const char* const kEvalParams = "(const double* const* in, double* const* out, double* w)";

// The batched entry point: full chunks of RD_W knots straight from the caller's arrays,
// the remainder through a staging area of the work buffer padded with copies of the
// last knot (so padding lanes compute harmless values).
std::string batchEntry(const FunctionDefinition& f, const std::string& prefix, std::uint32_t transfer) {
  const std::size_t ni = f.inputs.size(), no = f.outputs.size();
  std::ostringstream s;
  s << "static void " << prefix << "_eval_batch(uint64_t n, const double* const* in, double* const* out, double* work) {\n"
    << "  const double* ip[" << std::max<std::size_t>(ni, 1) << "];\n"
    << "  double* op[" << no << "];\n";
  if (ni == 0) s << "  (void)in;\n";
  auto pointAt = [&](const std::string& knot) {
    for (std::size_t b = 0; b < ni; ++b) {
      if (f.inputs[b].size == 0) s << "    ip[" << b << "] = in[" << b << "];\n";
      else s << "    ip[" << b << "] = in[" << b << "] + " << knot << " * " << f.inputs[b].size << ";\n";
    }
    for (std::size_t b = 0; b < no; ++b) {
      if (f.outputs[b].size() == 0) s << "    op[" << b << "] = out[" << b << "];\n";
      else s << "    op[" << b << "] = out[" << b << "] + " << knot << " * " << f.outputs[b].size() << ";\n";
    }
  };
  s << "#if RD_VECTOR\n"
    << "  double* stage = work + " << transfer << " * RD_W;\n"
    << "  uint64_t k = 0;\n"
    << "  for (; k + RD_W <= n; k += RD_W) {\n";
  pointAt("k");
  s << "    " << prefix << "_chunk(ip, op, work);\n"
    << "  }\n"
    << "  if (k < n) {\n"
    << "    const uint64_t m = n - k;\n";
  if (f.inputCount() > 0) {
    s << "    for (int l = 0; l < RD_W; ++l) {\n"
      << "      const uint64_t src = k + ((uint64_t)l < m ? (uint64_t)l : m - 1);\n";
    std::uint64_t offset = 0;
    for (std::size_t b = 0; b < ni; ++b) {
      const std::uint32_t size = f.inputs[b].size;
      if (size > 0)
        s << "      memcpy(stage + " << offset << " * RD_W + l * " << size << ", in[" << b << "] + src * " << size
          << ", " << size << " * sizeof(double));\n";
      offset += size;
    }
    s << "    }\n";
  }
  std::uint64_t offset = 0;
  for (std::size_t b = 0; b < ni; ++b) {
    s << "    ip[" << b << "] = stage + " << offset << " * RD_W;\n";
    offset += f.inputs[b].size;
  }
  for (std::size_t b = 0; b < no; ++b) {
    s << "    op[" << b << "] = stage + " << offset << " * RD_W;\n";
    offset += f.outputs[b].size();
  }
  s << "    " << prefix << "_chunk(ip, op, work);\n"
    << "    for (uint64_t l = 0; l < m; ++l) {\n";
  for (std::size_t b = 0; b < no; ++b) {
    const std::uint32_t size = f.outputs[b].size();
    if (size > 0)
      s << "      memcpy(out[" << b << "] + (k + l) * " << size << ", op[" << b << "] + l * " << size << ", " << size
        << " * sizeof(double));\n";
  }
  s << "    }\n  }\n"
    << "#else\n"
    << "  for (uint64_t k = 0; k < n; ++k) {\n";
  pointAt("k");
  s << "    " << prefix << "_eval(ip, op, work);\n"
    << "  }\n"
    << "#endif\n"
    << "}\n\n";
  return s.str();
}

std::string beyondRangeMask(const std::string& name,
                            const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles) {
  auto element = [&](std::size_t k) {
    const auto& [block, index] = angles[std::min(k, angles.size() - 1)];  // an odd count repeats the last
    return "in[" + std::to_string(block) + "][" + std::to_string(index) + "]";
  };
  std::string s = "  const rd_pair_u " + name + " =";
  for (std::size_t k = 0; k < angles.size(); k += 2)
    s += (k == 0 ? "" : " |") + std::string("\n    rd_beyond_pair(") + element(k) + ", " + element(k + 1) + ")";
  return s + ";\n";
}

std::string rangeCheckedEntry(const std::string& prefix,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles) {
  std::ostringstream s;
  s << "RD_SCALAR_FN static void " << prefix << "_eval" << kEvalParams << " {\n"
    << beyondRangeMask("beyond", angles)
    << "  if (__builtin_expect((beyond[0] | beyond[1]) != 0, 0)) {\n"
    << "    " << prefix << "_exact(in, out, w);\n"
    << "    return;\n"
    << "  }\n"
    << "  " << prefix << "_in_range(in, out, w);\n"
    << "}\n";
  return s.str();
}

std::string descriptorTables(const FunctionDefinition& f, const std::string& prefix) {
  std::ostringstream s;
  if (!f.inputs.empty()) {
    s << "static const robodiff_input_desc " << prefix << "_inputs[] = {\n";
    for (const auto& b : f.inputs) s << "  {" << cString(b.name) << ", " << b.size << "u},\n";
    s << "};\n";
  }
  for (std::size_t j = 0; j < f.outputs.size(); ++j) {
    const OutputBlock& b = f.outputs[j];
    if (b.kind != OutputKind::Sparse) continue;
    auto list = [&](const char* what, const std::vector<std::uint32_t>& v) {
      if (v.empty()) return;
      s << "static const uint32_t " << prefix << "_o" << j << "_" << what << "[] = {";
      for (std::size_t i = 0; i < v.size(); ++i) s << (i % 16 == 0 ? "\n  " : " ") << v[i] << "u,";
      s << "\n};\n";
    };
    list("row_ptr", b.row_ptr);
    list("col_idx", b.col_idx);
  }
  s << "static const robodiff_output_desc " << prefix << "_outputs[] = {\n";
  for (std::size_t j = 0; j < f.outputs.size(); ++j) {
    const OutputBlock& b = f.outputs[j];
    const bool sparse = b.kind == OutputKind::Sparse;
    const std::string o = prefix + "_o" + std::to_string(j);
    s << "  {" << cString(b.name) << ", " << b.rows << "u, " << b.cols << "u, "
      << (sparse ? "ROBODIFF_OUTPUT_SPARSE" : "ROBODIFF_OUTPUT_DENSE") << ", " << b.size() << "u, "
      << (sparse ? o + "_row_ptr" : "NULL") << ", " << (sparse && !b.col_idx.empty() ? o + "_col_idx" : "NULL")
      << "},\n";
  }
  s << "};\n\n";
  return s.str();
}

}  // namespace robodiff::codegen::detail
