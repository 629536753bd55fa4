// robodiffd's configuration: the documented file (deploy/robodiffd.conf) states exactly
// the built-in defaults, every key round-trips through --print-config, and bad input is
// refused with the file, line, key and value.
#include <gtest/gtest.h>

#include "server_config.hpp"
#include "support/test_paths.hpp"

namespace robodiff::server {
namespace {

std::string errorOf(const std::string& text) {
  ServerConfig config;
  try {
    applyConfigText(config, text, "test.conf");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
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

TEST(ServerConfig, PrintedConfigReadsBackToTheSameValues) {
  ServerConfig config;
  applyConfigText(config,
                  "[service]\nrequest_threads = 7\nmax_batch_knots=5000\ninstance_id = \"robot-1 # left\"\n"
                  "[build]\ntimeout = 90s\nmemory_limit = 2GiB\ncompile = false\n"
                  "[cache]\nbudget = 512MiB # comment\ndir = /tmp/x\n"
                  "[iceoryx]\nroudi = external\n[dds]\ndomain = 17\nmax_sample = 64KiB\n"
                  "[log]\nlevel = debug\nformat = text\n",
                  "test.conf");
  EXPECT_EQ(config.service.request_threads, 7u);
  EXPECT_EQ(config.service.max_batch_knots, 5000u);
  EXPECT_EQ(config.service.instance_id, "robot-1 # left");
  EXPECT_EQ(config.service.build_timeout, std::chrono::seconds(90));
  EXPECT_EQ(config.service.compiler_memory_limit_bytes, std::uint64_t{2} << 30);
  EXPECT_FALSE(config.service.compile);
  EXPECT_EQ(config.service.cache_budget_bytes, std::uint64_t{512} << 20);
  EXPECT_EQ(config.service.cache_dir, "/tmp/x");
  EXPECT_EQ(config.shm.roudi, "external");
  EXPECT_EQ(config.dds.domain, 17);
  EXPECT_EQ(config.dds.max_sample_bytes, 64u * 1024);
  EXPECT_EQ(config.log_level, LogLevel::Debug);
  EXPECT_EQ(config.log_format, LogFormat::Text);

  ServerConfig again;
  applyConfigText(again, formatConfig(config), "printed");
  EXPECT_EQ(formatConfig(again), formatConfig(config));
}

TEST(ServerConfig, ErrorsNameFileLineKeyAndValue) {
  std::string e = errorOf("[service]\n\nrequest_threads = many\n");
  EXPECT_NE(e.find("test.conf:3"), std::string::npos) << e;
  EXPECT_NE(e.find("service.request_threads"), std::string::npos) << e;
  EXPECT_NE(e.find("'many'"), std::string::npos) << e;

  e = errorOf("[service]\nthreads = 2\n");
  EXPECT_NE(e.find("test.conf:2"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown setting 'service.threads'"), std::string::npos) << e;

  e = errorOf("[services]\n");
  EXPECT_NE(e.find("unknown section [services]"), std::string::npos) << e;

  e = errorOf("workers = 2\n");
  EXPECT_NE(e.find("before any [section]"), std::string::npos) << e;

  e = errorOf("[cache]\nbudget = 3 parsecs\n");
  EXPECT_NE(e.find("unit 'parsecs'"), std::string::npos) << e;

  e = errorOf("[iceoryx]\nroudi = sometimes\n");
  EXPECT_NE(e.find("auto, external, embedded"), std::string::npos) << e;

  e = errorOf("[log]\nlevel = loud\n");
  EXPECT_NE(e.find("'loud'"), std::string::npos) << e;

  e = errorOf("[build]\nworkers\n");
  EXPECT_NE(e.find("expected 'key = value'"), std::string::npos) << e;
}

TEST(ServerConfig, SetOverridesOneKey) {
  ServerConfig config;
  applySetting(config, "dds.domain", "default", "--set");
  EXPECT_EQ(config.dds.domain, -1);
  applySetting(config, "build.workers", "3", "--set");
  EXPECT_EQ(config.service.build_workers, 3u);
  EXPECT_THROW(applySetting(config, "build.workers", "-1", "--set"), ConfigError);
  EXPECT_THROW(applySetting(config, "nope.key", "1", "--set"), ConfigError);
}

}  // namespace
}  // namespace robodiff::server
