// The URDF text must be well-formed UTF-8 without NUL bytes before any XML parser sees
// it: TinyXML (Debian's 2.6.2, used by the validator and by urdfdom) skips a multi-byte
// sequence by its lead byte's length, so a sequence cut short at the end of the text
// makes it read past the terminating NUL (found by tests/fuzz/urdf_fuzz.cpp).
#pragma once

#include <string>

namespace robodiff::detail {

// Throws ModelError naming the source, the line, the byte offset and the byte value of
// the first byte that is not part of a valid UTF-8 sequence (RFC 3629: no overlong
// forms, no surrogates, nothing past U+10FFFF), or of the first NUL byte.
void checkUtf8(const std::string& text, const std::string& source);

}  // namespace robodiff::detail
