// Writing per-knot outputs as CSV (numbers formatted on all cores) or the binary format,
// atomically; reading the binary format back.
#include "robodiff/batch/trajectory_output.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/batch/atomic_file.hpp"
#include "robodiff/batch/trajectory_error.hpp"

namespace robodiff::batch {
namespace {

using nlohmann::json;

constexpr char kMagic[8] = {'R', 'D', 'T', 'R', 'A', 'J', '0', '1'};
constexpr std::size_t kPreamble = 16;     // magic + header length
constexpr std::size_t kDataAlignment = 64;
constexpr std::uint64_t kCsvPiece = 1024;  // rows one thread formats at a time

void appendNumber(std::string& out, double x) {
  char buffer[32];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, x);
  out.append(buffer, end);
}

// Rows [begin, end) as CSV text.
void formatRows(const TrajectoryOutput& output, std::uint64_t begin, std::uint64_t end, std::string& out) {
  out.clear();
  for (std::uint64_t k = begin; k < end; ++k) {
    bool first = true;
    if (!output.times.empty()) appendNumber(out, output.times[k]), first = false;
    const double* row = output.knot(k);
    for (std::size_t i = 0; i < output.output_count; ++i) {
      if (!first) out += ',';
      first = false;
      appendNumber(out, row[i]);
    }
    out += '\n';
  }
}

void checkCancelled(const OutputWriteOptions& options, const std::filesystem::path& path) {
  if (options.cancelled && options.cancelled())
    throw TrajectoryCancelled("writing " + path.string() + " was cancelled; nothing was written");
}

void writeCsv(AtomicFile& file, const std::filesystem::path& path, const TrajectoryOutput& output,
              const OutputWriteOptions& options) {
  std::string header = output.times.empty() ? "" : "t";
  for (const std::string& name : outputColumnNames(output.blocks, output.labels)) header += (header.empty() ? "" : ",") + name;
  file.write(header + "\n");
  const unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::string> texts(threads);
  // Rounds of `threads` pieces: formatted in parallel, written in order.
  for (std::uint64_t round = 0; round < output.knots; round += kCsvPiece * threads) {
    checkCancelled(options, path);
    std::vector<std::thread> pool;
    auto piece = [&](unsigned t) {
      const std::uint64_t begin = std::min(output.knots, round + t * kCsvPiece);
      formatRows(output, begin, std::min(output.knots, begin + kCsvPiece), texts[t]);
    };
    for (unsigned t = 1; t < threads && round + t * kCsvPiece < output.knots; ++t) pool.emplace_back(piece, t);
    piece(0);
    for (std::thread& t : pool) t.join();
    for (unsigned t = 0; t <= pool.size(); ++t) file.write(texts[t]);
  }
}

json blockJson(const BlockLayout& block, std::size_t offset) {
  json j = {{"name", block.name},          {"rows", block.rows}, {"cols", block.cols},
            {"layout", block.sparse ? "csr" : "dense"}, {"offset", offset},   {"size", block.size}};
  if (block.sparse) j["row_ptr"] = block.row_ptr, j["col_idx"] = block.col_idx;
  return j;
}

std::string binaryHeader(const TrajectoryOutput& output) {
  const std::size_t shift = output.times.empty() ? 0 : 1;
  json header = {{"format", "robodiff-trajectory"},
                 {"version", 1},
                 {"byte_order", "little"},
                 {"dtype", "float64"},
                 {"knots", output.knots},
                 {"row_stride", output.output_count + shift},
                 {"has_time", shift == 1},
                 {"function", output.function},
                 {"model", output.model}};
  if (!output.spec_json.empty()) header["spec"] = json::parse(output.spec_json);
  json blocks = json::array();
  for (const BlockLayout& block : output.blocks) blocks.push_back(blockJson(block, block.offset + shift));
  header["blocks"] = std::move(blocks);
  // data_offset's own digits change the length: pad until stable.
  std::size_t data_offset = 0;
  std::string text;
  for (int round = 0; round < 4; ++round) {
    header["data_offset"] = data_offset;
    text = header.dump();
    const std::size_t wanted = (kPreamble + text.size() + kDataAlignment - 1) / kDataAlignment * kDataAlignment;
    if (wanted == data_offset) break;
    data_offset = wanted;
  }
  text.resize(data_offset - kPreamble, ' ');
  return text;
}

void appendLittleEndian(std::string& out, const double* values, std::size_t count) {
  const std::size_t at = out.size();
  out.resize(at + count * sizeof(double));
  std::memcpy(out.data() + at, values, count * sizeof(double));
  if constexpr (std::endian::native == std::endian::big) {
    for (std::size_t i = 0; i < count; ++i) std::reverse(out.data() + at + 8 * i, out.data() + at + 8 * i + 8);
  }
}

void writeBinary(AtomicFile& file, const std::filesystem::path& path, const TrajectoryOutput& output,
                 const OutputWriteOptions& options) {
  const std::string header = binaryHeader(output);
  std::string preamble(kMagic, sizeof kMagic);
  const std::uint64_t length = header.size();
  for (int i = 0; i < 8; ++i) preamble += static_cast<char>((length >> (8 * i)) & 0xff);
  file.write(preamble);
  file.write(header);
  const bool has_time = !output.times.empty();
  std::string rows;
  for (std::uint64_t k0 = 0; k0 < output.knots; k0 += 4096) {
    checkCancelled(options, path);
    rows.clear();
    const std::uint64_t end = std::min(output.knots, k0 + 4096);
    if (!has_time) {
      appendLittleEndian(rows, output.knot(k0), (end - k0) * output.output_count);
    } else {
      for (std::uint64_t k = k0; k < end; ++k) {
        appendLittleEndian(rows, &output.times[k], 1);
        appendLittleEndian(rows, output.knot(k), output.output_count);
      }
    }
    file.write(rows);
  }
}

std::uint32_t u32(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || !j[key].is_number_unsigned())
    throw TrajectoryError(where + ": \"" + key + "\" is missing or not a non-negative integer");
  return j[key].get<std::uint32_t>();
}

}  // namespace

const char* toString(OutputFormat format) { return format == OutputFormat::Csv ? "csv" : "binary"; }

OutputFormat parseOutputFormat(const std::string& text) {
  if (text == "csv") return OutputFormat::Csv;
  if (text == "binary" || text == "rdb" || text == "bin") return OutputFormat::Binary;
  throw std::invalid_argument("output format '" + text + "' is not one of csv, binary");
}

OutputFormat outputFormatFor(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".csv") return OutputFormat::Csv;
  if (ext == ".rdb" || ext == ".bin") return OutputFormat::Binary;
  throw TrajectoryError(path.string() + ": the extension says no output format (.csv for CSV, .rdb or .bin for the "
                        "binary format)");
}

std::vector<std::string> outputColumnNames(const std::vector<BlockLayout>& blocks,
                                           const std::vector<AxisLabels>& labels) {
  std::vector<std::string> names;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const BlockLayout& block = blocks[b];
    const AxisLabels none;
    const AxisLabels& axes = b < labels.size() ? labels[b] : none;
    auto row = [&](std::uint32_t r) { return r < axes.rows.size() ? axes.rows[r] : std::to_string(r); };
    auto col = [&](std::uint32_t c) { return c < axes.cols.size() ? axes.cols[c] : std::to_string(c); };
    const std::size_t first = names.size();
    names.resize(first + block.size);
    const std::string prefix = block.name + "_";
    if (block.sparse) {
      for (std::uint32_t r = 0; r < block.rows; ++r)
        for (std::uint32_t i = block.row_ptr[r]; i < block.row_ptr[r + 1]; ++i)
          names[first + i] = prefix + row(r) + "_" + col(block.col_idx[i]);
    } else if (block.cols == 1) {
      for (std::uint32_t r = 0; r < block.size; ++r) names[first + r] = prefix + row(r);
    } else {
      for (std::uint32_t i = 0; i < block.size; ++i)
        names[first + i] = prefix + row(i / block.cols) + "_" + col(i % block.cols);
    }
  }
  return names;
}

void writeTrajectoryOutput(const std::filesystem::path& path, const TrajectoryOutput& output,
                           const OutputWriteOptions& options) {
  if (output.values.size() != output.knots * output.output_count || (!output.times.empty() && output.times.size() != output.knots))
    throw std::invalid_argument("writeTrajectoryOutput: values or times do not match the knot count");
  const OutputFormat format = options.format ? *options.format : outputFormatFor(path);
  checkCancelled(options, path);
  try {
    AtomicFile file(path);
    if (format == OutputFormat::Csv)
      writeCsv(file, path, output, options);
    else
      writeBinary(file, path, output, options);
    checkCancelled(options, path);
    file.commit();
  } catch (const AtomicFileError& e) {
    throw TrajectoryError(e.what());  // this layer's error type, the same message
  }
}

namespace {

// The JSON header after a binary file's preamble (its magic, then the header's length),
// checked to be robodiff-trajectory version 1 in float64 little-endian. `length`: the
// header's bytes.
json readBinaryHeader(std::ifstream& in, const std::string& where, std::uint64_t file_size, std::uint64_t* length) {
  char preamble[kPreamble];
  if (!in.read(preamble, kPreamble) || std::memcmp(preamble, kMagic, sizeof kMagic) != 0)
    throw TrajectoryError(where + ": not a robodiff trajectory file (no RDTRAJ01 magic)");
  *length = 0;
  for (int i = 0; i < 8; ++i) *length |= std::uint64_t{static_cast<unsigned char>(preamble[8 + i])} << (8 * i);
  if (*length > file_size - kPreamble)
    throw TrajectoryError(where + ": the header length " + std::to_string(*length) + " is past the end of the file");
  std::string text(*length, '\0');
  in.read(text.data(), static_cast<std::streamsize>(*length));
  json header;
  try {
    header = json::parse(text);
  } catch (const json::exception& e) {
    throw TrajectoryError(where + ": the JSON header does not parse: " + e.what());
  }
  if (header.value("format", "") != "robodiff-trajectory" || header.value("version", 0) != 1)
    throw TrajectoryError(where + ": the header is not robodiff-trajectory version 1");
  if (header.value("dtype", "") != "float64" || header.value("byte_order", "") != "little")
    throw TrajectoryError(where + ": dtype " + header.value("dtype", "?") + ", byte order " +
                          header.value("byte_order", "?") + ": only float64 little-endian is known");
  return header;
}

// One of the header's "blocks", its offset counted from the first output (after the
// time column, `shift` 1, when there is one); within a row of `stride` doubles.
BlockLayout blockOf(const json& b, const std::string& where, std::size_t shift, std::uint32_t stride) {
  BlockLayout block;
  block.name = b.value("name", "");
  const std::string at = where + ": block " + block.name;
  block.rows = u32(b, "rows", at);
  block.cols = u32(b, "cols", at);
  block.size = u32(b, "size", at);
  block.offset = u32(b, "offset", at);
  if (block.offset < shift) throw TrajectoryError(at + ": offset 0 is the time column's");
  block.offset -= static_cast<std::uint32_t>(shift);
  block.sparse = b.value("layout", "dense") == "csr";
  if (block.sparse) {
    block.row_ptr = b.at("row_ptr").get<std::vector<std::uint32_t>>();
    block.col_idx = b.at("col_idx").get<std::vector<std::uint32_t>>();
  }
  if (block.offset + shift + block.size > stride) throw TrajectoryError(at + ": past the end of a row");
  return block;
}

// The knots' rows of `stride` doubles from `data_offset` on, into output.times (the
// first column, with `shift` 1) and output.values.
void readRows(std::ifstream& in, const std::string& where, std::uint64_t data_offset, std::uint32_t stride,
              std::size_t shift, TrajectoryOutput& output) {
  std::vector<double> rows(output.knots * stride);
  in.seekg(static_cast<std::streamoff>(data_offset));
  in.read(reinterpret_cast<char*>(rows.data()), static_cast<std::streamsize>(rows.size() * sizeof(double)));
  if (!in) throw TrajectoryError(where + ": reading the data failed");
  if constexpr (std::endian::native == std::endian::big) {
    for (double& x : rows) {
      auto* bytes = reinterpret_cast<char*>(&x);
      std::reverse(bytes, bytes + 8);
    }
  }
  output.values.resize(output.knots * output.output_count);
  if (shift) output.times.resize(output.knots);
  for (std::uint64_t k = 0; k < output.knots; ++k) {
    const double* row = rows.data() + k * stride;
    if (shift) output.times[k] = row[0];
    std::copy_n(row + shift, output.output_count, output.values.data() + k * output.output_count);
  }
}

}  // namespace

TrajectoryOutput readTrajectoryBinary(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw TrajectoryError(where + ": cannot open the file");
  const std::uint64_t file_size = std::filesystem::file_size(path);
  std::uint64_t length = 0;
  const json header = readBinaryHeader(in, where, file_size, &length);
  TrajectoryOutput output;
  output.function = header.value("function", "");
  output.model = header.value("model", "");
  if (header.contains("spec")) output.spec_json = header["spec"].dump();
  const std::size_t shift = header.value("has_time", false) ? 1 : 0;
  const std::uint32_t stride = u32(header, "row_stride", where);
  if (!header.contains("knots") || !header["knots"].is_number_unsigned())
    throw TrajectoryError(where + ": \"knots\" is missing or not a non-negative integer");
  output.knots = header["knots"].get<std::uint64_t>();
  const std::uint64_t data_offset = header.value("data_offset", std::uint64_t{0});
  if (data_offset != kPreamble + length) throw TrajectoryError(where + ": data_offset does not follow the header");
  for (const json& b : header.value("blocks", json::array())) {
    output.blocks.push_back(blockOf(b, where, shift, stride));
    output.output_count = std::max<std::size_t>(output.output_count, output.blocks.back().offset + output.blocks.back().size);
  }
  if (output.output_count + shift != stride)
    throw TrajectoryError(where + ": the blocks cover " + std::to_string(output.output_count + shift) +
                          " doubles of a row, row_stride is " + std::to_string(stride));
  const std::uint64_t expected = data_offset + output.knots * stride * sizeof(double);
  if (file_size != expected)
    throw TrajectoryError(where + ": " + std::to_string(file_size) + " bytes, the header says " +
                          std::to_string(expected) + " (" + std::to_string(output.knots) + " knots of " +
                          std::to_string(stride) + " doubles)");
  readRows(in, where, data_offset, stride, shift, output);
  return output;
}

}  // namespace robodiff::batch
