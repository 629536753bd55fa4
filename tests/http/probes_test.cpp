// The probes: liveness notes, readiness lines and status, a throwing check, the cache
// directory's check; and both served over HTTP.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include "http/http_client.hpp"
#include "robodiff/server/probes.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::testing {
namespace {

using server::ProbeResult;
using server::Probes;

TEST(Probes, ReadyWhenEveryCheckPassesElse503NamingTheFailure) {
  Probes probes;
  bool roudi_up = true;
  probes.addReadinessCheck("roudi", [&] { return roudi_up ? ProbeResult{} : ProbeResult{false, "gone"}; });
  probes.addReadinessCheck("cache", [] { return ProbeResult{true, "writable"}; });
  auto r = probes.readiness();
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "roudi: ok\ncache: ok (writable)\n");
  roudi_up = false;
  r = probes.readiness();
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(r.body, "roudi: failed (gone)\ncache: ok (writable)\n");
}

TEST(Probes, ACheckThatThrowsFails) {
  Probes probes;
  probes.addReadinessCheck("dds", []() -> ProbeResult { throw std::runtime_error("participant lost"); });
  const auto r = probes.readiness();
  EXPECT_EQ(r.status, 503);
  EXPECT_NE(r.body.find("dds: failed (check threw: participant lost)"), std::string::npos) << r.body;
}

TEST(Probes, LivenessStaysOkWithANote) {
  Probes probes;
  EXPECT_EQ(probes.liveness().status, 200);
  EXPECT_EQ(probes.liveness().body, "ok\n");
  probes.setLivenessNote([] { return std::string("draining"); });
  EXPECT_EQ(probes.liveness().status, 200);
  EXPECT_EQ(probes.liveness().body, "ok (draining)\n");
}

TEST(Probes, DirectoryWritableCheck) {
  TempDir dir;
  const ProbeResult ok = server::checkDirectoryWritable(dir.path(), 1);
  EXPECT_TRUE(ok.ok) << ok.detail;
  EXPECT_NE(ok.detail.find("writable"), std::string::npos);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));  // the probe file is gone

  const ProbeResult missing = server::checkDirectoryWritable(dir.path() / "absent", 1);
  EXPECT_FALSE(missing.ok);
  EXPECT_NE(missing.detail.find("absent"), std::string::npos) << missing.detail;

  const ProbeResult full = server::checkDirectoryWritable(dir.path(), std::uint64_t{1} << 62);
  EXPECT_FALSE(full.ok);
  EXPECT_NE(full.detail.find("free"), std::string::npos) << full.detail;

  if (::geteuid() != 0) {  // root writes anywhere
    ::chmod(dir.path().c_str(), 0500);
    const ProbeResult read_only = server::checkDirectoryWritable(dir.path(), 1);
    ::chmod(dir.path().c_str(), 0700);
    EXPECT_FALSE(read_only.ok);
    EXPECT_NE(read_only.detail.find("cannot create"), std::string::npos) << read_only.detail;
  }
}

TEST(Probes, ServedOverHttp) {
  Probes probes;
  bool ok = true;
  probes.addReadinessCheck("thing", [&] { return ProbeResult{ok, ok ? "" : "broken"}; });
  server::HttpServerOptions options;
  options.port = 0;
  server::HttpServer http(options);
  probes.routeOn(http);
  http.start();
  EXPECT_EQ(httpGet(http.port(), "/healthz").status, 200);
  EXPECT_EQ(httpGet(http.port(), "/healthz").body, "ok\n");
  EXPECT_EQ(httpGet(http.port(), "/readyz").status, 200);
  ok = false;
  const HttpReply r = httpGet(http.port(), "/readyz");
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(r.body, "thing: failed (broken)\n");
  http.stop();
}

}  // namespace
}  // namespace robodiff::testing
