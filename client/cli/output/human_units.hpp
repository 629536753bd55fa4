// The human-readable quantities the commands print and read: sizes ("1.5 GiB", parsed
// from "500M", "2G", "1.5GiB", plain bytes), ages ("3 min"), clock times ("0:42") and
// plain numbers ("0.125", "1,234,567").
#pragma once

#include <cstdint>
#include <string>

namespace robodiff::cli {

// "0 B", "812 B", "412.3 KiB", "1.5 GiB" (powers of 1024).
std::string formatBytes(std::uint64_t bytes);
// A size: plain bytes ("1048576"), or a number with a unit: K, M, G, T and KiB, MiB, GiB,
// TiB are powers of 1024; KB, MB, GB, TB powers of 1000; B bytes; any case. Throws
// std::invalid_argument naming the text when it is not a size.
std::uint64_t parseSize(const std::string& text);
// A duration for people, coarse: "12 s", "3 min", "2 h", "5 d".
std::string formatAge(std::int64_t seconds);
// A duration as a clock: "0:42", "12:05", "1:02:03".
std::string formatClock(double seconds);
// x with `digits` digits after the point: "0.125".
std::string formatFixed(double x, int digits);
// x rounded to a whole number with thousands separated: "1,234,567" (for counts people compare).
std::string formatGrouped(double x);

}  // namespace robodiff::cli
