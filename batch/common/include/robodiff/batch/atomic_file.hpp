#pragma once
// A file written all or nothing: the bytes go to a temporary file in the target's
// directory (".NAME.tmp-XXXXXX"), and commit() flushes, fsyncs and renames it over the
// target (then fsyncs the directory). Destroyed without commit() (an error, a
// cancellation), the temporary file is removed and the target is untouched.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace robodiff::batch {

// A file that could not be created, written or put in place; the message names it.
class AtomicFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);  // throws AtomicFileError naming the directory
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Buffered; throws AtomicFileError naming the target on a failed write (disk full).
  void write(std::string_view bytes);
  void commit();

 private:
  void flush();
  std::filesystem::path target_, temp_;
  int fd_ = -1;
  std::string buffer_;
  bool committed_ = false;
};

}  // namespace robodiff::batch
