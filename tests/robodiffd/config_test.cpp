// robodiffd's configuration: the documented file (deploy/robodiffd.conf) is TOML that
// toml++ itself reads and that states exactly the built-in defaults; --print-config writes
// a TOML file that reads back to the same configuration (in process and through the real
// robodiffd); sizes and durations are strings with units or integers (bytes, seconds).
// The errors are in config_errors_test.cpp.
#include <toml++/toml.h>

#include <gtest/gtest.h>

#include "robodiffd_process.hpp"
#include "server_config.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::server {
namespace {

ServerConfig fromText(const std::string& text) {
  ServerConfig config;
  applyConfigText(config, text, "test.conf");
  return config;
}

// The TOML type each key must have in deploy/robodiffd.conf and in --print-config's output.
toml::node_type documentedType(const std::string& key) {
  static const std::vector<std::string> counts = {
      "request_threads", "request_queue", "batch_threads", "background_nice", "max_batch_knots", "max_models",
      "max_functions", "max_urdf_depth", "max_urdf_elements", "max_urdf_links", "max_urdf_joints",
      "max_urdf_name_length", "max_urdf_attribute_length", "max_queued_requests_per_client",
      "max_running_requests_per_client", "error_replies_per_second", "max_shm_sessions", "max_models_per_client",
      "max_functions_per_client", "workers", "max_builds_per_robot"};
  const std::string name = key.substr(key.find('.') + 1);
  if (name == "enabled" || name == "compile" || name == "allow_unauthenticated" || name == "build_for_robots" ||
      name == "fetch_sources")
    return toml::node_type::boolean;
  for (const auto& c : counts)
    if (name == c) return toml::node_type::integer;
  return toml::node_type::string;  // names, paths, choices, sizes, durations, "default"
}

// Every key of the settings table in `root`, with its documented TOML type, and nothing else.
void expectEveryKeyWithItsType(const toml::table& root, const std::string& what) {
  std::size_t values = 0;
  for (const auto& [section, table] : root) {
    ASSERT_TRUE(table.is_table()) << what << ": " << section.str();
    values += table.as_table()->size();
  }
  EXPECT_EQ(values, configKeys().size()) << what;
  for (const std::string& key : configKeys()) {
    const toml::node* node = root.at_path(key).node();
    ASSERT_NE(node, nullptr) << what << " has no " << key;
    if (key == "dds.domain" && node->is_integer()) continue;  // an id, or "default"
    EXPECT_EQ(node->type(), documentedType(key)) << what << ": " << key;
  }
}

TEST(ServerConfig, DocumentedFileIsTomlWithEveryKeyOfItsType) {
  const std::string path = (testing::sourceDir() / "deploy/robodiffd.conf").string();
  toml::table root;
  ASSERT_NO_THROW(root = toml::parse_file(path));
  expectEveryKeyWithItsType(root, path);
  EXPECT_EQ(root["service"]["max_spec"].value<std::string>(), "1MiB");
  EXPECT_EQ(root["build"]["timeout"].value<std::string>(), "15min");
}

TEST(ServerConfig, DocumentedFileStatesTheDefaults) {
  ServerConfig from_file;
  applyConfigFile(from_file, (testing::sourceDir() / "deploy/robodiffd.conf").string());
  EXPECT_EQ(formatConfig(from_file), formatConfig(ServerConfig{}));
}

TEST(ServerConfig, DocumentedFileNamesEveryKey) {
  const std::string text = testing::readFile(testing::sourceDir() / "deploy/robodiffd.conf");
  for (const std::string& key : configKeys()) {
    const std::string name = key.substr(key.find('.') + 1);
    EXPECT_NE(text.find("\n" + name + " = "), std::string::npos) << key << " is not documented";
  }
}

TEST(ServerConfig, PrintedConfigIsTomlAndReadsBackToTheSameValues) {
  const ServerConfig config = fromText(
      "[service]\nrequest_threads = 7\nmax_batch_knots=5000\n"
      "instance_id = \"robot-1 # left \\\"arm\\\" \\\\ tab\\there, caf\\u00e9\"\n"
      "[build]\ntimeout = \"90s\"\nmemory_limit = \"2GiB\"\ncompile = false\ncompiler = 'C:\\tcc'\n"
      "[jobs]\ntimeout = \"250ms\"\ndata_dirs = \"/data/a:/data/b\"\n"
      "[cache]\nbudget = \"512MiB\" # comment\ndir = \"/tmp/x\"\n"
      "[iceoryx]\nroudi = \"external\"\n[dds]\ndomain = 17\nmax_sample = \"64KiB\"\n"
      "[http]\nlisten = \"0.0.0.0:0\"\nallowed_hosts = \"robot1.lan, metrics\"\n"
      "[log]\nlevel = \"debug\"\nformat = \"text\"\n");
  EXPECT_EQ(config.service.request_threads, 7u);
  EXPECT_EQ(config.service.max_batch_knots, 5000u);
  EXPECT_EQ(config.service.instance_id, "robot-1 # left \"arm\" \\ tab\there, caf\u00e9");
  EXPECT_EQ(config.service.compiler, "C:\\tcc");  // a TOML literal string: no escapes
  EXPECT_EQ(config.service.build_timeout, std::chrono::seconds(90));
  EXPECT_EQ(config.service.job_timeout, std::chrono::milliseconds(250));
  EXPECT_EQ(config.service.compiler_memory_limit_bytes, std::uint64_t{2} << 30);
  EXPECT_FALSE(config.service.compile);
  EXPECT_EQ(config.service.cache_budget_bytes, std::uint64_t{512} << 20);
  EXPECT_EQ(config.service.cache_dir, "/tmp/x");
  EXPECT_EQ(config.service.job_data_dirs.size(), 2u);
  EXPECT_EQ(config.shm.roudi, "external");
  EXPECT_EQ(config.dds.domain, 17);
  EXPECT_EQ(config.dds.max_sample_bytes, 64u * 1024);
  EXPECT_EQ(config.http.allowed_hosts, (std::vector<std::string>{"robot1.lan", "metrics"}));
  EXPECT_EQ(config.log_level, LogLevel::Debug);
  EXPECT_EQ(config.log_format, LogFormat::Text);

  for (const ServerConfig& c : {config, ServerConfig{}}) {
    const std::string printed = formatConfig(c);
    toml::table root;
    ASSERT_NO_THROW(root = toml::parse(printed)) << printed;  // toml++ itself reads it
    expectEveryKeyWithItsType(root, "--print-config");
    const ServerConfig again = fromText(printed);
    EXPECT_EQ(formatConfig(again), printed);
    EXPECT_EQ(again.service.instance_id, c.service.instance_id);
    EXPECT_EQ(again.service.job_timeout, c.service.job_timeout);
    EXPECT_EQ(again.dds.domain, c.dds.domain);
  }
  EXPECT_EQ(toml::parse(formatConfig(config))["dds"]["domain"].value<std::int64_t>(), 17);
  EXPECT_EQ(toml::parse(formatConfig(ServerConfig{}))["dds"]["domain"].value<std::string>(), "default");
}

TEST(ServerConfig, SizesAndDurationsAreStringsWithUnitsOrIntegerBytesAndSeconds) {
  ServerConfig c = fromText(
      "[service]\nmax_spec = 1048576\nmax_urdf = \"1.5MiB\"\n[build]\ntimeout = 90\nmemory_limit = \"3GB\"\n"
      "[jobs]\ntimeout = \"2h\"\n[dds]\ndomain = \"default\"\nmax_sample = 0\n");
  EXPECT_EQ(c.service.max_spec_bytes, std::size_t{1} << 20);
  EXPECT_EQ(c.service.max_urdf_bytes, std::size_t{3} << 19);
  EXPECT_EQ(c.service.build_timeout, std::chrono::seconds(90));
  EXPECT_EQ(c.service.compiler_memory_limit_bytes, 3'000'000'000u);
  EXPECT_EQ(c.service.job_timeout, std::chrono::hours(2));
  EXPECT_EQ(c.dds.domain, -1);
  EXPECT_EQ(c.dds.max_sample_bytes, 0u);
  // Dotted keys and inline tables are TOML too.
  c = fromText("service.request_threads = 5\ndds = { domain = 3, enabled = false }\n");
  EXPECT_EQ(c.service.request_threads, 5u);
  EXPECT_EQ(c.dds.domain, 3);
  EXPECT_FALSE(c.dds.enabled);
}

TEST(ServerConfig, SetOverridesOneKey) {
  ServerConfig config;
  applySetting(config, "dds.domain", "default", "--set");
  EXPECT_EQ(config.dds.domain, -1);
  applySetting(config, "build.workers", "3", "--set");
  EXPECT_EQ(config.service.build_workers, 3u);
  applySetting(config, "service.max_spec", "\"2MiB\"", "--set");  // quotes optional
  EXPECT_EQ(config.service.max_spec_bytes, std::size_t{2} << 20);
  applySetting(config, "build.compile", "no", "--set");
  EXPECT_FALSE(config.service.compile);
  EXPECT_THROW(applySetting(config, "build.workers", "-1", "--set"), ConfigError);
  EXPECT_THROW(applySetting(config, "nope.key", "1", "--set"), ConfigError);
}

// The real robodiffd: --print-config's output, given back with --config, prints the same.
TEST(ServerConfig, RobodiffdReadsItsPrintedConfigBack) {
  testing::TempDir dir;
  const std::string robodiffd = testing::shellQuote(testing::robodiffdPath().string());
  const testing::ProcessResult first = testing::runCommand(
      robodiffd + " --print-config --set service.max_spec=3MiB --set jobs.timeout=45s --set dds.domain=9" +
      " --instance-id 'a \"quoted\" id'");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const std::string printed = first.out;
  const std::string printed_path = dir.file("printed.conf", printed).string();
  EXPECT_NE(printed.find("max_spec = \"3MiB\"\n"), std::string::npos) << printed;
  EXPECT_NE(printed.find("timeout = \"45s\"\n"), std::string::npos) << printed;
  EXPECT_NE(printed.find("domain = 9\n"), std::string::npos) << printed;
  const testing::ProcessResult second =
      testing::runCommand(robodiffd + " --config " + testing::shellQuote(printed_path) + " --print-config");
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(second.out, printed);
}

}  // namespace
}  // namespace robodiff::server
