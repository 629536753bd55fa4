// Quoting what a client sent (names, ids, spec text) in messages and logs without
// echoing all of it: a 10 MB frame name must not become a 10 MB error or log line.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace robodiff::language {

// How much of a client-sent string a message quotes.
inline constexpr std::size_t kQuotedPrefixBytes = 120;

// `text` itself when at most max_bytes long, else its first max_bytes (never cutting a
// UTF-8 character) followed by "… (<size> bytes)".
std::string boundedText(std::string_view text, std::size_t max_bytes = kQuotedPrefixBytes);

// boundedText in single quotes: 'panda_hand'.
std::string quote(std::string_view text, std::size_t max_bytes = kQuotedPrefixBytes);

}  // namespace robodiff::language
