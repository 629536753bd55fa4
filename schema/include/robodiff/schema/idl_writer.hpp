#pragma once
// The wire structs in IDL, written from their field lists (field_list.hpp), so that
// messages.hpp is their one description: the build runs robodiff_idl_writer
// (schema/idl/idl_writer_main.cpp), which puts the schema version (status.hpp) and the
// structs written here into the hand-written rest of the IDL (schema/robodiff.idl.in: the
// module, the enums, the unions and the envelopes) and hands the result to idlc
// (docs/transports.md, "One description per message").
//
// Each struct comes after the structs it contains. A field whose C++ type has no IDL type
// below is reported by name (IdlWriter::errors), and the build stops there.

#include <concepts>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::idl {

// IdlType<T>::name(): the IDL type of a field of C++ type T; no name() for a type the wire
// does not carry.
template <class T>
struct IdlType {};

template <class T>
concept Mappable = requires {
  { IdlType<T>::name() } -> std::convertible_to<std::string>;
};

#define ROBODIFF_IDL_TYPE(Cpp, Idl) \
  template <>                       \
  struct IdlType<Cpp> {             \
    static std::string name() { return Idl; } \
  }
ROBODIFF_IDL_TYPE(std::string, "string");
ROBODIFF_IDL_TYPE(bool, "boolean");
ROBODIFF_IDL_TYPE(double, "double");
ROBODIFF_IDL_TYPE(float, "float");
ROBODIFF_IDL_TYPE(std::uint8_t, "octet");  // bytes: sequence<octet> (idlc: dds_sequence_octet)
ROBODIFF_IDL_TYPE(std::uint16_t, "unsigned short");
ROBODIFF_IDL_TYPE(std::uint32_t, "unsigned long");
ROBODIFF_IDL_TYPE(std::uint64_t, "unsigned long long");
ROBODIFF_IDL_TYPE(std::int32_t, "long");
ROBODIFF_IDL_TYPE(std::int64_t, "long long");
#undef ROBODIFF_IDL_TYPE

// An enum by the name rpc::idlName gives it (messages.hpp, beside valueCount).
template <class T>
  requires std::is_enum_v<T> && requires(T value) {
    { rpc::idlName(value) } -> std::convertible_to<std::string_view>;
  }
struct IdlType<T> {
  static std::string name() { return rpc::idlName(T{}); }
};

// A struct with a field list, by its name.
template <rpc::HasFields T>
struct IdlType<T> {
  static std::string name() { return rpc::Fields<T>::kName; }
};

template <Mappable T>
struct IdlType<std::vector<T>> {
  static std::string name() { return "sequence<" + IdlType<T>::name() + ">"; }
};

template <class T>
struct IsSequence : std::false_type {};
template <class T>
struct IsSequence<std::vector<T>> : std::true_type {};

// Writes structs (and, first, the structs they contain) once each, in the IDL's syntax.
class IdlWriter {
 public:
  template <rpc::HasFields T>
  void add() {
    if (!written_.insert(rpc::Fields<T>::kName).second) return;  // also ends a cycle
    T sample{};
    rpc::Fields<T>::visit(sample, sample, [&](const char*, auto& field, auto&) {
      addContained<std::remove_cvref_t<decltype(field)>>();
    });
    text_ += std::string("  @final struct ") + rpc::Fields<T>::kName + " {\n";
    rpc::Fields<T>::visit(sample, sample, [&](const char* name, auto& field, auto&) {
      writeField<std::remove_cvref_t<decltype(field)>>(rpc::Fields<T>::kName, name);
    });
    text_ += "  };\n\n";
    order_.emplace_back(rpc::Fields<T>::kName);
  }

  const std::string& text() const { return text_; }
  const std::vector<std::string>& order() const { return order_; }  // struct names, as written
  // "Message.field: ..." for each field with no IDL type; the text is unusable unless empty.
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  template <class F>
  void addContained() {
    if constexpr (rpc::HasFields<F>) {
      add<F>();
    } else if constexpr (IsSequence<F>::value) {
      addContained<typename F::value_type>();
    }
  }

  template <class F>
  void writeField(const char* message, const char* field) {
    if constexpr (Mappable<F>) {
      text_ += "    " + IdlType<F>::name() + " " + field + ";\n";
    } else {
      errors_.push_back(std::string(message) + "." + field +
                        ": its C++ type has no IDL type (map it in robodiff/schema/idl_writer.hpp, IdlType; "
                        "an enum needs an rpc::idlName overload in messages.hpp)");
    }
  }

  std::set<std::string> written_;
  std::vector<std::string> order_;
  std::vector<std::string> errors_;
  std::string text_;
};

// Every struct the wire carries: the envelopes' headers (robodiff.idl.in's Request and Reply
// hold them), then each request and reply of ROBODIFF_RPC_MESSAGES.
inline IdlWriter writeWireStructs() {
  IdlWriter writer;
  writer.add<rpc::RequestHeader>();
  writer.add<rpc::ReplyHeader>();
#define ROBODIFF_IDL_ADD(Message) writer.add<rpc::Message>();
  ROBODIFF_RPC_MESSAGES(ROBODIFF_IDL_ADD)
#undef ROBODIFF_IDL_ADD
  return writer;
}

// The line of robodiff.idl.in that the version constants and the structs replace.
inline constexpr std::string_view kStructsMarker = "// @WIRE_VERSION_AND_STRUCTS@";

struct FilledFrame {
  std::string idl;    // the whole IDL, when error is empty
  std::string error;  // what is wrong with the frame
};

// The frame with its one marker line replaced by `written` (and a note saying where it
// comes from). An error when the marker is missing or there twice.
inline FilledFrame fillFrame(std::string_view frame, std::string_view written) {
  std::vector<std::size_t> markers;
  std::size_t line_start = 0;
  while (line_start < frame.size()) {
    std::size_t line_end = frame.find('\n', line_start);
    if (line_end == std::string_view::npos) line_end = frame.size();
    std::string_view line = frame.substr(line_start, line_end - line_start);
    const std::size_t first = line.find_first_not_of(" \t");
    if (first != std::string_view::npos && line.substr(first) == kStructsMarker) markers.push_back(line_start);
    line_start = line_end + 1;
  }
  if (markers.size() != 1) {
    return {"", "the frame (robodiff.idl.in) must have exactly one line \"" + std::string(kStructsMarker) +
                    "\" (where the version and the structs go); it has " + std::to_string(markers.size())};
  }
  std::size_t after = frame.find('\n', markers[0]);
  after = after == std::string_view::npos ? frame.size() : after + 1;
  std::string idl =
      "// Generated at build time by robodiff_idl_writer from schema/robodiff.idl.in, status.hpp\n"
      "// and the field lists of schema/include/robodiff/schema/messages.hpp: edit those, not this.\n";
  idl += frame.substr(0, markers[0]);
  idl += "  // Written by robodiff_idl_writer from status.hpp (the version) and the field lists of\n"
         "  // messages.hpp (the structs; what each field means is said there).\n\n";
  idl += written;
  idl += frame.substr(after);
  return {idl, ""};
}

// The schema version as IDL constants (robodiff_wire_SCHEMA_VERSION_MAJOR / MINOR in C).
inline std::string schemaVersionConstants() {
  return "  // Bump MINOR for additions a server can ignore or answer (a new method, a new enum\n"
         "  // value at the end); bump MAJOR for anything else (status.hpp).\n"
         "  const unsigned short SCHEMA_VERSION_MAJOR = " + std::to_string(kSchemaVersionMajor) + ";\n"
         "  const unsigned short SCHEMA_VERSION_MINOR = " + std::to_string(kSchemaVersionMinor) + ";\n\n";
}

// The whole robodiff.idl: the frame with the version and every wire struct at its marker;
// an error naming each field with no IDL type, or what is wrong with the frame.
inline FilledFrame writeWireIdl(std::string_view frame) {
  const IdlWriter structs = writeWireStructs();
  if (!structs.errors().empty()) {
    std::string error = "messages.hpp: " + structs.errors().front();
    for (std::size_t i = 1; i < structs.errors().size(); ++i) error += "; " + structs.errors()[i];
    return {"", error};
  }
  return fillFrame(frame, schemaVersionConstants() + structs.text());
}

}  // namespace robodiff::idl
