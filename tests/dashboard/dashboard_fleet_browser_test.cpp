// The dashboard's Fleet panel and the "fetching" phase in headless Chromium, without a
// fleet: the page (as in the source tree) is opened from a file with `fetch` replaced by
// one that answers /api/overview with a fixture the test changes between refreshes. A
// standalone server hides the panel; a robot host shows its counts and a row per build
// host, with strings from the network shown as text (never as HTML); a build host shows
// what it served; a function being fetched is listed and coloured as in progress.
// Skips (naming the program) where chromium or chromedriver is not installed.
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"
#include "support/webdriver.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;
using json = nlohmann::json;

// An /api/overview with every field the page reads (docs/service.md, "The dashboard"):
// no model, no request; one function asking the build hosts; `fleet` as given.
json fleetPageOverview(const json& fleet) {
  return {{"instance_id", "robot:1:fixture"}, {"version", "9.9.9"}, {"state", "SERVING"}, {"uptime_seconds", 3.0},
          {"unix_seconds", 1.8e9}, {"models", json::array()},
          {"functions", json::array({{{"id", "f-fetching"}, {"model_id", "m1"}, {"model_name", "arm7"},
                                      {"function", "rnea"}, {"outputs", "value"}, {"phase", "fetching"},
                                      {"message", ""}, {"references", 1}, {"evaluations", 0}, {"calls", 0},
                                      {"p50_us", 0}, {"p99_us", 0}, {"max_us", 0}, {"batch_calls", 0},
                                      {"batch_knots", 0}, {"batch_us_per_knot", nullptr}, {"trace_seconds", 0.1},
                                      {"compile_seconds", nullptr}, {"from_cache", false}}})},
          {"builds", {{"queued", 0}, {"running", 0}, {"failed", 0}, {"done", 0}}}, {"specs_invalid", 0},
          {"build_failures", json::array()},
          {"cache", {{"hits", 0}, {"misses", 1}, {"hit_rate", 0.0}, {"bytes", 0}, {"entries", 0}, {"stats_ok", true}}},
          {"workers", {{"total", 1}, {"busy", 0}}}, {"queue", {{"depth", 0}, {"capacity", 64}}},
          {"jobs_enabled", false},
          {"job_counts", {{"QUEUED", 0}, {"RUNNING", 0}, {"SUCCEEDED", 0}, {"FAILED", 0}, {"CANCELLED", 0}}},
          {"jobs", json::array()}, {"jobs_error", ""}, {"methods", json::array()}, {"transports", json::array()},
          {"fleet", fleet}};
}

json fleetPageFigures(const std::string& role) {
  return {{"role", role}, {"target", ""}, {"artifacts_fetched", 0}, {"bytes_fetched", 0}, {"artifacts_refused", 0},
          {"fetch_failures", 0}, {"artifacts_served", 0}, {"bytes_served", 0}, {"builds_for_robots", 0},
          {"peers", json::array()}};
}

// The page with, before its own script, a `fetch` answering from window.__overview.
std::string fleetPageWithFixture(const json& overview) {
  std::string page = readFile(sourceDir() / "server/http/dashboard/dashboard.html");
  const std::string stub =
      "<head>\n<script>\nwindow.__overview = " + overview.dump() +
      ";\nwindow.fetch = async (path) => ({ ok: true, status: 200, json: async () => JSON.parse(JSON.stringify("
      "path.startsWith('/api/overview') ? window.__overview : "
      "{ capacity: 120, interval_seconds: 1, points: [] })) });\n</script>";
  const std::size_t head = page.find("<head>");
  if (head == std::string::npos) throw std::runtime_error("dashboard.html has no <head>");
  page.replace(head, 6, stub);
  return page;
}

void fleetPageWriteBytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Sets the fixture; the page shows it from its next refresh on, when `drawn` (a JS
// expression) becomes true.
void fleetPageShow(WebDriverSession& browser, const json& overview, const std::string& drawn) {
  browser.executeScript("window.__overview = arguments[0];", json::array({overview}));
  ASSERT_TRUE(browser.waitFor(drawn, 10s));
}

const char* const kFleetRole = "document.getElementById('fleet-role').textContent";
const char* const kFleetDisplay = "getComputedStyle(document.getElementById('fleet')).display";

TEST(DashboardFleet, PanelHiddenWhenStandaloneShownForRobotAndBuildHostsAsText) {
  TempDir dir;
  ChromeDriverProcess driver(dir / "chromedriver.log");
  if (!driver.available()) GTEST_SKIP() << driver.unavailableReason();
  ASSERT_TRUE(driver.running()) << driver.startError();
  WebDriverSession browser(driver);
  const std::filesystem::path page =
      dir.file("dashboard.html", fleetPageWithFixture(fleetPageOverview(fleetPageFigures("standalone"))));
  browser.navigate("file://" + page.string());
  ASSERT_TRUE(browser.waitFor("window.robodiffDashboard && window.robodiffDashboard.refreshes >= 1 || "
                              "(window.robodiffDashboard && window.robodiffDashboard.errors)",
                              10s));

  // Standalone: no panel. The function being fetched waits in the build queue, coloured
  // as work in progress (not the grey of an unknown phase).
  EXPECT_EQ(browser.executeScript(std::string("return ") + kFleetDisplay + ";"), "none");
  const json fetching = browser.executeScript(
      "const b = document.querySelector('#build-queue tr[data-function-id=\"f-fetching\"] .badge'); "
      "return b && {text: b.textContent, colour: getComputedStyle(b).color, title: b.title};");
  ASSERT_TRUE(fetching.is_object()) << "no build-queue row for the function being fetched";
  EXPECT_EQ(fetching["text"], "fetching");
  EXPECT_EQ(fetching["colour"], "rgb(31, 95, 191)");  // --info, as queued and compiling
  EXPECT_NE(fetching["title"].get<std::string>().find("build hosts"), std::string::npos) << fetching;

  // A robot host with two build hosts; one's name and problem are HTML.
  json robot = fleetPageFigures("robot");
  robot.update({{"target", "x86-64-v3"}, {"artifacts_fetched", 5}, {"bytes_fetched", 3 << 20},
                {"artifacts_refused", 1}, {"fetch_failures", 2}});
  const std::string evil_problem = "<img src=x onerror=\"window.__injected = 1\">bad signature";
  robot["peers"] = {{{"service", "robodiff_build_a"}, {"instance_id", "builder-a:42:x"}, {"reachable", true},
                     {"artifacts_fetched", 4}, {"bytes_fetched", 2 << 20}, {"refusals", 0}, {"failures", 1},
                     {"fetch_seconds", 0.25},
                     {"last_problem", "lost after 0 of 9 bytes"}},
                    {{"service", "<b>evil</b>"}, {"instance_id", ""}, {"reachable", false}, {"artifacts_fetched", 1},
                     {"bytes_fetched", 1 << 20}, {"refusals", 1}, {"failures", 7}, {"fetch_seconds", 12.0},
                     {"last_problem", evil_problem}}};
  fleetPageShow(browser, fleetPageOverview(robot),
                std::string(kFleetRole) + " === 'robot host' && document.querySelectorAll('#fleet-peers tbody tr')"
                                          ".length === 2");
  const json shown = browser.executeScript(
      "const fleet = document.getElementById('fleet'); "
      "const tile = (k) => { const t = fleet.querySelector('[data-fleet=\"' + k + '\"]'); "
      "  return t && [t.querySelector('.value').textContent, t.querySelector('.sub').textContent]; }; "
      "const rows = [...fleet.querySelectorAll('#fleet-peers tbody tr')].map((r) => ({host: r.dataset.buildHost, "
      "  cells: [...r.querySelectorAll('td')].map((c) => c.textContent)})); "
      "return {display: getComputedStyle(fleet).display, role: document.getElementById('fleet-role').textContent, "
      "  target: tile('target'), fetched: tile('fetched'), refused: tile('refused'), "
      "  failures: tile('fetch-failures'), served: tile('served'), rows, "
      "  elements: fleet.querySelectorAll('img, b').length, injected: window.__injected === 1};");
  EXPECT_NE(shown["display"], "none") << shown;
  EXPECT_EQ(shown["role"], "robot host");
  EXPECT_EQ(shown["target"][0], "x86-64-v3");
  EXPECT_EQ(shown["fetched"], json::parse(R"(["5", "3.0 MiB verified and filed"])"));
  EXPECT_EQ(shown["refused"][0], "1");
  EXPECT_EQ(shown["failures"][0], "2");
  EXPECT_TRUE(shown["served"].is_null()) << shown;  // a build host's figure
  ASSERT_EQ(shown["rows"].size(), 2u) << shown;
  EXPECT_EQ(shown["rows"][0]["host"], "robodiff_build_a");
  EXPECT_EQ(shown["rows"][0]["cells"], json::parse(R"(["robodiff_build_a", "builder-a:42:x", "yes", "4", "2.0 MiB",
                                                       "250 ms", "0", "1", "lost after 0 of 9 bytes"])"));
  EXPECT_EQ(shown["rows"][1]["host"], "<b>evil</b>");
  EXPECT_EQ(shown["rows"][1]["cells"], json({"<b>evil</b>", "never reached", "no", "1", "1.0 MiB", "12.0 s", "1", "7",
                                             evil_problem}));
  EXPECT_EQ(shown["elements"], 0) << "a string from the network became HTML";
  EXPECT_EQ(shown["injected"], false);
  fleetPageWriteBytes(std::filesystem::path(ROBODIFF_TEST_ARTIFACTS_DIR) / "dashboard-fleet.png", browser.screenshotPng());

  // A build host: what it served; no build-host table.
  json build = fleetPageFigures("build");
  build.update({{"artifacts_served", 3}, {"bytes_served", 5 << 20}, {"builds_for_robots", 2}});
  fleetPageShow(browser, fleetPageOverview(build), std::string(kFleetRole) + " === 'build host'");
  const json host = browser.executeScript(
      "const tile = (k) => { const t = document.querySelector('#fleet [data-fleet=\"' + k + '\"]'); "
      "  return t && t.querySelector('.value').textContent; }; "
      "return {role: document.getElementById('fleet-role').textContent, served: tile('served'), "
      "  builds: tile('builds-for-robots'), fetched: tile('fetched'), "
      "  peers: getComputedStyle(document.getElementById('fleet-peers')).display};");
  EXPECT_EQ(host, json::parse(R"({"role": "build host", "served": "3", "builds": "2", "fetched": null,
                                  "peers": "none"})"));

  // Back to standalone: hidden again.
  fleetPageShow(browser, fleetPageOverview(fleetPageFigures("standalone")), std::string(kFleetDisplay) + " === 'none'");
  EXPECT_EQ(browser.executeScript("return window.robodiffDashboard.errors;"), json::array());
  browser.quit();
  driver.stop();
}

}  // namespace
}  // namespace robodiff::testing
