// Writing per-knot outputs: CSV column names, numbers that read back to the same doubles,
// the binary format read back equal to the CSV, and files written all or nothing.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/batch/csv_table.hpp"
#include "robodiff/batch/trajectory_error.hpp"
#include "robodiff/batch/trajectory_output.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

namespace fs = std::filesystem;
using batch::BlockLayout;
using batch::OutputFormat;
using batch::TrajectoryOutput;

// A value (3 x 1), a dense 2 x 3 matrix and a 3 x 4 CSR block with 4 nonzeros.
std::vector<BlockLayout> exampleBlocks() {
  BlockLayout value{"value", 3, 1, false, 3, 0, {}, {}};
  BlockLayout dense{"jacobian", 2, 3, false, 6, 3, {}, {}};
  BlockLayout sparse{"hessian", 3, 4, true, 4, 9, {0, 1, 1, 4}, {2, 0, 1, 3}};
  return {value, dense, sparse};
}

TrajectoryOutput exampleOutput(std::uint64_t knots, bool with_time) {
  TrajectoryOutput out;
  out.blocks = exampleBlocks();
  out.output_count = 13;
  out.knots = knots;
  out.function = "rnea";
  out.model = "toy";
  out.spec_json = R"({"function":"rnea"})";
  for (std::uint64_t k = 0; k < knots; ++k) {
    if (with_time) out.times.push_back(0.001 * static_cast<double>(k));
    for (int i = 0; i < 13; ++i) out.values.push_back(std::sin(1e3 * k + i) * std::pow(10.0, i % 7 - 3) + 1.0 / 3.0);
  }
  return out;
}

std::vector<fs::path> filesIn(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path().filename());
  return files;
}

TEST(TrajectoryOutput, ColumnNamesPerBlockKind) {
  EXPECT_EQ(batch::outputColumnNames(exampleBlocks()),
            (std::vector<std::string>{"value_0", "value_1", "value_2", "jacobian_0_0", "jacobian_0_1", "jacobian_0_2",
                                      "jacobian_1_0", "jacobian_1_1", "jacobian_1_2", "hessian_0_2", "hessian_2_0",
                                      "hessian_2_1", "hessian_2_3"}));
}

TEST(TrajectoryOutput, FormatsByExtensionAndName) {
  EXPECT_EQ(batch::outputFormatFor("a/out.csv"), OutputFormat::Csv);
  EXPECT_EQ(batch::outputFormatFor("out.rdb"), OutputFormat::Binary);
  EXPECT_EQ(batch::outputFormatFor("out.bin"), OutputFormat::Binary);
  EXPECT_THROW(batch::outputFormatFor("out.txt"), batch::TrajectoryError);
  EXPECT_EQ(batch::parseOutputFormat("binary"), OutputFormat::Binary);
  EXPECT_THROW(batch::parseOutputFormat("hdf5"), std::invalid_argument);
}

// Enough knots for several formatting rounds on several threads.
TEST(TrajectoryOutput, CsvReadsBackToTheSameDoubles) {
  TempDir tmp;
  const TrajectoryOutput out = exampleOutput(5000, true);
  batch::OutputWriteOptions options;
  options.threads = 3;
  batch::writeTrajectoryOutput(tmp / "out.csv", out, options);
  const batch::CsvTable csv = batch::CsvTable::readFile(tmp / "out.csv");
  std::vector<std::string> header = {"t"};
  for (const std::string& name : batch::outputColumnNames(out.blocks)) header.push_back(name);
  EXPECT_EQ(csv.header(), header);
  ASSERT_EQ(csv.rows(), out.knots);
  for (std::size_t k = 0; k < csv.rows(); ++k) {
    ASSERT_EQ(csv.number(k, 0), out.times[k]);
    for (std::size_t i = 0; i < out.output_count; ++i) ASSERT_EQ(csv.number(k, i + 1), out.knot(k)[i]) << k << " " << i;
  }
  EXPECT_EQ(filesIn(tmp.path()), (std::vector<fs::path>{"out.csv"}));  // no temporary file left
}

TEST(TrajectoryOutput, BinaryReadsBackEqualToTheCsv) {
  TempDir tmp;
  for (const bool with_time : {true, false}) {
    const TrajectoryOutput out = exampleOutput(777, with_time);
    batch::writeTrajectoryOutput(tmp / "out.rdb", out);
    batch::writeTrajectoryOutput(tmp / "out.csv", out);
    const TrajectoryOutput back = batch::readTrajectoryBinary(tmp / "out.rdb");
    EXPECT_EQ(back.knots, out.knots);
    EXPECT_EQ(back.output_count, out.output_count);
    EXPECT_EQ(back.function, "rnea");
    EXPECT_EQ(back.model, "toy");
    EXPECT_EQ(nlohmann::json::parse(back.spec_json), nlohmann::json::parse(out.spec_json));
    ASSERT_EQ(back.blocks.size(), 3u);
    for (std::size_t b = 0; b < 3; ++b) {
      EXPECT_EQ(back.blocks[b].name, out.blocks[b].name);
      EXPECT_EQ(back.blocks[b].rows, out.blocks[b].rows);
      EXPECT_EQ(back.blocks[b].cols, out.blocks[b].cols);
      EXPECT_EQ(back.blocks[b].offset, out.blocks[b].offset);
      EXPECT_EQ(back.blocks[b].sparse, out.blocks[b].sparse);
      EXPECT_EQ(back.blocks[b].row_ptr, out.blocks[b].row_ptr);
      EXPECT_EQ(back.blocks[b].col_idx, out.blocks[b].col_idx);
    }
    EXPECT_EQ(back.times, out.times);
    EXPECT_EQ(back.values, out.values);
    // The CSV of the same outputs holds the same numbers.
    const batch::CsvTable csv = batch::CsvTable::readFile(tmp / "out.csv");
    const std::size_t shift = with_time ? 1 : 0;
    for (std::size_t k = 0; k < csv.rows(); ++k)
      for (std::size_t i = 0; i < back.output_count; ++i) ASSERT_EQ(csv.number(k, i + shift), back.knot(k)[i]);
    // The data starts 64-byte aligned, after the header the file states.
    const std::string bytes = readFile(tmp / "out.rdb");
    EXPECT_EQ(bytes.substr(0, 8), "RDTRAJ01");
    std::uint64_t length = 0;
    for (int i = 0; i < 8; ++i) length |= std::uint64_t{static_cast<unsigned char>(bytes[8 + i])} << (8 * i);
    const nlohmann::json header = nlohmann::json::parse(bytes.substr(16, length));
    EXPECT_EQ(header["data_offset"], 16 + length);
    EXPECT_EQ((16 + length) % 64, 0u);
    EXPECT_EQ(header["row_stride"], 13 + shift);
    EXPECT_EQ(header["blocks"][2]["layout"], "csr");
    EXPECT_EQ(bytes.size(), 16 + length + out.knots * (13 + shift) * 8);
  }
}

TEST(TrajectoryOutput, ATruncatedBinaryFileIsRefused) {
  TempDir tmp;
  batch::writeTrajectoryOutput(tmp / "out.rdb", exampleOutput(10, true));
  fs::resize_file(tmp / "out.rdb", fs::file_size(tmp / "out.rdb") - 8);
  try {
    batch::readTrajectoryBinary(tmp / "out.rdb");
    ADD_FAILURE() << "no error";
  } catch (const batch::TrajectoryError& e) {
    EXPECT_NE(std::string(e.what()).find("the header says"), std::string::npos) << e.what();
  }
  tmp.file("text.rdb", "t,value_0\n1,2\n");
  EXPECT_THROW(batch::readTrajectoryBinary(tmp / "text.rdb"), batch::TrajectoryError);
}

TEST(TrajectoryOutput, ACancelledWriteLeavesNothingAndKeepsAnOlderFile) {
  TempDir tmp;
  const TrajectoryOutput out = exampleOutput(20000, true);
  for (const char* name : {"new.csv", "new.rdb"}) {
    int polls = 0;
    batch::OutputWriteOptions options;
    options.cancelled = [&] { return ++polls > 2; };  // part of the file is written by then
    EXPECT_THROW(batch::writeTrajectoryOutput(tmp / name, out, options), batch::TrajectoryCancelled);
    EXPECT_TRUE(filesIn(tmp.path()).empty()) << name;
  }
  tmp.file("old.csv", "older\n");
  batch::OutputWriteOptions cancel_now;
  cancel_now.cancelled = [] { return true; };
  EXPECT_THROW(batch::writeTrajectoryOutput(tmp / "old.csv", out, cancel_now), batch::TrajectoryCancelled);
  EXPECT_EQ(readFile(tmp / "old.csv"), "older\n");
}

TEST(TrajectoryOutput, AnUnwritableDirectoryIsNamed) {
  try {
    batch::writeTrajectoryOutput("/nonexistent-dir/out.csv", exampleOutput(1, false));
    ADD_FAILURE() << "no error";
  } catch (const batch::TrajectoryError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace robodiff::testing
