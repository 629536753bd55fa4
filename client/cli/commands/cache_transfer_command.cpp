// `robodiff cache export` and `robodiff cache import`: signed cache entries moved between
// hosts as one file (cache/include/robodiff/cache/artifact_bundle.hpp does the work).
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "options/cache_location.hpp"
#include "output/human_units.hpp"
#include "robodiff/cache/artifact_bundle.hpp"
#include "robodiff/cache/cache_key.hpp"

namespace robodiff::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::size_t kMinimumKeyPrefix = 8;

struct TransferArgs {
  std::string dir;
  bool json = false;
  std::vector<std::string> keys;  // export
  bool all = false;               // export
  std::string sign, out;          // export
  std::string bundle;             // import
  std::vector<std::string> trust;  // import
  std::string budget;             // import
};

// Full keys for what was named: a whole key, or a prefix naming exactly one ready entry.
std::vector<std::string> chooseKeys(cache::Cache& cache, const TransferArgs& args) {
  if (args.all == !args.keys.empty()) throw std::runtime_error("cache export: give --key KEY (repeatable) or --all, not both");
  std::vector<std::string> ready, chosen;
  for (const cache::Entry& e : cache.list())
    if (e.state == "ready") ready.push_back(e.key);
  if (args.all) {
    if (ready.empty()) throw std::runtime_error("cache export --all: the cache " + cache.dir().string() + " has no entries");
    return ready;
  }
  for (const std::string& text : args.keys) {
    std::vector<std::string> matches;
    if (cache::isCacheKey(text)) matches.push_back(text);
    else if (text.size() >= kMinimumKeyPrefix)
      for (const std::string& k : ready)
        if (k.rfind(text, 0) == 0) matches.push_back(k);
    if (matches.size() != 1)
      throw std::runtime_error("cache export: --key " + text +
                               (matches.empty() ? " names no entry (give a key, or a prefix of at least " +
                                                      std::to_string(kMinimumKeyPrefix) + " hex digits; cache ls shows them)"
                                                : " is ambiguous; give more digits"));
    chosen.push_back(matches.front());
  }
  return chosen;
}

void exportEntries(const TransferArgs& args) {
  const fs::path dir = cacheDirFor(args.dir);
  if (!fs::exists(dir)) throw std::runtime_error("no cache at " + dir.string() + " (nothing to export)");
  const cache::SigningKey signer = cache::SigningKey::load(args.sign);  // before anything is written
  cache::Cache cache = openCliCache(dir, "", false);
  const cache::ExportReport report = cache::exportBundle(cache, chooseKeys(cache, args), signer, args.out);
  if (args.json) {
    json keys = json::array();
    for (const cache::Entry& e : report.exported)
      keys.push_back({{"key", e.key}, {"robot", e.info.robot}, {"function", e.info.function}});
    std::cout << json{{"file", args.out}, {"signer", signer.keyId()}, {"bytes", report.bytes}, {"entries", keys}}.dump(2)
              << "\n";
    return;
  }
  for (const cache::Entry& e : report.exported)
    std::cout << "exported  " << e.key.substr(0, 12) << "  " << e.info.robot << "  " << e.info.function << "\n";
  std::cout << report.exported.size() << (report.exported.size() == 1 ? " entry" : " entries") << " signed by key "
            << signer.keyId() << ", written to " << args.out << " (" << formatBytes(report.bytes) << ")\n";
}

const char* statusName(cache::ImportResult::Status s) {
  switch (s) {
    case cache::ImportResult::Status::Imported: return "imported";
    case cache::ImportResult::Status::Present: return "present";
    case cache::ImportResult::Status::Refused: break;
  }
  return "refused";
}

void printImport(const cache::ImportReport& report, bool as_json) {
  using Status = cache::ImportResult::Status;
  if (as_json) {
    json rows = json::array();
    for (const cache::ImportResult& r : report.entries)
      rows.push_back({{"key", r.key}, {"status", statusName(r.status)}, {"robot", r.robot}, {"function", r.function},
                      {"signer", r.signer}, {"problem", r.problem}});
    std::cout << json{{"imported", report.count(Status::Imported)}, {"present", report.count(Status::Present)},
                      {"refused", report.count(Status::Refused)}, {"entries", rows}}
                     .dump(2)
              << "\n";
    return;
  }
  for (const cache::ImportResult& r : report.entries) {
    std::string status = statusName(r.status);
    status.resize(10, ' ');
    std::cout << status << (cache::isCacheKey(r.key) ? r.key.substr(0, 12) : r.key);
    if (r.status == Status::Refused)
      std::cout << "  " << r.problem << "\n";
    else
      std::cout << "  " << r.robot << "  " << r.function << "  (signed by " << r.signer << ")\n";
  }
  std::cout << report.count(Status::Imported) << " imported, " << report.count(Status::Present)
            << " already present and intact, " << report.count(Status::Refused) << " refused";
  if (report.count(Status::Refused) > 0 && report.count(Status::Imported) > 0)
    std::cout << " (the other entries were imported)";
  std::cout << "\n";
}

void importEntries(const TransferArgs& args) {
  std::vector<fs::path> trust(args.trust.begin(), args.trust.end());
  const cache::TrustedKeys trusted = cache::TrustedKeys::load(trust);
  if (!fs::is_regular_file(args.bundle)) throw std::runtime_error("no bundle file " + args.bundle);
  cache::Cache cache = openCliCache(cacheDirFor(args.dir), args.budget, true);
  const cache::ImportReport report = cache::importBundle(cache, args.bundle, trusted);
  printImport(report, args.json);
  std::cout.flush();
  if (!report.allAccepted()) throw CLI::RuntimeError(1);  // each refusal is listed above
}

void addCacheOption(CLI::App& cmd, TransferArgs& args) {
  cmd.add_option("--cache", args.dir,
                 "Cache directory (default: $ROBODIFF_CACHE_DIR, else $XDG_CACHE_HOME/robodiff, else ~/.cache/robodiff)")
      ->type_name("DIR");
}

}  // namespace

void addCacheTransferCommands(CLI::App& cache_command) {
  auto args = std::make_shared<TransferArgs>();
  CLI::App* ex = cache_command.add_subcommand("export", "Write verified entries, signed, to one bundle file");
  addCacheOption(*ex, *args);
  ex->add_option("--key", args->keys, "An entry to export: its key, or a unique prefix of at least 8 hex digits (repeatable)")
      ->type_name("KEY");
  ex->add_flag("--all", args->all, "Export every ready entry");
  ex->add_option("--sign", args->sign, "Private key to sign with (robodiff keygen makes one; mode 0600)")
      ->required()
      ->type_name("KEYFILE");
  ex->add_option("--out", args->out, "The bundle file to write (a tar archive; replaced when it exists)")
      ->required()
      ->type_name("FILE");
  ex->add_flag("--json", args->json, "Print a JSON object: file, signer, bytes, entries [{key, robot, function}]");
  ex->footer(
      "Each entry is verified (its library's SHA-256) before it is written; its manifest (key, model hash, spec, "
      "compiler and flags, each file's size and SHA-256, the signer's key id and the time) is signed with Ed25519.\n"
      "Exit status: 0, or 1 on errors (unknown key, entry being built or damaged, unsafe key file); nothing is "
      "written then.");
  ex->callback([args] { exportEntries(*args); });

  CLI::App* im = cache_command.add_subcommand("import", "Verify a bundle's signed entries and file the good ones");
  addCacheOption(*im, *args);
  im->add_option("bundle", args->bundle, "The bundle file (from robodiff cache export)")->required()->type_name("FILE");
  im->add_option("--trust", args->trust, "A trusted public key file, or a directory of *.pub files (repeatable)")
      ->required()
      ->type_name("PUBFILE|DIR");
  im->add_option("--budget", args->budget, "The cache's size budget (default 4G)")->type_name("SIZE");
  im->add_flag("--json", args->json,
               "Print a JSON object: imported, present, refused, entries [{key, status, robot, function, signer, problem}]");
  im->footer(
      "Every entry is checked before it touches the cache: signed by a trusted key, its manifest's key = its "
      "directory, plain file names only, sizes within limits, each file's size and SHA-256 as signed, no file "
      "missing or extra. Good entries appear atomically; entries already present and intact are left alone; "
      "refused entries leave nothing behind, and the others still import.\n"
      "Exit status: 0 when every entry was imported or present, 1 when any was refused (each is listed with "
      "its problem) or on errors.");
  im->callback([args] { importEntries(*args); });
}

}  // namespace robodiff::cli
