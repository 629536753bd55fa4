#pragma once
// Test helpers for signed bundles: take a tar bundle apart into its members and put a
// (tampered) list of members together again, with libarchive as the product does.
#include <archive.h>
#include <archive_entry.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace robodiff::cache::testing_bundle {

struct Member {
  std::string name;
  std::string bytes;
  bool symlink = false;  // written as a symbolic link to `bytes`
};

inline std::vector<Member> readMembers(const std::filesystem::path& tar) {
  std::unique_ptr<archive, decltype(&archive_read_free)> a(archive_read_new(), archive_read_free);
  archive_read_support_format_tar(a.get());
  EXPECT_EQ(archive_read_open_filename(a.get(), tar.c_str(), 1 << 16), ARCHIVE_OK) << tar;
  std::vector<Member> members;
  archive_entry* e = nullptr;
  while (archive_read_next_header(a.get(), &e) == ARCHIVE_OK) {
    Member m{archive_entry_pathname(e), std::string(static_cast<std::size_t>(archive_entry_size(e)), '\0')};
    if (!m.bytes.empty()) {
      EXPECT_EQ(archive_read_data(a.get(), m.bytes.data(), m.bytes.size()), static_cast<la_ssize_t>(m.bytes.size()));
    }
    members.push_back(std::move(m));
  }
  return members;
}

inline void writeMembers(const std::filesystem::path& tar, const std::vector<Member>& members) {
  std::unique_ptr<archive, decltype(&archive_write_free)> a(archive_write_new(), archive_write_free);
  archive_write_set_format_pax_restricted(a.get());
  ASSERT_EQ(archive_write_open_filename(a.get(), tar.c_str()), ARCHIVE_OK) << tar;
  for (const Member& m : members) {
    std::unique_ptr<archive_entry, decltype(&archive_entry_free)> e(archive_entry_new(), archive_entry_free);
    archive_entry_set_pathname(e.get(), m.name.c_str());
    archive_entry_set_perm(e.get(), 0644);
    if (m.symlink) {
      archive_entry_set_filetype(e.get(), AE_IFLNK);
      archive_entry_set_symlink(e.get(), m.bytes.c_str());
      archive_entry_set_size(e.get(), 0);
      ASSERT_EQ(archive_write_header(a.get(), e.get()), ARCHIVE_OK);
      continue;
    }
    archive_entry_set_filetype(e.get(), AE_IFREG);
    archive_entry_set_size(e.get(), static_cast<la_int64_t>(m.bytes.size()));
    ASSERT_EQ(archive_write_header(a.get(), e.get()), ARCHIVE_OK);
    if (!m.bytes.empty()) archive_write_data(a.get(), m.bytes.data(), m.bytes.size());
  }
  archive_write_close(a.get());
}

// The member named `name`; fails the test (and returns a dummy) when there is none.
inline Member& member(std::vector<Member>& members, const std::string& name) {
  for (Member& m : members)
    if (m.name == name) return m;
  ADD_FAILURE() << "no member " << name;
  static Member none;
  return none;
}

}  // namespace robodiff::cache::testing_bundle
