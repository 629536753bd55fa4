#pragma once
// Random wire messages and a field-by-field comparison, both walked through the messages'
// field lists (rpc::Fields), so that the codecs' tests cover every field of every message
// by construction: a field added to a message is filled, encoded and compared with no
// change to the tests.

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::testing {

template <class T>
struct IsMessageVector : std::false_type {};
template <class T>
struct IsMessageVector<std::vector<T>> : std::true_type {};

// Calls f(Message{}) once for each message of ROBODIFF_RPC_MESSAGES.
template <class F>
void forEachMessage(F&& f) {
#define ROBODIFF_EACH_MESSAGE(Message) f(rpc::Message{});
  ROBODIFF_RPC_MESSAGES(ROBODIFF_EACH_MESSAGE)
#undef ROBODIFF_EACH_MESSAGE
}

// Every field random: enums in range, strings of 0..12 printable or UTF-8 bytes (no NUL:
// DDS strings are C strings), sequences of 0..3 elements, doubles finite and signed.
template <class T>
void fillRandom(T& v, std::mt19937_64& rng) {
  if constexpr (std::is_same_v<T, bool>) {
    v = rng() % 2 == 1;
  } else if constexpr (std::is_enum_v<T>) {
    v = static_cast<T>(rng() % rpc::valueCount(T{}));
  } else if constexpr (std::is_floating_point_v<T>) {
    v = std::uniform_real_distribution<T>(-1e6, 1e6)(rng);
  } else if constexpr (std::is_arithmetic_v<T>) {
    v = static_cast<T>(rng());
  } else if constexpr (std::is_same_v<T, std::string>) {
    static const std::string alphabet = "abcXYZ019_-/.:{}\"' \xc3\xa4\xe2\x82\xac";
    v.resize(rng() % 13);
    for (char& c : v) c = alphabet[rng() % alphabet.size()];
  } else if constexpr (IsMessageVector<T>::value) {
    v.resize(rng() % 4);
    for (auto& element : v) fillRandom(element, rng);
  } else {
    rpc::Fields<T>::visit(v, v, [&](const char*, auto& f, auto&) { fillRandom(f, rng); });
  }
}

// "" when a and b agree in every field (doubles bit for bit); else the first field that
// differs, by its path ("outputs[1].row_offsets[0]").
template <class T>
std::string firstDifference(const T& a, const T& b, const std::string& path = "") {
  if constexpr (std::is_floating_point_v<T>) {
    return std::memcmp(&a, &b, sizeof a) == 0 ? "" : path;
  } else if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T> || std::is_same_v<T, std::string>) {
    return a == b ? "" : path;
  } else if constexpr (IsMessageVector<T>::value) {
    if (a.size() != b.size()) return path + " (size " + std::to_string(a.size()) + " vs " + std::to_string(b.size()) + ")";
    for (std::size_t i = 0; i < a.size(); ++i)
      if (auto d = firstDifference(a[i], b[i], path + "[" + std::to_string(i) + "]"); !d.empty()) return d;
    return "";
  } else {
    std::string difference;
    rpc::Fields<T>::visit(a, b, [&](const char* name, const auto& x, const auto& y) {
      if (difference.empty()) difference = firstDifference(x, y, path.empty() ? name : path + "." + name);
    });
    return difference;
  }
}

// The names of T's fields, in order.
template <class T>
std::vector<std::string> fieldNames() {
  T sample{};
  std::vector<std::string> names;
  rpc::Fields<T>::visit(sample, sample, [&](const char* name, auto&, auto&) { names.emplace_back(name); });
  return names;
}

// Calls check(message, sample) for `samples` random messages of each kind (seeded: the
// same messages every run); returns how many kinds there were.
template <class Check>
int forEachRandomMessage(std::uint64_t seed, int samples, Check&& check) {
  std::mt19937_64 rng(seed);
  int kinds = 0;
  forEachMessage([&](auto empty) {
    ++kinds;
    for (int sample = 0; sample < samples; ++sample) {
      decltype(empty) message;
      fillRandom(message, rng);
      check(message, sample);
    }
  });
  return kinds;
}

}  // namespace robodiff::testing
