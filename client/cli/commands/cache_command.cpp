// `robodiff cache ls|stat|verify|repair|gc|rm`: look into the cache of compiled libraries,
// check every artifact's hash, rebuild a lost index, trim it to a budget, remove entries.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "output/output_table.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/entry_json.hpp"
#include "options/cache_location.hpp"
#include "output/human_units.hpp"

namespace robodiff::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::size_t kMinimumPrefix = 8;  // hex digits `cache rm` needs to name a key

struct CacheArgs {
  std::string dir;
  bool json = false;
  std::string budget;             // gc, stat
  std::vector<std::string> keys;  // rm
  bool all = false;               // rm
};

fs::path cacheDir(const CacheArgs& args) { return cacheDirFor(args.dir); }

// The cache, or nothing when its directory does not exist yet (nothing was ever built
// there); a path that exists but is no directory, or is unsafe, is an error.
std::optional<cache::Cache> openExisting(const CacheArgs& args) {
  const fs::path dir = cacheDir(args);
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    std::cerr << "robodiff: no cache at " << dir.string() << " (nothing built there yet)\n";
    return std::nullopt;
  }
  return openCliCache(dir, args.budget, false);
}

std::int64_t nowSeconds() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string keyPrefix(const std::string& key) { return key.substr(0, 12); }

std::map<std::string, cache::Entry> entriesByKey(cache::Cache& cache) {
  std::map<std::string, cache::Entry> entries;
  for (cache::Entry& e : cache.list()) entries.emplace(e.key, std::move(e));
  return entries;
}

// ---- ls -----------------------------------------------------------------------------

void listEntries(const CacheArgs& args) {
  std::optional<cache::Cache> cache = openExisting(args);
  const std::vector<cache::Entry> entries = cache ? cache->list() : std::vector<cache::Entry>{};
  if (args.json) {
    json rows = json::array();
    for (const cache::Entry& e : entries) rows.push_back(robodiff::cache::entryJson(e));
    std::cout << rows.dump(2) << "\n";
    return;
  }
  if (entries.empty()) {
    std::cout << "no entries\n";
    return;
  }
  const std::int64_t now = nowSeconds();
  Table table = Table::rows({"key", "robot", "function", "state", "size", "age", "hits", "last used"},
                            {false, false, false, false, true, true, true, true});
  std::uint64_t total = 0;
  for (const cache::Entry& e : entries) {
    total += e.total_bytes;
    table.addRow({keyPrefix(e.key), e.info.robot, e.info.function, e.state, formatBytes(e.total_bytes),
                  formatAge(now - e.created), std::to_string(e.hits),
                  e.last_used > 0 ? formatAge(now - e.last_used) + " ago" : "never"});
  }
  table.print(std::cout);
  std::cout << entries.size() << (entries.size() == 1 ? " entry, " : " entries, ") << formatBytes(total)
            << ", most recently used first\n";
}

// ---- stat ---------------------------------------------------------------------------

void showStats(const CacheArgs& args) {
  std::optional<cache::Cache> cache = openExisting(args);
  cache::CacheStats s;
  if (cache) {
    s = cache->stats();
  } else {
    s.dir = cacheDir(args);
    s.budget_bytes = args.budget.empty() ? cache::CacheOptions{}.budget_bytes : parseSize(args.budget);
  }
  if (args.json) {
    std::cout << json{{"dir", s.dir.string()}, {"exists", cache.has_value()},
                      {"entries", s.entries},  {"building", s.building},
                      {"bytes", s.bytes},      {"budget_bytes", s.budget_bytes},
                      {"hits", s.hits},        {"quarantined", s.quarantined}}
                     .dump(2)
              << "\n";
    return;
  }
  const std::string budget = s.budget_bytes == 0 ? "none" : formatBytes(s.budget_bytes);
  std::cout << "directory    " << s.dir.string() << (cache ? "" : " (does not exist yet)") << "\n"
            << "entries      " << s.entries << " ready, " << s.building << " building\n"
            << "size         " << formatBytes(s.bytes) << " (" << s.bytes << " bytes)\n"
            << "budget       " << budget << "\n"
            << "hits         " << s.hits << "\n"
            << "quarantined  " << s.quarantined << "\n";
}

// ---- verify -------------------------------------------------------------------------

void verifyEntries(const CacheArgs& args) {
  std::optional<cache::Cache> cache = openExisting(args);
  if (!cache) {
    std::cout << (args.json ? json{{"checked", 0}, {"problems", json::array()}}.dump(2) : "0 entries checked") << "\n";
    return;
  }
  // Problem entries leave the index during verify: their names are read first.
  const std::map<std::string, cache::Entry> entries = entriesByKey(*cache);
  const cache::VerifyReport report = cache->verify();
  const auto name = [&](const std::string& key, bool robot) {
    const auto it = entries.find(key);
    return it == entries.end() ? std::string("?") : robot ? it->second.info.robot : it->second.info.function;
  };
  if (args.json) {
    json problems = json::array();
    for (const cache::VerifyProblem& p : report.problems)
      problems.push_back(
          {{"key", p.key}, {"robot", name(p.key, true)}, {"function", name(p.key, false)}, {"problem", p.problem}});
    std::cout << json{{"checked", report.checked}, {"problems", problems}}.dump(2) << "\n";
  } else {
    if (!report.problems.empty()) {
      Table table = Table::rows({"key", "robot", "function", "problem"}, {false, false, false, false});
      for (const cache::VerifyProblem& p : report.problems)
        table.addRow({keyPrefix(p.key), name(p.key, true), name(p.key, false), p.problem});
      table.print(std::cout);
    }
    std::cout << report.checked << (report.checked == 1 ? " entry" : " entries") << " checked, ";
    if (report.problems.empty())
      std::cout << "no problems\n";
    else
      std::cout << report.problems.size()
                << (report.problems.size() == 1
                        ? " problem (moved to quarantine; it will be rebuilt on next use)\n"
                        : " problems (moved to quarantine; they will be rebuilt on next use)\n");
  }
  std::cout.flush();
  if (!report.problems.empty()) throw CLI::RuntimeError(2);  // main returns the status without a message
}

// ---- repair -------------------------------------------------------------------------

void repairIndex(const CacheArgs& args) {
  const fs::path dir = cacheDir(args);
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    std::cerr << "robodiff: no cache at " << dir.string() << " (nothing built there yet)\n";
    std::cout << (args.json ? json{{"scanned", 0}, {"recovered", 0}, {"already_indexed", 0}, {"quarantined", json::array()}}.dump(2)
                            : "nothing to repair")
              << "\n";
    return;
  }
  cache::Cache cache = openCliCache(dir, args.budget, false, false);
  const cache::RepairReport report = cache.repair();
  if (args.json) {
    json quarantined = json::array();
    for (const cache::VerifyProblem& p : report.quarantined) quarantined.push_back({{"key", p.key}, {"problem", p.problem}});
    std::cout << json{{"scanned", report.scanned},
                      {"recovered", report.recovered},
                      {"already_indexed", report.already_indexed},
                      {"quarantined", quarantined}}
                     .dump(2)
              << "\n";
    return;
  }
  if (!report.quarantined.empty()) {
    Table table = Table::rows({"key", "problem"}, {false, false});
    for (const cache::VerifyProblem& p : report.quarantined) table.addRow({keyPrefix(p.key), p.problem});
    table.print(std::cout);
  }
  std::cout << report.recovered << " recovered, " << report.quarantined.size() << " quarantined, "
            << report.already_indexed << " already indexed (" << report.scanned
            << (report.scanned == 1 ? " object directory" : " object directories") << " scanned)\n";
}

// ---- gc -----------------------------------------------------------------------------

void collectGarbage(const CacheArgs& args) {
  std::optional<cache::Cache> cache = openExisting(args);
  if (!cache) {
    std::cout << (args.json ? json{{"evicted", json::array()}, {"freed_bytes", 0}}.dump(2) : "nothing to do") << "\n";
    return;
  }
  const std::map<std::string, cache::Entry> entries = entriesByKey(*cache);
  const std::optional<std::uint64_t> asked =
      args.budget.empty() ? std::nullopt : std::optional<std::uint64_t>(parseSize(args.budget));
  const std::uint64_t budget = asked.value_or(cache->options().budget_bytes);
  const cache::GcReport report = cache->gc(asked);
  if (args.json) {
    json evicted = json::array();
    for (const std::string& key : report.evicted) {
      const auto it = entries.find(key);
      evicted.push_back({{"key", key},
                         {"robot", it == entries.end() ? "" : it->second.info.robot},
                         {"function", it == entries.end() ? "" : it->second.info.function},
                         {"bytes", it == entries.end() ? 0 : it->second.total_bytes}});
    }
    std::cout << json{{"budget_bytes", budget},
                      {"evicted", evicted},
                      {"freed_bytes", report.freed_bytes},
                      {"bytes_after", report.bytes_after},
                      {"kept_in_use", report.kept_in_use},
                      {"stale_claims", report.stale_claims},
                      {"stale_staging", report.stale_staging},
                      {"quarantine_removed", report.quarantine_removed}}
                     .dump(2)
              << "\n";
    return;
  }
  if (!report.evicted.empty()) {
    Table table = Table::rows({"evicted", "robot", "function", "size"}, {false, false, false, true});
    for (const std::string& key : report.evicted) {
      const auto it = entries.find(key);
      table.addRow({keyPrefix(key), it == entries.end() ? "?" : it->second.info.robot,
                    it == entries.end() ? "?" : it->second.info.function,
                    it == entries.end() ? "?" : formatBytes(it->second.total_bytes)});
    }
    table.print(std::cout);
  }
  std::cout << "evicted " << report.evicted.size() << (report.evicted.size() == 1 ? " entry" : " entries") << ", freed "
            << formatBytes(report.freed_bytes) << "; now " << formatBytes(report.bytes_after)
            << (budget == 0 ? " (no budget)" : " of a budget of " + formatBytes(budget)) << "\n";
  if (report.kept_in_use > 0)
    std::cout << "kept " << report.kept_in_use << (report.kept_in_use == 1 ? " entry" : " entries")
              << " over the budget because in use\n";
  if (report.stale_claims + report.stale_staging > 0)
    std::cout << "removed " << report.stale_claims << " stale claims and " << report.stale_staging
              << " staging directories left by processes that are gone\n";
  if (report.quarantine_removed > 0)
    std::cout << "removed " << report.quarantine_removed << " quarantined artifacts (found corrupt earlier)\n";
}

// ---- rm -----------------------------------------------------------------------------

std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string describe(const cache::Entry& e) {
  return keyPrefix(e.key) + "  " + e.info.robot + "  " + e.info.function + "  " + formatBytes(e.total_bytes);
}

// The one entry `text` (a key, or a prefix of at least 8 hex digits) names.
const cache::Entry& resolve(const std::string& text, const std::vector<cache::Entry>& entries) {
  const std::string prefix = lowercase(text);
  const bool hex = std::all_of(prefix.begin(), prefix.end(), [](char c) { return std::isxdigit(c) != 0; });
  if (!hex || prefix.size() < kMinimumPrefix || prefix.size() > 64)
    throw std::runtime_error("'" + text + "' is not a key: give a key or its first " + std::to_string(kMinimumPrefix) +
                             " or more hex digits (robodiff cache ls shows them)");
  std::vector<const cache::Entry*> matches;
  for (const cache::Entry& e : entries)
    if (e.key.compare(0, prefix.size(), prefix) == 0) matches.push_back(&e);
  if (matches.empty()) throw std::runtime_error("no entry has a key starting with " + prefix);
  if (matches.size() > 1) {
    std::string list;
    for (const cache::Entry* e : matches) list += "\n  " + e->key + "  " + e->info.robot + "  " + e->info.function;
    throw std::runtime_error(prefix + " is ambiguous: " + std::to_string(matches.size()) +
                             " keys start with it; give more digits:" + list);
  }
  return *matches.front();
}

void removeEntries(const CacheArgs& args) {
  if (args.all == !args.keys.empty())
    throw std::runtime_error("cache rm: give the keys to remove, or --all (and not both)");
  std::optional<cache::Cache> cache = openExisting(args);
  const std::vector<cache::Entry> entries = cache ? cache->list() : std::vector<cache::Entry>{};

  // Every key is resolved before anything is removed: a typo removes nothing.
  std::vector<const cache::Entry*> chosen;
  if (args.all) {
    for (const cache::Entry& e : entries) chosen.push_back(&e);
  } else {
    for (const std::string& text : args.keys) {
      const cache::Entry& e = resolve(text, entries);
      if (std::find(chosen.begin(), chosen.end(), &e) == chosen.end()) chosen.push_back(&e);
    }
  }

  json removed = json::array(), kept = json::array();
  std::uint64_t freed = 0;
  std::vector<std::string> refusals;
  for (const cache::Entry* e : chosen) {
    std::string why;
    if (e->state != "ready") {
      why = "being built by " + (e->owner.empty() ? std::string("another process") : e->owner);
    } else {
      try {
        if (!cache->remove(e->key)) why = "already gone";
      } catch (const cache::CacheError& error) {
        why = error.what();
      }
    }
    if (why.empty()) {
      freed += e->total_bytes;
      removed.push_back(
          {{"key", e->key}, {"robot", e->info.robot}, {"function", e->info.function}, {"bytes", e->total_bytes}});
      if (!args.json) std::cout << "removed  " << describe(*e) << "\n";
    } else {
      kept.push_back({{"key", e->key}, {"robot", e->info.robot}, {"function", e->info.function}, {"reason", why}});
      if (!args.json) std::cout << "kept     " << describe(*e) << "  (" << why << ")\n";
      refusals.push_back(keyPrefix(e->key) + ": " + why);
    }
  }
  if (args.json) {
    std::cout << json{{"removed", removed}, {"kept", kept}, {"freed_bytes", freed}}.dump(2) << "\n";
  } else {
    std::cout << "removed " << removed.size() << (removed.size() == 1 ? " entry" : " entries") << ", freed "
              << formatBytes(freed);
    if (!kept.empty()) std::cout << "; kept " << kept.size() << " (in use)";
    std::cout << "\n";
  }
  std::cout.flush();
  // --all removes what it can; named keys that could not be removed are an error.
  if (!args.all && !refusals.empty()) {
    std::string list;
    for (const std::string& r : refusals) list += "\n  " + r;
    throw std::runtime_error("not removed:" + list);
  }
}

// --cache and --json, on every subcommand.
void addCommonOptions(CLI::App& cmd, CacheArgs& args, const std::string& json_help) {
  cmd.add_option("--cache", args.dir,
                 "Cache directory (default: $ROBODIFF_CACHE_DIR, else $XDG_CACHE_HOME/robodiff, else "
                 "~/.cache/robodiff)")
      ->type_name("DIR");
  cmd.add_flag("--json", args.json, json_help);
}

}  // namespace

void addCacheCommand(CLI::App& app) {
  auto args = std::make_shared<CacheArgs>();
  CLI::App* cmd = app.add_subcommand("cache", "List, check, trim and clean the cache of compiled function libraries");
  cmd->require_subcommand(1);
  cmd->footer(
      "The cache holds one directory per key (a SHA-256 over the robot, the spec, the generator, the compiler "
      "and the target CPU); `robodiff warmup` fills it.\n"
      "Exit status: 0 on success, 1 on errors (unusable cache directory, unknown key); `cache verify` returns "
      "2 when it found a problem.");

  CLI::App* ls = cmd->add_subcommand("ls", "List the entries, most recently used first");
  addCommonOptions(*ls, *args, "Print a JSON array with every field of each entry");
  ls->footer(
      "Columns: key (first 12 hex digits), robot, function, state (ready, building), size on disk, age, "
      "hits, last use.\nExit status: 0, or 1 on errors.");
  ls->callback([args] { listEntries(*args); });

  CLI::App* st = cmd->add_subcommand("stat", "Show the cache's directory, entries, size, budget, hits, quarantine");
  addCommonOptions(*st, *args, "Print a JSON object");
  st->add_option("--budget", args->budget,
                 "The size budget to show (default 4G, as warmup and gc use when not given one)")
      ->type_name("SIZE");
  st->footer("Exit status: 0, or 1 on errors.");
  st->callback([args] { showStats(*args); });

  CLI::App* vf = cmd->add_subcommand(
      "verify", "Check every entry's files and library hash; move bad ones to quarantine (rebuilt on next use)");
  addCommonOptions(*vf, *args, "Print a JSON object: checked, problems [{key, robot, function, problem}]");
  vf->footer(
      "Exit status: 0 when every entry is sound, 2 when problems were found (each is listed), 1 on "
      "errors.");
  vf->callback([args] { verifyEntries(*args); });

  CLI::App* rp = cmd->add_subcommand(
      "repair", "Rebuild the index from the objects on disk: re-index good ones, quarantine bad ones");
  addCommonOptions(*rp, *args, "Print a JSON object: scanned, recovered, already_indexed, quarantined [{key, problem}]");
  rp->footer(
      "Each object directory's entry.json (written when it was published) gives its index row; the library's "
      "size and SHA-256 are checked against it. Entries that are missing, damaged or cannot be verified are "
      "moved to quarantine (rebuilt on next use). Opening a cache whose index is missing or empty repairs it "
      "by itself; this command does it on demand and reports it.\n"
      "Exit status: 0 when the index was repaired (quarantined entries included), 1 on errors.");
  rp->callback([args] { repairIndex(*args); });

  CLI::App* gcc = cmd->add_subcommand(
      "gc",
      "Evict least recently used entries to fit the budget; remove what dead processes left behind and the "
      "quarantined artifacts");
  addCommonOptions(*gcc, *args, "Print a JSON object: evicted, freed_bytes, bytes_after, kept_in_use, ...");
  gcc->add_option("--budget", args->budget,
                  "Trim to this size: 500M, 2G, 1.5GiB, plain bytes (K, M, G, KiB, MiB, GiB: powers of 1024; "
                  "KB, MB, GB: powers of 1000; default 4G)")
      ->type_name("SIZE");
  gcc->footer(
      "Entries in use by a running process are never evicted (reported as kept).\n"
      "Exit status: 0, or 1 on errors.");
  gcc->callback([args] { collectGarbage(*args); });

  CLI::App* rm = cmd->add_subcommand("rm", "Remove entries by key (or unique key prefix), or --all");
  addCommonOptions(*rm, *args, "Print a JSON object: removed, kept, freed_bytes");
  rm->add_option("keys", args->keys,
                 "Keys, or prefixes of at least " + std::to_string(kMinimumPrefix) +
                     " hex digits naming one entry each (robodiff cache ls shows them)")
      ->type_name("KEY");
  rm->add_flag("--all", args->all, "Remove every entry not in use");
  rm->footer(
      "Nothing is removed when a key is unknown or a prefix is ambiguous (the matches are listed).\n"
      "Exit status: 0 when every named entry was removed (--all: entries in use are kept), 1 on errors.");
  rm->callback([args] { removeEntries(*args); });

  addCacheTransferCommands(*cmd);  // export, import
}

}  // namespace robodiff::cli
