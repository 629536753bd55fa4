// A build host in the test process that lies: a real Service (a build host with its own
// cache and signing key) served over a real DdsServer, behind a ServiceApi that passes
// every call through but spoils the artifact answers the way a compromised or broken
// build host (or a network in between) would. The robot is a real robodiffd process.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <string>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/entry_manifest.hpp"
#include "robodiff/server/dds_server.hpp"
#include "robodiff/server/log.hpp"
#include "robodiff/server/service.hpp"

namespace robodiff::testing {

enum class ArtifactFault {
  None,
  FlippedByte,     // one payload byte changed on the way (the signature still good)
  OtherTarget,     // a manifest re-signed (with the trusted key) claiming another x86-64 level
  OtherFunction,   // a manifest re-signed for another portable key (a swapped library)
  ShortChunk,      // a chunk that says the payload is smaller than the manifest's
};

class FaultyArtifacts final : public server::ServiceApi {
 public:
  FaultyArtifacts(server::Service& real, const cache::SigningKey& key) : real_(real), key_(key) {}
  void set(ArtifactFault fault) { fault_ = fault; }

  const std::string& instanceId() const override { return real_.instanceId(); }
  Status admit(const rpc::RequestHeader& h) const override { return real_.admit(h); }
  Status loadModel(const server::CallContext& c, const rpc::LoadModelRequest& q, rpc::LoadModelReply& r) override {
    return real_.loadModel(c, q, r);
  }
  Status getFunction(const server::CallContext& c, const rpc::GetFunctionRequest& q,
                     rpc::GetFunctionReply& r) override {
    return real_.getFunction(c, q, r);
  }
  Status listFunctions(const server::CallContext& c, const rpc::ListFunctionsRequest& q,
                       rpc::ListFunctionsReply& r) override {
    return real_.listFunctions(c, q, r);
  }
  Status health(const server::CallContext& c, const rpc::HealthRequest& q, rpc::HealthReply& r) override {
    return real_.health(c, q, r);
  }
  Status release(const server::CallContext& c, const rpc::ReleaseRequest& q, rpc::ReleaseReply& r) override {
    return real_.release(c, q, r);
  }
  Status shape(std::string_view id, server::FunctionShape& s) override { return real_.shape(id, s); }
  Status evaluate(const server::CallContext& c, std::string_view id, std::span<const double> in,
                  std::span<double> out) override {
    return real_.evaluate(c, id, in, out);
  }
  Status evaluateBatch(const server::CallContext& c, std::string_view id, std::uint64_t knots,
                       std::span<const double> in, std::span<double> out) override {
    return real_.evaluateBatch(c, id, knots, in, out);
  }
  bool post(std::function<void()> task) override { return real_.post(std::move(task)); }
  void recordRequest(std::string_view t, rpc::Method m, StatusCode code, std::chrono::nanoseconds l) override {
    real_.recordRequest(t, m, code, l);
  }

  Status queryArtifact(const server::CallContext& c, const rpc::QueryArtifactRequest& q,
                       rpc::QueryArtifactReply& r) override {
    const Status s = real_.queryArtifact(c, q, r);
    if (!s.ok() || r.state != rpc::ArtifactState::Have) return s;
    if (fault_ == ArtifactFault::OtherTarget || fault_ == ArtifactFault::OtherFunction) resign(r);
    return s;
  }
  Status fetchArtifactChunk(const server::CallContext& c, const rpc::FetchArtifactChunkRequest& q,
                            rpc::FetchArtifactChunkReply& r) override {
    const Status s = real_.fetchArtifactChunk(c, q, r);
    if (!s.ok() || r.data.empty()) return s;
    if (fault_ == ArtifactFault::FlippedByte) r.data[r.data.size() / 2] ^= 0x40;
    if (fault_ == ArtifactFault::ShortChunk) r.payload_bytes -= 1;
    return s;
  }

 private:
  // The manifest changed as the fault says and signed again with the build host's key.
  void resign(rpc::QueryArtifactReply& r) const {
    cache::EntryManifest m = cache::parseManifest(r.manifest_json);
    if (fault_ == ArtifactFault::OtherTarget) {
      const auto at = m.info.compiler.rfind(" target=");
      m.info.compiler = m.info.compiler.substr(0, at) + " target=x86-64-v2";
      if (m.info.compiler.find("target=x86-64-v2") != std::string::npos && r.manifest_json.find("x86-64-v2") != std::string::npos)
        m.info.compiler = m.info.compiler.substr(0, at) + " target=x86-64-v3";  // the robot asked v2: claim v3
    } else {
      m.info.portable_key = std::string(64, 'a');
    }
    r.manifest_json = cache::manifestText(m);
    r.signature_hex = cache::toHex(key_.sign(r.manifest_json));
  }

  server::Service& real_;
  const cache::SigningKey& key_;
  std::atomic<ArtifactFault> fault_{ArtifactFault::None};
};

}  // namespace robodiff::testing
