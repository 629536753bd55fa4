// Re-creating the index from the objects on disk: each object directory carries its
// row's metadata in entry.json; a directory whose files match it is indexed again, one
// that does not (or has no entry.json) is quarantined.
#include <iostream>

#include "artifact_files.hpp"
#include "cache_state.hpp"
#include "entry_sidecar.hpp"
#include "robodiff/cache/cache_key.hpp"

namespace robodiff::cache {

namespace fs = std::filesystem;
using namespace detail;

namespace {

// The key directories under objects/<kk>/, whatever the index says.
std::vector<std::pair<std::string, fs::path>> objectDirectories(const Cache::State& s) {
  std::vector<std::pair<std::string, fs::path>> out;
  std::error_code ec;
  for (fs::directory_iterator prefix(s.objects(), ec), end; !ec && prefix != end; prefix.increment(ec)) {
    if (!prefix->is_directory(ec)) continue;
    std::error_code inner;
    for (fs::directory_iterator it(prefix->path(), inner); !inner && it != end; it.increment(inner)) {
      const std::string name = it->path().filename().string();
      if (it->is_directory(inner) && isCacheKey(name) && name.compare(0, 2, prefix->path().filename().string()) == 0)
        out.emplace_back(name, it->path());
    }
  }
  return out;
}

// The entry an unindexed object directory holds, or why it cannot be trusted.
std::string recoverableEntry(const std::string& key, const fs::path& dir, Entry& entry) {
  try {
    entry = readSidecar(dir / kSidecarName);
  } catch (const std::exception& e) {
    return std::string("it cannot be verified: ") + e.what();
  }
  if (entry.key != key) return std::string(kSidecarName) + " names another key (" + entry.key + "): moved or replaced";
  return entryProblem(entry, dir);
}

}  // namespace

RepairReport detail::repairIndex(Cache::State& s) {
  RepairReport report;
  // 1. Indexed entries whose files went bad.
  for (const Entry& e : s.db->entries("WHERE state = 'ready' ORDER BY key")) {
    const std::string problem = entryProblem(e, s.objectDir(e.key));
    if (problem.empty()) continue;
    report.quarantined.push_back({e.key, problem});
    quarantineEntry(s, e.key, problem);
  }
  // 2. Every object directory: indexed already, recovered, or quarantined.
  for (const auto& [key, dir] : objectDirectories(s)) {
    ++report.scanned;
    const std::optional<Entry> row = s.db->entry(key);
    if (row && row->state == "ready") {
      ++report.already_indexed;
      continue;
    }
    if (row) continue;  // claimed: its builder's publish() replaces the directory
    Entry entry;
    if (const std::string problem = recoverableEntry(key, dir, entry); !problem.empty()) {
      report.quarantined.push_back({key, problem});
      quarantineEntry(s, key, problem);
      continue;
    }
    std::error_code ec;
    if (!fs::exists(dir / "pin", ec)) writeFileSynced(dir / "pin", "");
    entry.total_bytes = directoryBytes(dir);
    indexReadyRow(s, entry, ExistingRow::Keep);
    ++report.recovered;
  }
  return report;
}

void detail::repairWhenIndexEmpty(Cache::State& s) {
  if (Statement(s.db->handle(), "SELECT 1 FROM entries LIMIT 1").step() || objectDirectories(s).empty()) return;
  std::cerr << "robodiff cache: the index " << (s.dir / "index.sqlite").string()
            << " has no entries but objects exist; repairing it from the objects\n";
  const RepairReport r = repairIndex(s);
  std::cerr << "robodiff cache: repair: " << r.recovered << " recovered, " << r.quarantined.size()
            << " quarantined, " << r.already_indexed << " already indexed\n";
}

RepairReport Cache::repair() {
  std::lock_guard lock(state_->mutex);
  return repairIndex(*state_);
}

}  // namespace robodiff::cache
