#pragma once
// A message's fields, listed once beside its struct (messages.hpp):
//
//   ROBODIFF_FIELDS(LoadModelRequest, urdf, floating_base, options_json);
//
// defines rpc::Fields<LoadModelRequest>: its name, and visit(a, b, field), which calls
// field("urdf", a.urdf, b.urdf), ... in the listed order. a and b are two objects with the
// same field names: the message twice (encoding, comparing, filling) or the message and
// its idlc C type (the DDS codec). The iceoryx codec, the DDS codec and the codecs' tests
// are all derived from these lists (docs/transports.md, "One description per message").

// ROBODIFF_FOR_EACH(m, x, y, z) expands to m(x) m(y) m(z): each rescan level below expands
// one more element, 4^4 = 256 levels in all (the longest message has 23 fields).
#define ROBODIFF_PARENS ()
#define ROBODIFF_EXPAND(...) ROBODIFF_EXPAND3(ROBODIFF_EXPAND3(ROBODIFF_EXPAND3(ROBODIFF_EXPAND3(__VA_ARGS__))))
#define ROBODIFF_EXPAND3(...) ROBODIFF_EXPAND2(ROBODIFF_EXPAND2(ROBODIFF_EXPAND2(ROBODIFF_EXPAND2(__VA_ARGS__))))
#define ROBODIFF_EXPAND2(...) ROBODIFF_EXPAND1(ROBODIFF_EXPAND1(ROBODIFF_EXPAND1(ROBODIFF_EXPAND1(__VA_ARGS__))))
#define ROBODIFF_EXPAND1(...) __VA_ARGS__
#define ROBODIFF_FOR_EACH(macro, ...) __VA_OPT__(ROBODIFF_EXPAND(ROBODIFF_FOR_EACH_STEP(macro, __VA_ARGS__)))
#define ROBODIFF_FOR_EACH_STEP(macro, first, ...) \
  macro(first) __VA_OPT__(ROBODIFF_FOR_EACH_AGAIN ROBODIFF_PARENS(macro, __VA_ARGS__))
#define ROBODIFF_FOR_EACH_AGAIN() ROBODIFF_FOR_EACH_STEP

#define ROBODIFF_VISIT_FIELD(name) field(#name, a.name, b.name);

// Used inside namespace robodiff::rpc, after the struct.
#define ROBODIFF_FIELDS(Message, ...)                                 \
  template <>                                                         \
  struct Fields<Message> {                                            \
    static constexpr const char* kName = #Message;                    \
    template <class A, class B, class Field>                          \
    static void visit(A& a, B& b, Field&& field) {                    \
      ROBODIFF_FOR_EACH(ROBODIFF_VISIT_FIELD, __VA_ARGS__)            \
    }                                                                 \
  }

namespace robodiff::rpc {

template <class Message>
struct Fields;  // specialised by ROBODIFF_FIELDS for every wire struct

template <class T>
concept HasFields = requires { Fields<T>::kName; };

}  // namespace robodiff::rpc
