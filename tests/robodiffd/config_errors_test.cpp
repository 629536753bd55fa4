// robodiffd.conf's errors: every one is a ConfigError naming the file, line and column,
// the key and the value (a TOML syntax error: toml++'s description at its position), with
// the nearest known name for a misspelt one; no other exception escapes, whatever the text.
#include <gtest/gtest.h>

#include "server_config.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::server {
namespace {

// The ConfigError's message, "" when the text is accepted. Any other exception fails the test.
std::string errorOf(const std::string& text) {
  ServerConfig config;
  try {
    applyConfigText(config, text, "test.conf");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_CONTAINS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

TEST(ServerConfigErrors, BadValuesNameFileLineColumnKeyAndValue) {
  std::string e = errorOf("[service]\n\nrequest_threads = 9999\n");
  EXPECT_CONTAINS(e, "test.conf:3:19: service.request_threads = '9999' is beyond 256");

  e = errorOf("[cache]\nbudget = \"3 parsecs\"\n");
  EXPECT_CONTAINS(e, "test.conf:2:10: cache.budget = '3 parsecs' has unit 'parsecs'");

  e = errorOf("[iceoryx]\nroudi = \"sometimes\"\n");
  EXPECT_CONTAINS(e, "test.conf:2:9: iceoryx.roudi = 'sometimes' is not one of auto, external, embedded");

  e = errorOf("[log]\nlevel = \"loud\"\n");
  EXPECT_CONTAINS(e, "log.level = 'loud'");

  e = errorOf("[build]\nworkers = -1\n");
  EXPECT_CONTAINS(e, "test.conf:2:11: build.workers = '-1' is negative");

  e = errorOf("[limits]\nmax_shm_sessions = 0\n");
  EXPECT_CONTAINS(e, "limits.max_shm_sessions = '0' must be at least 1");

  e = errorOf("[jobs]\ndata_dirs = \"relative/dir\"\n");
  EXPECT_CONTAINS(e, "jobs.data_dirs = 'relative/dir' names 'relative/dir', which is not an absolute path");
}

TEST(ServerConfigErrors, ValuesOfTheWrongTomlTypeSayWhatToWrite) {
  std::string e = errorOf("[service]\nrequest_threads = \"many\"\n");
  EXPECT_CONTAINS(e, "test.conf:2:19: service.request_threads = \"many\" is a string; expected a whole number, "
                     "unquoted (e.g. request_threads = 2)");

  e = errorOf("[build]\ncompile = \"true\"\n");
  EXPECT_CONTAINS(e, "build.compile = \"true\" is a string; expected true or false, unquoted");

  e = errorOf("[service]\nmax_spec = 1.5\n");
  EXPECT_CONTAINS(e, "service.max_spec = 1.5 is a floating-point number; expected a size: a string with a unit");

  e = errorOf("[build]\ntimeout = 1979-05-27\n");
  EXPECT_CONTAINS(e, "build.timeout = 1979-05-27 is a date or time; expected a duration");

  e = errorOf("[cache]\ndir = 5\n");
  EXPECT_CONTAINS(e, "cache.dir = 5 is an integer; expected a string in double quotes");

  e = errorOf("[dds]\ndomain = true\n");
  EXPECT_CONTAINS(e, "dds.domain = true is a boolean; expected a domain id 0..232 or the string \"default\"");
}

TEST(ServerConfigErrors, TablesAndArraysWhereAValueBelongsAreRefused) {
  std::string e = errorOf("[service]\nrequest_threads = { count = 2 }\n");
  EXPECT_CONTAINS(e, "test.conf:2:19: service.request_threads = {...} is a table; expected a whole number");

  e = errorOf("[http]\nallowed_hosts = [\"a\", \"b\"]\n");
  EXPECT_CONTAINS(e, "test.conf:2:17: http.allowed_hosts = [...] is an array; expected a string");

  e = errorOf("[service.request_threads]\ncount = 2\n");
  EXPECT_CONTAINS(e, "service.request_threads = {...} is a table");

  e = errorOf("[[service]]\nrequest_threads = 2\n");
  EXPECT_CONTAINS(e, "test.conf:1:3: service is an array; expected the section [service] (written once, not [[service]])");

  e = errorOf("service = 3\n");
  EXPECT_CONTAINS(e, "test.conf:1:1: service is an integer; expected the section [service]");

  e = errorOf("workers = 2\n");
  EXPECT_CONTAINS(e, "test.conf:1:1: workers = 2 comes before any [section] (workers is a key of [build], [jobs])");
}

TEST(ServerConfigErrors, UnknownSectionsAndKeysNameTheClosestAndTheKnown) {
  std::string e = errorOf("[service]\nrequest_thread = 2\n");
  EXPECT_CONTAINS(e, "test.conf:2:1: unknown setting 'service.request_thread' (did you mean "
                     "'service.request_threads'?); [service] has: instance_id, request_threads,");

  e = errorOf("# a comment\n[servce]\n");
  EXPECT_CONTAINS(e, "test.conf:2:2: unknown section [servce] (did you mean [service]?); known: service, limits, "
                     "build, jobs, cache, iceoryx, dds, http, log");

  e = errorOf("[metrics]\n");
  EXPECT_CONTAINS(e, "unknown section [metrics]; known: service,");

  e = errorOf("[build]\nnice_level = 2\n");
  EXPECT_CONTAINS(e, "unknown setting 'build.nice_level'; [build] has: workers, compile,");

  ServerConfig config;
  try {
    applySetting(config, "build.worker", "1", "--set");
    ADD_FAILURE() << "build.worker accepted";
  } catch (const ConfigError& error) {
    EXPECT_CONTAINS(std::string(error.what()), "--set: unknown setting 'build.worker' (did you mean 'build.workers'?)");
  }
}

TEST(ServerConfigErrors, SyntaxErrorsAreTomlPlusPlusDescriptionsAtLineAndColumn) {
  // The old format's bare sizes and words: toml++'s description, and the quoted form.
  std::string e = errorOf("[service]\nmax_spec = 1MiB\n");
  EXPECT_CONTAINS(e, "test.conf:2:13: not valid TOML: Error while parsing decimal integer: expected digit, saw 'M'");
  EXPECT_CONTAINS(e, "(sizes, durations and names are strings in TOML: max_spec = \"1MiB\")");

  e = errorOf("[log]\nlevel = info # the default\n");
  EXPECT_CONTAINS(e, "test.conf:2:");
  EXPECT_CONTAINS(e, "level = \"info\")");

  e = errorOf("[build]\ncompile = yes\n");
  EXPECT_CONTAINS(e, "(a flag is true or false: compile = true)");

  e = errorOf("[build]\nworkers\n");
  EXPECT_CONTAINS(e, "test.conf:2:8: not valid TOML: Error while parsing key-value pair");

  e = errorOf("[build]\nworkers = 1\nworkers = 2\n");
  EXPECT_CONTAINS(e, "test.conf:3:");
  EXPECT_CONTAINS(e, "cannot redefine existing integer 'workers'");

  e = errorOf("[service\n");
  EXPECT_CONTAINS(e, "test.conf:1:9: not valid TOML: Error while parsing table header");

  e = errorOf("[service]\ninstance_id = \"\xff\"\n");
  EXPECT_CONTAINS(e, "test.conf:2:");
  EXPECT_CONTAINS(e, "invalid utf-8");

  e = errorOf("[service]\nmax_models = 99999999999999999999\n");
  EXPECT_CONTAINS(e, "not representable in 64 bits");
}

// Every prefix and some corruptions of the documented file: accepted or a ConfigError
// naming test.conf, never another exception or a crash.
TEST(ServerConfigErrors, DamagedFilesGiveConfigErrorsOnly) {
  const std::string text = testing::readFile(testing::sourceDir() / "deploy/robodiffd.conf");
  std::size_t refused = 0;
  for (std::size_t n = 0; n < text.size(); n += 13) {
    std::string damaged = text.substr(0, n);
    if (n % 2 == 0 && n + 1 < text.size()) damaged += std::string(1, static_cast<char>(n % 256)) + text.substr(n + 1);
    const std::string e = errorOf(damaged);
    if (e.empty()) continue;
    ++refused;
    EXPECT_EQ(e.rfind("test.conf:", 0), 0u) << e;
  }
  EXPECT_GT(refused, 0u);
}

TEST(ServerConfigErrors, MissingFileOrDirectoryIsNamed) {
  testing::TempDir dir;
  ServerConfig config;
  for (const std::string& path : {(dir / "absent.conf").string(), dir.path().string()}) {
    try {
      applyConfigFile(config, path);
      ADD_FAILURE() << path << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_CONTAINS(std::string(e.what()), "cannot read configuration file " + path);
    }
  }
}

}  // namespace
}  // namespace robodiff::server
