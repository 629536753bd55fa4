#pragma once
// The compact encoding of the iceoryx bodies other than Evaluate's, derived from the
// messages' field lists (rpc::Fields): every field in order; u8 booleans, u32 enums and
// counts, u8 / u16 / u32 / u64 / f64 numbers in native byte order (shared memory never
// leaves the host), strings and sequences as a u32 count then the elements (a sequence of
// numbers as one block), nested structs inline.
// Reading checks every length against what remains and every enum against its range; the
// first failure sticks and names the field by its path ("outputs.row_offsets").

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::shm::compact {

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

// Appends values in native byte order.
class Writer {
 public:
  void raw(const void* data, std::size_t size) {
    const auto* p = static_cast<const std::byte*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  template <class T>
  void number(T v) { raw(&v, sizeof v); }
  std::vector<std::byte> take() { return std::move(bytes_); }

 private:
  std::vector<std::byte> bytes_;
};

// Reads what Writer wrote, never past the end.
class Reader {
 public:
  explicit Reader(std::span<const std::byte> body) : body_(body) {}

  template <class T>
  T number(const std::string& field) {
    T v{};
    if (!ok()) return v;
    if (sizeof v > remaining()) {
      fail(field + " is cut off (" + std::to_string(remaining()) + " bytes left, " + std::to_string(sizeof v) +
           " needed)");
      return v;
    }
    std::memcpy(&v, body_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  std::string text(const std::string& field, std::uint32_t size) {
    if (!ok()) return {};
    if (size > remaining()) {
      fail(field + " claims " + std::to_string(size) + " bytes but only " + std::to_string(remaining()) + " remain");
      return {};
    }
    std::string s(reinterpret_cast<const char*>(body_.data() + pos_), size);
    pos_ += size;
    return s;
  }
  // A count of elements each at least min_element_bytes long (guards the allocation).
  std::uint32_t count(const std::string& field, std::size_t min_element_bytes) {
    const auto n = number<std::uint32_t>(field);
    if (ok() && std::uint64_t{n} * min_element_bytes > remaining()) {
      fail(field + " claims " + std::to_string(n) + " elements but only " + std::to_string(remaining()) +
           " bytes remain");
      return 0;
    }
    return ok() ? n : 0;
  }
  // A sequence of numbers (no bools, no enums: their values need checking) copied at once;
  // byte for byte what a count and element-by-element number() reads would give.
  template <class T>
  void numbers(const std::string& field, std::vector<T>& out) {
    out.resize(count(field, sizeof(T)));
    if (out.empty()) return;
    std::memcpy(out.data(), body_.data() + pos_, out.size() * sizeof(T));
    pos_ += out.size() * sizeof(T);
  }
  // OK only when every byte was read.
  Status finish(const char* message) {
    if (ok() && pos_ != body_.size()) fail(std::to_string(body_.size() - pos_) + " unexpected trailing bytes");
    if (ok()) return {};
    return {StatusCode::InvalidArgument, std::string("malformed shared-memory chunk: ") + message + ": " + error_};
  }
  bool ok() const { return error_.empty(); }
  void fail(std::string error) {
    if (ok()) error_ = std::move(error);
  }

 private:
  std::size_t remaining() const { return body_.size() - pos_; }
  std::span<const std::byte> body_;
  std::size_t pos_ = 0;
  std::string error_;
};

// The fewest bytes a value of type T takes (bounds a claimed element count).
template <class T>
std::size_t minimumBytes() {
  if constexpr (std::is_same_v<T, bool>) return 1;
  else if constexpr (std::is_enum_v<T>) return 4;
  else if constexpr (std::is_arithmetic_v<T>) return sizeof(T);
  else if constexpr (std::is_same_v<T, std::string> || IsVector<T>::value) return 4;
  else {
    static const std::size_t bytes = [] {
      T sample{};
      std::size_t n = 0;
      rpc::Fields<T>::visit(sample, sample, [&](const char*, auto& f, auto&) {
        n += minimumBytes<std::remove_cvref_t<decltype(f)>>();
      });
      return n;
    }();
    return bytes;
  }
}

// Sequences whose elements are plain numbers travel as one block (bytes, doubles, counts):
// the same layout as element by element, without a call per element.
template <class T>
constexpr bool kNumberBlock = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;

template <class T>
void write(Writer& w, const T& v) {
  if constexpr (std::is_same_v<T, bool>) w.number<std::uint8_t>(v ? 1 : 0);
  else if constexpr (std::is_enum_v<T>) w.number(static_cast<std::uint32_t>(v));
  else if constexpr (std::is_arithmetic_v<T>) w.number(v);
  else if constexpr (std::is_same_v<T, std::string>) {
    w.number(static_cast<std::uint32_t>(v.size()));
    w.raw(v.data(), v.size());
  } else if constexpr (IsVector<T>::value) {
    w.number(static_cast<std::uint32_t>(v.size()));
    if constexpr (kNumberBlock<typename T::value_type>) w.raw(v.data(), v.size() * sizeof(typename T::value_type));
    else for (const auto& element : v) write(w, element);
  } else {
    rpc::Fields<T>::visit(v, v, [&](const char*, const auto& f, const auto&) { write(w, f); });
  }
}

inline std::string pathOf(const std::string& prefix, const char* name) {
  return prefix.empty() ? std::string(name) : prefix + "." + name;
}

template <class T>
void read(Reader& r, const std::string& field, T& v) {
  if constexpr (std::is_same_v<T, bool>) {
    const auto byte = r.number<std::uint8_t>(field);
    if (byte > 1) r.fail(field + " is not a boolean (" + std::to_string(byte) + ")");
    v = byte == 1;
  } else if constexpr (std::is_enum_v<T>) {
    const auto value = r.number<std::uint32_t>(field);
    if (r.ok() && value >= rpc::valueCount(T{})) r.fail(field + " has unknown value " + std::to_string(value));
    v = static_cast<T>(r.ok() ? value : 0);
  } else if constexpr (std::is_arithmetic_v<T>) {
    v = r.number<T>(field);
  } else if constexpr (std::is_same_v<T, std::string>) {
    v = r.text(field, r.number<std::uint32_t>(field));
  } else if constexpr (IsVector<T>::value) {
    if constexpr (kNumberBlock<typename T::value_type>) {
      r.numbers(field, v);
    } else {
      v.assign(r.count(field, minimumBytes<typename T::value_type>()), {});
      for (auto& element : v) read(r, field, element);
    }
  } else {
    rpc::Fields<T>::visit(v, v, [&](const char* name, auto& f, auto&) { read(r, pathOf(field, name), f); });
  }
}

}  // namespace robodiff::shm::compact
