// CsvTable: what a trajectory CSV may look like (CRLF, comments, blank lines, quoted
// header names, spaces), and bad files reported by file, line, column and text.
#include <gtest/gtest.h>

#include "robodiff/batch/csv_table.hpp"
#include "robodiff/batch/trajectory_error.hpp"
#include "trajectory/trajectory_fixtures.hpp"

namespace robodiff::testing {
namespace {

using batch::CsvTable;
using batch::TrajectoryError;

TEST(CsvTable, ReadsCrlfCommentsBlankLinesAndQuotedNames) {
  const CsvTable csv = CsvTable::parse(
      "# recorded on the arm\r\n\"t\", \"q_a\" ,q_b\r\n0, 1.5 ,-2e-3\r\n\r\n# a pause\r\n0.5,+3,4\r\n\r\n\n", "x.csv");
  EXPECT_EQ(csv.header(), (std::vector<std::string>{"t", "q_a", "q_b"}));
  EXPECT_EQ(csv.headerLine(), 2u);
  ASSERT_EQ(csv.rows(), 2u);
  EXPECT_EQ(csv.lineOf(0), 3u);
  EXPECT_EQ(csv.lineOf(1), 6u);
  EXPECT_EQ(csv.number(0, 1), 1.5);
  EXPECT_EQ(csv.number(0, 2), -2e-3);
  EXPECT_EQ(csv.number(1, 1), 3.0);
  EXPECT_EQ(csv.column("q_b"), 2u);
  EXPECT_FALSE(csv.column("q_c"));
}

TEST(CsvTable, ALastLineWithoutNewlineAndAQuotedFieldWithCommas) {
  const CsvTable csv = CsvTable::parse("t,label,x\n1,\"a, b\",2", "x.csv");
  ASSERT_EQ(csv.rows(), 1u);
  EXPECT_EQ(csv.field(0, 1), "\"a, b\"");
  EXPECT_EQ(csv.number(0, 2), 2.0);
}

TEST(CsvTable, AWrongWidthNamesTheLineAndBothCounts) {
  EXPECT_EQ(errorOf([] { CsvTable::parse("t,a,b\n1,2,3\n\n1,2\n", "traj.csv"); }),
            "traj.csv:4: 2 fields, the header (line 1) has 3");
  EXPECT_EQ(errorOf([] { CsvTable::parse("t,a\n1,2,3,4\n", "traj.csv"); }),
            "traj.csv:2: 4 fields, the header (line 1) has 2");
}

TEST(CsvTable, BadNumbersNameLineColumnAndText) {
  const CsvTable csv = CsvTable::parse("t,q_j1,q_j2\n0,1,2\n1,abc,2\n2,nan,3\n3,1,-inf\n4,,1\n5,1e999,1\n6,1.5x,1\n",
                                       "traj.csv");
  EXPECT_EQ(errorOf([&] { csv.number(1, 1); }), "traj.csv:3: column q_j1: 'abc' is not a number");
  EXPECT_EQ(errorOf([&] { csv.number(2, 1); }), "traj.csv:4: column q_j1: 'nan' is not finite");
  EXPECT_EQ(errorOf([&] { csv.number(3, 2); }), "traj.csv:5: column q_j2: '-inf' is not finite");
  EXPECT_EQ(errorOf([&] { csv.number(4, 1); }), "traj.csv:6: column q_j1: is empty");
  EXPECT_EQ(errorOf([&] { csv.number(5, 1); }), "traj.csv:7: column q_j1: '1e999' is out of the range of a double");
  EXPECT_EQ(errorOf([&] { csv.number(6, 1); }), "traj.csv:8: column q_j1: '1.5x' is not a number");
}

TEST(CsvTable, BadHeaders) {
  EXPECT_EQ(errorOf([] { CsvTable::parse("t,q,q\n", "h.csv"); }), "h.csv:1: column 'q' is named twice in the header");
  EXPECT_EQ(errorOf([] { CsvTable::parse("t,,q\n", "h.csv"); }), "h.csv:1: column 2 of the header has no name");
  EXPECT_NE(errorOf([] { CsvTable::parse("\n# only a comment\n", "h.csv"); }).find("h.csv: no header row"),
            std::string::npos);
}

TEST(CsvTable, FiniteDoubles) {
  EXPECT_EQ(batch::parseFiniteDouble("-1.25e2"), -125.0);
  EXPECT_EQ(batch::parseFiniteDouble("+7"), 7.0);
  EXPECT_FALSE(batch::parseFiniteDouble("+-7"));
  EXPECT_FALSE(batch::parseFiniteDouble("inf"));
  EXPECT_FALSE(batch::parseFiniteDouble("1 2"));
  EXPECT_FALSE(batch::parseFiniteDouble(""));
}

}  // namespace
}  // namespace robodiff::testing
