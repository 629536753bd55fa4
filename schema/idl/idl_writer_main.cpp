// robodiff_idl_writer FRAME OUTPUT: writes robodiff.idl for idlc at build time, the frame
// (schema/robodiff.idl.in) with the schema version and the wire structs written from
// status.hpp and messages.hpp's field lists (robodiff/schema/idl_writer.hpp). OUTPUT is
// left alone when it already has that text, so that idlc and what it feeds do not run
// again for nothing.
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "robodiff/schema/idl_writer.hpp"

namespace {

bool readWholeFile(const char* path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream buffer;
  buffer << in.rdbuf();
  text = buffer.str();
  return true;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "robodiff_idl_writer: %s\n", message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) return fail("usage: robodiff_idl_writer FRAME OUTPUT (FRAME: schema/robodiff.idl.in)");
  std::string frame;
  if (!readWholeFile(argv[1], frame)) return fail(std::string(argv[1]) + ": cannot be read");

  const robodiff::idl::FilledFrame filled = robodiff::idl::writeWireIdl(frame);
  if (!filled.error.empty()) return fail(filled.error);

  std::string previous;
  if (readWholeFile(argv[2], previous) && previous == filled.idl) return 0;
  std::ofstream out(argv[2], std::ios::binary | std::ios::trunc);
  out << filled.idl;
  out.close();
  if (!out) return fail(std::string(argv[2]) + ": cannot be written");
  return 0;
}
