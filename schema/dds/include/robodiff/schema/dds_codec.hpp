#pragma once
// The DDS codec: the C++ messages of robodiff/schema/messages.hpp to and from the C types that
// idlc generates from robodiff.idl ("robodiff.h", robodiff_wire_*), which the build writes
// from messages.hpp's field lists: each field is paired with the C field of the same name.
//
// Ownership. toWire()/encode*() fill a C struct that must start zeroed, with memory from
// dds_alloc / dds_string_dup (sequences get _release = true); WireSample frees all of it with
// dds_sample_free(DDS_FREE_CONTENTS) in its destructor. fromWire()/decode*() only read the C
// struct and copy into the C++ message. The one exception is borrowDoubles(): a sequence that
// points into memory the caller owns, which must be detached (detachDoubles) before the
// sample is freed.

#include <dds/dds.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <variant>

#include "robodiff.h"  // idlc's C types of build/schema/robodiff.idl
#include "robodiff/schema/messages.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::dds_codec {

// ---- owning C samples ----------------------------------------------------------------

template <class T>
struct WireDescriptor;
template <>
struct WireDescriptor<robodiff_wire_Request> {
  static const dds_topic_descriptor_t* get() { return &robodiff_wire_Request_desc; }
};
template <>
struct WireDescriptor<robodiff_wire_Reply> {
  static const dds_topic_descriptor_t* get() { return &robodiff_wire_Reply_desc; }
};

// One zero-initialised C sample that owns everything it points to (see above). Not copyable
// or movable: the address is handed to dds_take / dds_write; hold it in a unique_ptr or
// shared_ptr to pass it around.
template <class T>
class WireSample {
 public:
  WireSample() { std::memset(static_cast<void*>(&sample_), 0, sizeof sample_); }
  ~WireSample() { dds_sample_free(&sample_, WireDescriptor<T>::get(), DDS_FREE_CONTENTS); }
  WireSample(const WireSample&) = delete;
  WireSample& operator=(const WireSample&) = delete;

  T& get() { return sample_; }
  const T& get() const { return sample_; }
  T* operator->() { return &sample_; }
  const T* operator->() const { return &sample_; }

 private:
  T sample_;
};
using WireRequest = WireSample<robodiff_wire_Request>;
using WireReply = WireSample<robodiff_wire_Reply>;

// ---- small pieces --------------------------------------------------------------------

// A dds_string_dup copy (never null: "" for an empty string).
char* dupString(std::string_view text);
// The C string as std::string; a null pointer reads as "".
std::string toString(const char* text);
// A sequence of `count` doubles from dds_alloc (uninitialised), owned by the sample.
void allocDoubles(dds_sequence_double& sequence, std::size_t count);
// A sequence pointing into the caller's memory (_release = false); detach it before the
// sample is freed.
void borrowDoubles(dds_sequence_double& sequence, std::span<const double> values);
void detachDoubles(dds_sequence_double& sequence);
inline std::span<const double> view(const dds_sequence_double& s) { return {s._buffer, s._buffer ? s._length : 0}; }
inline std::span<double> view(dds_sequence_double& s) { return {s._buffer, s._buffer ? s._length : 0}; }

// A status code read off the wire; a value this build does not know (a newer peer) is UNKNOWN.
StatusCode statusFromWire(robodiff_wire_StatusCode code);
// The method of a union discriminator; nullopt for a value this build does not know.
std::optional<rpc::Method> methodFromWire(robodiff_wire_Method method);

// ---- headers -------------------------------------------------------------------------

void toWire(const rpc::RequestHeader& header, robodiff_wire_RequestHeader& out);
rpc::RequestHeader fromWire(const robodiff_wire_RequestHeader& header);
void toWire(const rpc::ReplyHeader& header, robodiff_wire_ReplyHeader& out);
rpc::ReplyHeader fromWire(const robodiff_wire_ReplyHeader& header);

// ---- bodies: every message, both ways -------------------------------------------------

// Each message of ROBODIFF_RPC_MESSAGES (messages.hpp) to and from its idlc type
// (robodiff_wire_<Name>), field by field as its field list says; nested structs,
// sequences, strings and enums alike. Instantiated for those pairs only.
template <class Message, class Wire>
void toWire(const Message& in, Wire& out);
template <class Wire, class Message>
void fromWire(const Wire& in, Message& out);

// ---- envelopes -------------------------------------------------------------------------

// The union members, in Method order: the variant index is the method's number.
using RequestBody = std::variant<rpc::LoadModelRequest, rpc::GetFunctionRequest, rpc::EvaluateRequest,
                                 rpc::EvaluateBatchRequest, rpc::ListFunctionsRequest, rpc::HealthRequest,
                                 rpc::ReleaseRequest, rpc::SubmitJobRequest, rpc::JobStatusRequest,
                                 rpc::CancelJobRequest, rpc::JobResultRequest, rpc::QueryArtifactRequest,
                                 rpc::FetchArtifactChunkRequest, rpc::FleetStatusRequest>;
using ReplyBody = std::variant<rpc::LoadModelReply, rpc::GetFunctionReply, rpc::EvaluateReply,
                               rpc::EvaluateBatchReply, rpc::ListFunctionsReply, rpc::HealthReply,
                               rpc::ReleaseReply, rpc::SubmitJobReply, rpc::JobStatusReply, rpc::CancelJobReply,
                               rpc::JobResultReply, rpc::QueryArtifactReply, rpc::FetchArtifactChunkReply,
                               rpc::FleetStatusReply>;
static_assert(std::variant_size_v<RequestBody> == rpc::kMethodCount &&
              std::variant_size_v<ReplyBody> == rpc::kMethodCount, "one alternative per method, in Method order");

// Sets the discriminator and fills the union member (out must be zeroed).
void toWire(const RequestBody& body, robodiff_wire_RequestBody& out);
void toWire(const ReplyBody& body, robodiff_wire_ReplyBody& out);
// INVALID_ARGUMENT naming the value when the discriminator is not a method this build knows.
Status fromWire(const robodiff_wire_RequestBody& body, RequestBody& out);
Status fromWire(const robodiff_wire_ReplyBody& body, ReplyBody& out);

// The empty body of `method` (what a non-OK reply carries).
ReplyBody emptyReplyBody(rpc::Method method);

}  // namespace robodiff::dds_codec
