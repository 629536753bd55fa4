// Signing an entry's payload out and receiving one in (entry_transfer.hpp): what a tar
// bundle and a fleet transfer share.
#include "robodiff/cache/entry_transfer.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "artifact_files.hpp"
#include "received_files.hpp"
#include "robodiff/model/canonical.hpp"

namespace robodiff::cache {

namespace fs = std::filesystem;

namespace {

constexpr auto kClaimWait = std::chrono::seconds(30);

std::string readWhole(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CacheError(CacheError::Kind::Io, "cannot read " + file.string() + ": " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

// ---- sending ----

std::uint64_t SignedEntry::payloadBytes() const {
  std::uint64_t total = 0;
  for (const EntryFile& f : files) total += f.bytes.size();
  return total;
}

void SignedEntry::readPayload(std::uint64_t offset, std::size_t max_bytes, std::vector<std::uint8_t>& out) const {
  const std::uint64_t total = payloadBytes();
  out.resize(offset >= total ? 0 : static_cast<std::size_t>(std::min<std::uint64_t>(max_bytes, total - offset)));
  std::size_t filled = 0;
  std::uint64_t start = 0;  // where the current file begins in the payload
  for (const EntryFile& f : files) {
    if (filled == out.size()) break;
    const std::uint64_t end = start + f.bytes.size();
    const std::uint64_t at = offset + filled;
    if (at < end) {
      const auto take = static_cast<std::size_t>(std::min<std::uint64_t>(out.size() - filled, end - at));
      std::memcpy(out.data() + filled, f.bytes.data() + (at - start), take);
      filled += take;
    }
    start = end;
  }
}

Artifact exportableArtifact(Cache& cache, const std::string& key) {
  const std::optional<Entry> row = cache.entry(key);
  if (!row) throw std::runtime_error("cache entry " + key + " is not in the cache (nothing exported)");
  if (row->state != "ready")
    throw std::runtime_error("cache entry " + key + " is still being built (nothing exported)");
  if (std::optional<Artifact> a = cache.find(key)) return *a;
  throw std::runtime_error("cache entry " + key + " failed verification and was moved to quarantine (nothing exported)");
}

std::vector<EntryFile> entryFiles(const Artifact& artifact, bool include_sources) {
  std::vector<EntryFile> files{{"description.json", readWhole(artifact.description())},
                               {"library.so", readWhole(artifact.library())}};
  if (!include_sources) return files;
  std::vector<fs::path> sources;
  std::error_code ec;
  for (fs::directory_iterator it(artifact.dir() / "src", ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".zst") sources.push_back(it->path());
  std::sort(sources.begin(), sources.end());
  for (const fs::path& s : sources) {
    const std::string name = "src/" + s.stem().string();
    if (!isEntryFileName(name))
      throw std::runtime_error("cache entry " + artifact.key() + " has a source named " + s.filename().string() +
                               ", which cannot be exported");
    files.push_back({name, detail::decompressFile(s)});
  }
  return files;
}

SignedEntry signEntry(const Artifact& artifact, const SigningKey& signer, bool include_sources,
                      std::int64_t signed_at) {
  SignedEntry out;
  out.key = artifact.key();
  out.files = entryFiles(artifact, include_sources);
  EntryManifest m;
  m.key = artifact.key();
  m.info = artifact.entry().info;
  m.signer = signer.keyId();
  m.signed_at = signed_at;
  for (const EntryFile& f : out.files) m.files.push_back({f.name, f.bytes.size(), sha256Hex(f.bytes)});
  out.manifest = manifestText(m);
  out.signature_hex = toHex(signer.sign(out.manifest));
  return out;
}

// ---- filing a verified entry ----

ImportResult installVerifiedEntry(Cache& cache, const EntryManifest& m, const fs::path& dir) {
  ImportResult r;
  r.key = m.key;
  r.robot = m.info.robot;
  r.function = m.info.function;
  r.signer = m.signer;
  ClaimResult claim = cache.waitOrClaim(m.key, m.info, std::chrono::steady_clock::now() + kClaimWait);
  if (claim.state == ClaimResult::State::Ready) {
    r.status = ImportResult::Status::Present;
    return r;
  }
  if (claim.state == ClaimResult::State::Busy) {
    r.problem = "being built by another process (" + claim.holder + "); try again when it is done";
    return r;
  }
  ArtifactFiles files{dir / "library.so", dir / "description.json", {}};
  std::string library_sha;
  for (const ManifestFile& f : m.files) {
    if (f.name.rfind("src/", 0) == 0) files.sources.push_back(dir / f.name);
    if (f.name == "library.so") library_sha = f.sha256;
  }
  std::string published_sha;
  try {
    published_sha = cache.publish(*claim.claim, m.info, files).entry().library_sha256;  // the pin goes here
  } catch (const std::exception& e) {
    r.problem = std::string("could not be filed in the cache: ") + e.what();
    return r;
  }
  // What landed is what was signed (the scratch copy cannot have changed in between).
  if (published_sha != library_sha) {
    try {
      cache.remove(m.key);
    } catch (const std::exception&) {
      // In use already: find() verifies it against the index before every load.
    }
    r.problem = "library.so changed while it was filed in the cache; removed again";
    return r;
  }
  r.status = ImportResult::Status::Imported;
  return r;
}

// ---- receiving ----

struct EntryReceiver::State {
  std::string manifest_text, signature_hex;
  TrustedKeys trusted;
  EntryManifest manifest;
  std::uint64_t payload = 0, received = 0;
  std::unique_ptr<detail::ScratchDir> scratch;
  std::size_t next = 0;                         // the manifest's file being written
  std::unique_ptr<detail::HashingFile> writing;  // its scratch copy
  std::map<std::string, ReceivedEntry::File> done;
  std::string broken;  // a write that failed: the scratch copy cannot be trusted

  // Starts the next file that has bytes to come, creating the empty ones on the way.
  void openNext() {
    for (; next < manifest.files.size(); ++next) {
      const ManifestFile& f = manifest.files[next];
      const fs::path to = scratch->path() / f.name;
      if (f.name.rfind("src/", 0) == 0 && ::mkdir(to.parent_path().c_str(), 0700) != 0 && errno != EEXIST)
        throw CacheError(CacheError::Kind::Io, "cannot create " + to.parent_path().string() + ": " + std::strerror(errno));
      writing = std::make_unique<detail::HashingFile>(to);
      if (f.size > 0) return;
      done[f.name] = writing->finish();
      writing.reset();
    }
  }

  void write(const std::uint8_t* data, std::size_t size) {
    while (size > 0) {
      const ManifestFile& f = manifest.files[next];
      const auto take = static_cast<std::size_t>(std::min<std::uint64_t>(size, f.size - writing->size()));
      writing->write(data, take);
      data += take;
      size -= take;
      received += take;
      if (writing->size() == f.size) {
        done[f.name] = writing->finish();
        writing.reset();
        ++next;
        openNext();
      }
    }
  }

  // Which file the payload stopped in, for an incomplete one.
  std::string whereItStopped() const {
    if (next >= manifest.files.size()) return "";
    const ManifestFile& f = manifest.files[next];
    return "; it stops in " + f.name + " after " + std::to_string(writing ? writing->size() : 0) + " of its " +
           std::to_string(f.size) + " bytes";
  }
};

namespace {

// The signed, parsed manifest, within the limits and for `expected_key`; else TransferRefused.
EntryManifest acceptedManifest(const std::string& text, const std::string& signature_hex, const TrustedKeys& trusted,
                               const std::string& expected_key, const TransferLimits& limits) {
  if (text.size() > limits.max_manifest_bytes)
    throw TransferRefused("the manifest has " + std::to_string(text.size()) + " bytes, more than the limit of " +
                          std::to_string(limits.max_manifest_bytes));
  if (signature_hex.empty()) throw TransferRefused("unsigned: no signature came with the manifest");
  ManifestCheck check = verifySignedManifest(text, signature_hex, trusted);
  if (!check.manifest) throw TransferRefused(check.problem);
  EntryManifest& m = *check.manifest;
  if (!expected_key.empty() && m.key != expected_key)
    throw TransferRefused("swapped: the signed manifest is for entry " + m.key + ", but entry " + expected_key +
                          " was asked for");
  if (m.files.size() > limits.max_files)
    throw TransferRefused("the manifest lists " + std::to_string(m.files.size()) + " files, more than the limit of " +
                          std::to_string(limits.max_files));
  std::uint64_t total = 0;
  for (const ManifestFile& f : m.files) {
    if (f.size > limits.max_payload_bytes - total)  // no overflow: total <= the limit
      throw TransferRefused("the entry's files add up to more than the limit of " +
                            std::to_string(limits.max_payload_bytes) + " bytes (at " + f.name + ", " +
                            std::to_string(f.size) + " bytes); not received");
    total += f.size;
  }
  return std::move(m);
}

}  // namespace

EntryReceiver::EntryReceiver(const std::string& manifest, const std::string& signature_hex, const TrustedKeys& trusted,
                             const std::string& expected_key, const TransferLimits& limits)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.manifest = acceptedManifest(manifest, signature_hex, trusted, expected_key, limits);
  s.manifest_text = manifest;
  s.signature_hex = signature_hex;
  s.trusted = trusted;
  for (const ManifestFile& f : s.manifest.files) s.payload += f.size;
  s.scratch = std::make_unique<detail::ScratchDir>("receive");
  s.openNext();
}

EntryReceiver::~EntryReceiver() = default;
EntryReceiver::EntryReceiver(EntryReceiver&&) noexcept = default;
EntryReceiver& EntryReceiver::operator=(EntryReceiver&&) noexcept = default;

const EntryManifest& EntryReceiver::manifest() const { return state_->manifest; }
std::uint64_t EntryReceiver::payloadBytes() const { return state_->payload; }
std::uint64_t EntryReceiver::received() const { return state_->received; }

void EntryReceiver::append(const std::uint8_t* data, std::size_t size) {
  State& s = *state_;
  if (size > s.payload - s.received)
    throw TransferRefused("more bytes than the signed manifest lists: it lists " + std::to_string(s.payload) +
                          ", " + std::to_string(s.received) + " arrived and then " + std::to_string(size) + " more");
  try {
    s.write(data, size);
  } catch (const std::exception& e) {
    s.broken = e.what();
    throw;
  }
}

ImportResult EntryReceiver::install(Cache& cache) {
  State& s = *state_;
  if (!s.broken.empty()) throw TransferRefused("not received: writing it to a scratch directory failed: " + s.broken);
  if (!complete())
    throw TransferRefused("incomplete: " + std::to_string(s.received) + " of " + std::to_string(s.payload) +
                          " bytes received" + s.whereItStopped());
  ReceivedEntry r;
  r.key = s.manifest.key;
  r.manifest = s.manifest_text;
  r.signature = s.signature_hex;
  r.files = s.done;
  const ManifestCheck check = verifyReceivedEntry(r, s.trusted);
  if (!check.manifest) throw TransferRefused(check.problem);
  return installVerifiedEntry(cache, *check.manifest, s.scratch->path());
}

}  // namespace robodiff::cache
