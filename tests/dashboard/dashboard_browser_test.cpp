// robodiffd's dashboard page in headless Chromium, driven through chromedriver (W3C
// WebDriver, support/webdriver.hpp). First the browser plumbing on its own (a static page:
// scripts, waiting for a DOM change, a screenshot); then the page of a real robodiffd
// (RouDi, real build workers) while an iceoryx client loads arm7, gets a function built
// and evaluates it: the model row, the function's phase reaching "compiled", the call
// count and latency, a failed function with its message, a job's progress, all refreshed
// live without a reload and without errors; a screenshot is kept in
// <build>/test-artifacts/dashboard.png. Then a robodiffd whose compiler always fails with
// a long message: the page opened after a few seconds of calls draws its charts at once
// (the server's history), the 500-character note takes one line and shows whole on a
// click, and failed builds and invalid specs are counted apart.
// Skips (naming the program) where chromium or chromedriver is not installed.
#include <signal.h>

#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiffd/service_fixture.hpp"
#include "support/webdriver.hpp"

namespace robodiff::testing {
namespace {

using namespace std::chrono_literals;
using json = nlohmann::json;

std::filesystem::path artifactsDir() { return ROBODIFF_TEST_ARTIFACTS_DIR; }

void writeBytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// A PNG's width and height (from its IHDR chunk); zeros when too short.
std::pair<std::uint32_t, std::uint32_t> pngSize(const std::vector<std::uint8_t>& png) {
  if (png.size() < 24) return {0, 0};
  auto be32 = [&](std::size_t at) {
    return (std::uint32_t{png[at]} << 24) | (std::uint32_t{png[at + 1]} << 16) | (std::uint32_t{png[at + 2]} << 8) |
           std::uint32_t{png[at + 3]};
  };
  return {be32(16), be32(20)};
}

// Skips where a program is missing; fails (with chromedriver's log) where it does not start.
#define REQUIRE_CHROMEDRIVER(driver)                                                           \
  if (!(driver).available()) GTEST_SKIP() << (driver).unavailableReason();                     \
  ASSERT_TRUE((driver).running()) << (driver).startError()

TEST(DashboardBrowser, HeadlessChromiumRunsScriptsWaitsAndScreenshotsAStaticPage) {
  TempDir dir;
  ChromeDriverProcess driver(dir / "chromedriver.log");
  REQUIRE_CHROMEDRIVER(driver);
  WebDriverSession browser(driver);
  ASSERT_FALSE(browser.id().empty());

  const std::filesystem::path page = dir.file("page.html", R"html(<!doctype html>
<html><head><meta charset="utf-8"><title>robodiff static</title></head>
<body style="background: linear-gradient(90deg, #123 0%, #fa4 100%)">
<h1 id="status">waiting</h1>
<script>
  window.loadedAt = performance.now();
  setTimeout(() => {
    window.arrivedAt = performance.now();
    document.getElementById('status').textContent = 'arrived';
  }, 300);
</script></body></html>)html");
  browser.navigate("file://" + page.string());

  EXPECT_EQ(browser.executeScript("return document.title;"), "robodiff static");
  EXPECT_EQ(browser.executeScript("return arguments[0] * arguments[1];", {6, 7}), 42);
  EXPECT_EQ(browser.executeScript("return {a: [1, 'x'], b: null};"), json::parse(R"({"a": [1, "x"], "b": null})"));

  // The DOM change the page's timer makes, waited for; not before the timer fired.
  EXPECT_TRUE(browser.waitFor("document.getElementById('status').textContent === 'arrived'", 5s));
  EXPECT_GE(browser.executeScript("return window.arrivedAt - window.loadedAt;").get<double>(), 299.0);

  // A wait that times out names the last value; a script error names WebDriver's error.
  const ::testing::AssertionResult never = browser.waitFor("document.getElementById('status').textContent", 300ms);
  EXPECT_FALSE(never);
  EXPECT_NE(std::string(never.message()).find("\"arrived\""), std::string::npos) << never.message();
  try {
    browser.executeScript("throw new Error('boom from the page');");
    ADD_FAILURE() << "a throwing script did not throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("javascript error"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("boom from the page"), std::string::npos) << e.what();
  }

  const std::vector<std::uint8_t> png = browser.screenshotPng();
  EXPECT_TRUE(isPng(png)) << png.size() << " bytes";
  const auto [width, height] = pngSize(png);
  EXPECT_GE(width, 1000u);
  EXPECT_GE(height, 600u);

  browser.quit();
  driver.stop();
  EXPECT_FALSE(driver.running());
}

TEST(DashboardBrowser, Base64DecodesWithAndWithoutPadding) {
  auto text = [](const std::vector<std::uint8_t>& bytes) { return std::string(bytes.begin(), bytes.end()); };
  EXPECT_EQ(text(base64Decode("")), "");
  EXPECT_EQ(text(base64Decode("Zg==")), "f");
  EXPECT_EQ(text(base64Decode("Zm8=")), "fo");
  EXPECT_EQ(text(base64Decode("Zm9v")), "foo");
  EXPECT_EQ(text(base64Decode("Zm9vYmFy\nYmF6")), "foobarbaz");
  EXPECT_EQ(base64Decode("/+8A"), (std::vector<std::uint8_t>{0xFF, 0xEF, 0x00}));
  EXPECT_THROW(base64Decode("Zm9v!"), std::runtime_error);
}

// On a failure, the page as it was, for whoever reads the test's output.
struct ShowPageOnFailure {
  WebDriverSession& browser;
  ChromeDriverProcess& driver;
  RobodiffdProcess& server;
  ~ShowPageOnFailure() {
    if (!::testing::Test::HasFailure()) return;
    try {
      writeBytes(artifactsDir() / "dashboard-failure.png", browser.screenshotPng());
      std::cerr << "page text:\n"
                << browser.executeScript("return document.body ? document.body.innerText.slice(0, 3000) : '';")
                       .get<std::string>()
                << "\nwindow.robodiffDashboard.errors: "
                << browser.executeScript("return window.robodiffDashboard && window.robodiffDashboard.errors;")
                << "\nscreenshot: " << (artifactsDir() / "dashboard-failure.png").string() << "\n";
    } catch (const std::exception& e) {
      std::cerr << "no page to show: " << e.what() << "\n";
    }
    std::cerr << "robodiffd log:\n" << server.log() << "\nchromedriver log (tail):\n";
    const std::string log = driver.log();
    std::cerr << (log.size() > 4000 ? log.substr(log.size() - 4000) : log) << "\n";
  }
};

// A JS expression over the function row: true when `condition` (using `row`) holds,
// else what the row shows (so a timeout says what it was).
std::string functionRow(const std::string& function_id, const std::string& condition) {
  return "(() => { const row = document.querySelector('table#functions tbody tr[data-function-id=\"" + function_id +
         "\"]'); if (!row) return 'no row for the function'; "
         "const text = (sel) => { const e = row.querySelector(sel); return e ? e.textContent.trim() : null; }; "
         "const phase = row.getAttribute('data-phase'), calls = text('td.function-calls'), "
         "latency = text('td.function-latency'); "
         "return (" + condition + ") ? true : {phase, calls, latency, name: text('td.function-name')}; })()";
}

TEST(DashboardBrowser, LiveDashboardOfARealRobodiffd) {
  signal(SIGTERM, SIG_IGN);  // as the other robodiffd tests: this process registers with RouDi
  TempDir dir;
  ChromeDriverProcess driver(dir / "chromedriver.log");
  REQUIRE_CHROMEDRIVER(driver);
  sharedRoudi();
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log",
                          {"--roudi", "external", "--http", "127.0.0.1:0", "--set",
                           "jobs.data_dirs=" + (sourceDir() / "examples").string() + ":" + dir.path().string()});
  ASSERT_TRUE(server.running());
  const json listening = logEvent(server.log(), "http_listening");
  ASSERT_TRUE(listening.is_object()) << server.log();
  const auto port = listening["port"].get<std::uint16_t>();
  auto client = connectTo("iceoryx");

  rpc::LoadModelRequest load;
  load.urdf = arm7Text();
  rpc::LoadModelReply model;
  const Status loaded = client->loadModel(load, model);
  ASSERT_TRUE(loaded.ok()) << toString(loaded.code) << ": " << loaded.message;

  WebDriverSession browser(driver);
  const ShowPageOnFailure show_page_on_failure{browser, driver, server};

  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  browser.navigate(url);
  ASSERT_TRUE(browser.waitFor(
      "(() => { const row = document.querySelector('table#models tbody tr[data-model-id=\"" + model.model_id +
          "\"]'); const name = row && row.querySelector('td.model-name'); "
          "return name ? name.textContent.includes('arm7') || name.textContent : 'no model row'; })()",
      15s));

  // From here on the page must refresh itself: a reload would drop this mark.
  const int refreshes_before =
      browser.executeScript("window.__noReload = 1; return window.robodiffDashboard.refreshes;").get<int>();

  rpc::GetFunctionRequest get;
  get.model_id = model.model_id;
  get.spec_json = kRneaJacobianSpec;
  get.wait = false;
  rpc::GetFunctionReply function;
  const Status got = client->getFunction(get, function);
  ASSERT_TRUE(got.ok()) << toString(got.code) << ": " << got.message;
  ASSERT_FALSE(function.function_id.empty());
  // Every phase the function row shows from now on, sampled every 20 ms.
  browser.executeScript(
      "window.__phasesSeen = []; setInterval(() => { "
      "const row = document.querySelector('table#functions tbody tr[data-function-id=\"' + arguments[0] + '\"]'); "
      "const phase = row && row.getAttribute('data-phase'); "
      "if (phase && window.__phasesSeen[window.__phasesSeen.length - 1] !== phase) window.__phasesSeen.push(phase); "
      "}, 20);",
      {function.function_id});

  EXPECT_TRUE(browser.waitFor(functionRow(function.function_id, "phase === 'compiled'"), 60s));
  EXPECT_TRUE(browser.waitFor(functionRow(function.function_id, "text('td.function-name') === 'rnea'"), 5s));
  const json phases_seen = browser.executeScript("return window.__phasesSeen;");
  const std::set<std::string> building_phases = {"tracing", "queued", "compiling", "interpreted", "compiled"};
  for (const json& phase : phases_seen)
    EXPECT_TRUE(building_phases.count(phase.get<std::string>())) << "phase " << phase << " in " << phases_seen;
  EXPECT_EQ(browser.executeScript("return window.__noReload;"), 1) << "the page reloaded";
  EXPECT_GT(browser.executeScript("return window.robodiffDashboard.refreshes;").get<int>(), refreshes_before);

  // Calls: counted on the page, with a latency. In bursts over ~3 s, so that the charts
  // get several one-second points.
  constexpr int kEvaluations = 200, kBursts = 8;
  const std::vector<double> in(21, 0.1);
  std::vector<double> out(7 + 7 * 21);
  int evaluated = 0;
  for (int i = 0; i < kEvaluations; ++i) {
    if (i > 0 && i % (kEvaluations / kBursts) == 0) std::this_thread::sleep_for(350ms);
    const Status s = client->evaluate(function.function_id, in, out);
    if (s.ok()) ++evaluated;
    else ADD_FAILURE() << "evaluation " << i << ": " << toString(s.code) << ": " << s.message;
  }
  ASSERT_EQ(evaluated, kEvaluations);
  EXPECT_TRUE(browser.waitFor(functionRow(function.function_id,
                                          "calls !== null && /^\\d+$/.test(calls) && Number(calls) >= " +
                                              std::to_string(kEvaluations) +
                                              " && latency !== null && latency !== '' && latency !== '\u2013'"),
                              10s));

  // The latency chart draws a line (two points or more) of those calls. A point is one
  // refresh with calls in it; on a loaded machine the page may refresh only once or twice
  // during the bursts above, so small bursts go on (one every ~0.5 s) until the line is
  // there or 20 s have passed.
  const std::string line_drawn =
      "[...document.querySelectorAll('svg#latency-chart path, svg#latency-chart polyline')].some((line) => "
      "/[\\d.]+[ ,][\\d.]+[^\\d.]+[\\d.]+[ ,][\\d.]+/.test(line.getAttribute('d') || line.getAttribute('points') || "
      "'')) || document.querySelector('svg#latency-chart').innerHTML.slice(0, 300)";
  for (int burst = 0; burst < 40 && !browser.waitFor(line_drawn, 500ms); ++burst)
    for (int i = 0; i < 10; ++i) {
      const Status s = client->evaluate(function.function_id, in, out);
      ASSERT_TRUE(s.ok()) << "evaluation in burst " << burst << ": " << toString(s.code) << ": " << s.message;
    }
  EXPECT_TRUE(browser.waitFor(line_drawn, 1s));

  // A function the model cannot serve: refused and unloaded (a failed spec holds no slot),
  // and listed under failed builds as an invalid spec, with its message.
  {
    rpc::GetFunctionRequest bad;
    bad.model_id = model.model_id;
    bad.spec_json = R"({"function": "fk", "frame": "no_such_frame", "outputs": [{"kind": "value"}]})";
    bad.wait = true;
    rpc::GetFunctionReply reply;
    EXPECT_FALSE(client->getFunction(bad, reply).ok());
    rpc::ListFunctionsReply list;
    ASSERT_TRUE(client->listFunctions({}, list).ok());
    for (const rpc::FunctionSummary& f : list.functions) EXPECT_NE(f.function_name, "fk") << "a failed spec stayed loaded";
    EXPECT_TRUE(browser.waitFor(
        "(() => { const items = [...document.querySelectorAll('#build-failures li')]; "
        "const item = items.find((i) => i.textContent.includes('no_such_frame')); "
        "return item ? item.textContent.includes('invalid spec') || item.textContent : 'no failure listed'; })()",
        10s));
    EXPECT_TRUE(browser.waitFor("document.getElementById('specs-invalid').textContent === '1' || "
                                "document.getElementById('specs-invalid').textContent",
                                10s));
    EXPECT_EQ(browser.executeScript("return document.getElementById('builds-failed').textContent;"), "0");
  }

  // A small trajectory job (its function is in the cache by now): its row and progress.
  {
    std::ofstream csv(dir / "trajectory.csv");
    csv << "t";
    for (const char* block : {"q", "v", "a"})
      for (int i = 0; i < 7; ++i) csv << "," << block << "_" << i;
    csv << "\n";
    for (int k = 0; k < 20; ++k) {
      csv << 0.01 * k;
      for (int i = 0; i < 21; ++i) csv << "," << 0.05 * ((k + i) % 7);
      csv << "\n";
    }
  }
  const json params = {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()},
                       {"spec_json", json::parse(kRneaJacobianSpec)},
                       {"data", (dir / "trajectory.csv").string()},
                       {"out", "out.rdb"}};
  rpc::SubmitJobReply job;
  const Status submitted = client->submitJob(rpc::SubmitJobRequest{"trajectory", params.dump()}, job);
  ASSERT_TRUE(submitted.ok()) << toString(submitted.code) << ": " << submitted.message;
  EXPECT_TRUE(browser.waitFor(
      "(() => { const row = document.querySelector('table#jobs tbody tr[data-job-id=\"" + job.job_id +
          "\"]'); if (!row) return 'no row for the job'; const progress = row.querySelector('progress'); "
          "const state = row.getAttribute('data-state'); "
          "return (state === 'SUCCEEDED' && progress !== null && Number(progress.value) === 1) || "
          "{state, progress: progress && progress.value}; })()",
      30s));

  // The rest of the contract is there; nothing went wrong on the page.
  for (const char* selector : {"svg#latency-chart", "svg#rate-chart", "#cache-hit-rate", "#cache-bytes"})
    EXPECT_EQ(browser.executeScript("return document.querySelector(arguments[0]) !== null;", {selector}), true)
        << selector;
  EXPECT_EQ(browser.executeScript("return typeof window.robodiffDashboard.overview;"), "object");
  // Not in a fleet: no Fleet panel (dashboard_fleet_browser_test.cpp shows it for the others).
  EXPECT_EQ(browser.executeScript("return window.robodiffDashboard.overview.fleet.role;"), "standalone");
  EXPECT_EQ(browser.executeScript("return getComputedStyle(document.getElementById('fleet')).display;"), "none");
  EXPECT_EQ(browser.executeScript("return window.__noReload;"), 1) << "the page reloaded";
  EXPECT_EQ(browser.executeScript("return window.robodiffDashboard.errors;"), json::array());

  const std::vector<std::uint8_t> png = browser.screenshotPng();
  const std::filesystem::path artifact = artifactsDir() / "dashboard.png";
  writeBytes(artifact, png);
  EXPECT_TRUE(isPng(png));
  EXPECT_GT(png.size(), 10u * 1024) << artifact;
  EXPECT_EQ(std::filesystem::file_size(artifact), png.size());

  browser.quit();
  driver.stop();
  client.reset();
  EXPECT_EQ(server.terminate(), 0) << server.log();
}


// A "compiler" that tells its version and fails every build with one long line: the
// function is served by the interpreter, its note being that line (and the command).
std::filesystem::path failingCompiler(const TempDir& dir) {
  std::string line = "fakecc: error:";
  while (line.size() < 500) line += " this compiler fails every build on purpose, with a long message;";
  const std::filesystem::path path = dir.file("fakecc", "#!/bin/sh\ncase \"$1\" in --version|-v) echo 'fakecc 1.0'; exit 0;; esac\n"
                                                        "echo '" + line + " END' >&2\nexit 1\n");
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path;
}

TEST(DashboardBrowser, ChartsAtFirstSightOneLineNotesAndFailuresCountedApart) {
  signal(SIGTERM, SIG_IGN);
  TempDir dir;
  ChromeDriverProcess driver(dir / "chromedriver.log");
  REQUIRE_CHROMEDRIVER(driver);
  sharedRoudi();
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log",
                          {"--roudi", "external", "--http", "127.0.0.1:0", "--set",
                           "build.compiler=" + failingCompiler(dir).string()});
  ASSERT_TRUE(server.running());
  const json listening = logEvent(server.log(), "http_listening");
  ASSERT_TRUE(listening.is_object()) << server.log();
  const auto port = listening["port"].get<std::uint16_t>();
  auto client = connectTo("iceoryx");
  rpc::LoadModelRequest load;
  load.urdf = arm7Text();
  rpc::LoadModelReply model;
  ASSERT_TRUE(client->loadModel(load, model).ok());
  rpc::GetFunctionRequest get{model.model_id, kRneaJacobianSpec, true};
  rpc::GetFunctionReply function;
  const Status got = client->getFunction(get, function);
  ASSERT_TRUE(got.ok()) << toString(got.code) << ": " << got.message;  // the interpreter serves it
  rpc::GetFunctionRequest bad{model.model_id, R"({"function": "fk", "frame": "no_such_frame", "outputs": [{"kind": "value"}]})", true};
  rpc::GetFunctionReply bad_reply;
  EXPECT_EQ(client->getFunction(bad, bad_reply).code, StatusCode::InvalidArgument);

  // ~5 s of calls before any page is open: the server's history holds them. It samples
  // once a second and the check below counts the points older than a second before the
  // page opened, so ~4 of them (3 s of calls left 2 or 3, depending on the phase).
  const std::vector<double> in(21, 0.1);
  std::vector<double> out(7 + 7 * 21);
  for (int burst = 0; burst < 12; ++burst) {
    for (int i = 0; i < 20; ++i) ASSERT_TRUE(client->evaluate(function.function_id, in, out).ok());
    std::this_thread::sleep_for(400ms);
  }

  WebDriverSession browser(driver);
  const ShowPageOnFailure show_page_on_failure{browser, driver, server};
  browser.navigate("http://127.0.0.1:" + std::to_string(port) + "/");
  // Right after the first refresh: a latency line of several points, from before the page opened.
  ASSERT_TRUE(browser.waitFor("window.robodiffDashboard && window.robodiffDashboard.refreshes >= 1", 10s));
  const json first = browser.executeScript(
      "const d = window.robodiffDashboard; "
      "const vertices = [...document.querySelectorAll('svg#latency-chart path')].map((p) => "
      "(p.getAttribute('d').match(/[ML]/g) || []).length); "
      "return {refreshes: d.refreshes, vertices: Math.max(0, ...vertices), "
      "before_open: d.history.filter((p) => p.t < d.openedAt - 1 && p.latency['Evaluate p50'] != null).length};");
  EXPECT_LE(first["refreshes"].get<int>(), 2) << first;
  EXPECT_GE(first["vertices"].get<int>(), 3) << first;
  EXPECT_GE(first["before_open"].get<int>(), 3) << first;

  // The build failed: its note is one line, ellipsised, with the whole text on demand.
  ASSERT_TRUE(browser.waitFor(functionRow(function.function_id, "phase === 'build-failed'"), 60s));
  const std::string note = "document.querySelector('table#functions tbody tr[data-function-id=\"" +
                           function.function_id + "\"] td.message .note')";
  const std::string measure =
      "const n = " + note + "; const line = parseFloat(getComputedStyle(n).lineHeight); "
      "const f = window.robodiffDashboard.overview.functions.find((f) => f.id === arguments[0]); "
      "return {height: n.getBoundingClientRect().height, line, cut: n.scrollWidth > n.clientWidth, "
      "text: n.textContent, title: n.title, shown: n.innerText, message: f.message, "
      "expanded: n.classList.contains('expanded')};";
  json shown = browser.executeScript(measure, {function.function_id});
  const std::string message = shown["message"].get<std::string>();
  EXPECT_GE(message.size(), 500u);
  EXPECT_NE(message.find("on purpose"), std::string::npos) << message;
  EXPECT_LT(shown["height"].get<double>(), 1.5 * shown["line"].get<double>()) << shown;  // one line
  EXPECT_TRUE(shown["cut"].get<bool>()) << shown;
  EXPECT_EQ(shown["title"], message);
  EXPECT_EQ(shown["text"], message);

  browser.executeScript(note + ".click();");
  const int refreshes = browser.executeScript("return window.robodiffDashboard.refreshes;").get<int>();
  ASSERT_TRUE(browser.waitFor("window.robodiffDashboard.refreshes > " + std::to_string(refreshes), 5s));
  shown = browser.executeScript(measure, {function.function_id});  // redrawn since the click
  EXPECT_TRUE(shown["expanded"].get<bool>()) << shown;
  EXPECT_GT(shown["height"].get<double>(), 3 * shown["line"].get<double>()) << shown;
  EXPECT_EQ(shown["shown"], message);  // every character visible
  browser.executeScript(note + ".click();");
  shown = browser.executeScript(measure, {function.function_id});
  EXPECT_LT(shown["height"].get<double>(), 1.5 * shown["line"].get<double>()) << shown;

  // One failed build, one invalid spec: each in its own tile.
  EXPECT_TRUE(browser.waitFor("document.getElementById('builds-failed').textContent === '1' && "
                              "document.getElementById('specs-invalid').textContent === '1' || "
                              "[document.getElementById('builds-failed').textContent, "
                              "document.getElementById('specs-invalid').textContent]",
                              5s));
  EXPECT_EQ(browser.executeScript("return window.robodiffDashboard.errors;"), json::array());
  writeBytes(artifactsDir() / "dashboard-notes.png", browser.screenshotPng());

  browser.quit();
  driver.stop();
  client.reset();
  EXPECT_EQ(server.terminate(), 0) << server.log();
}

}  // namespace
}  // namespace robodiff::testing
