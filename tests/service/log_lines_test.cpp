// server/log's lines: one whole, valid JSON object (or logfmt line) per event, with the
// UTC time stamp, escapes, non-finite numbers as strings, the level filter, and whole
// lines when several threads log at once.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "robodiff/server/log.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::testing {
namespace {

using server::LogFormat;
using server::Logger;
using server::LogLevel;

std::vector<std::string> linesOf(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(LogLines, JsonLinesParseAndKeepEveryField) {
  TempDir tmp;
  const auto path = tmp / "log.jsonl";
  std::FILE* file = std::fopen(path.c_str(), "w");
  {
    Logger log(file, LogLevel::Info);
    log.debug("hidden", {{"n", 1}});
    log.warn("odd_values", {{"text", "quote \" backslash \\ newline \n tab \t bell \a"},
                            {"nan", std::nan("")},
                            {"inf", 1.0 / 0.0},
                            {"x", 0.25},
                            {"n", -3},
                            {"big", 18446744073709551615ull},
                            {"ok", true}});
  }
  std::fclose(file);
  const auto lines = linesOf(path);
  ASSERT_EQ(lines.size(), 1u);  // debug filtered out
  const nlohmann::json j = nlohmann::json::parse(lines[0]);
  EXPECT_TRUE(std::regex_match(j["ts"].get<std::string>(),
                               std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z)")))
      << j["ts"];
  EXPECT_EQ(j["level"], "warn");
  EXPECT_EQ(j["event"], "odd_values");
  EXPECT_EQ(j["text"], "quote \" backslash \\ newline \n tab \t bell \a");
  EXPECT_EQ(j["nan"], "nan");
  EXPECT_EQ(j["inf"], "inf");
  EXPECT_DOUBLE_EQ(j["x"].get<double>(), 0.25);
  EXPECT_EQ(j["n"], -3);
  EXPECT_EQ(j["big"].get<std::uint64_t>(), 18446744073709551615ull);
  EXPECT_EQ(j["ok"], true);
}

TEST(LogLines, TextLinesQuoteOnlyWhatNeedsIt) {
  TempDir tmp;
  const auto path = tmp / "log.txt";
  std::FILE* file = std::fopen(path.c_str(), "w");
  {
    Logger log(file, LogLevel::Debug, LogFormat::Text);
    log.debug("model_loaded", {{"model_id", "m-1"}, {"name", "two words"}, {"nq", 7}});
  }
  std::fclose(file);
  const auto lines = linesOf(path);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(std::regex_match(
      lines[0], std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z debug model_loaded model_id=m-1 name="two words" nq=7)")))
      << lines[0];
}

TEST(LogLines, ThreadsLoggingAtOnceWriteWholeLines) {
  TempDir tmp;
  const auto path = tmp / "log.jsonl";
  std::FILE* file = std::fopen(path.c_str(), "w");
  {
    Logger log(file);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&log, t] {
        for (int i = 0; i < 500; ++i) log.info("tick", {{"thread", t}, {"i", i}, {"pad", std::string(100, 'p')}});
      });
    for (auto& th : threads) th.join();
  }
  std::fclose(file);
  const auto lines = linesOf(path);
  ASSERT_EQ(lines.size(), 2000u);
  nlohmann::json parsed;
  for (const std::string& line : lines) ASSERT_NO_THROW(parsed = nlohmann::json::parse(line)) << line;
}

}  // namespace
}  // namespace robodiff::testing
