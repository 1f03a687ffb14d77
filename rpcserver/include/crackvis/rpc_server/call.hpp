// The boundary of every RPC handler of both services: the caller's identity
// from the call, and the end of a call (its access-log line, then its gRPC
// status). guarded() is where an exception from a handler's body stops (the
// boundary of crackvis/common/exception_boundary.hpp): it is logged as an
// event line and fails only that call, with INTERNAL, so a bug hit by one
// input never takes the process down.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include <grpcpp/grpcpp.h>

#include <crackvis/common/exception_boundary.hpp>
#include <crackvis/common/status.hpp>
#include <crackvis/rpc_server/access_log.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::rpc {

using CallClock = std::chrono::steady_clock;

// Authenticates the call; fills the record's peer, certificate and user.
Result<Caller> authenticateCall(const Authenticator& authenticator,
                                const grpc::ServerContextBase& context, AccessRecord& record);

// Fills the record's time and status and writes its line (before the client
// sees the status, so a client's calls appear in the order it made them):
// the end of a call through any front door (gRPC, the web page's).
void recordCall(AccessLog& log, AccessRecord& record, CallClock::time_point start,
                const Status& status);
// recordCall, then the status for gRPC.
grpc::Status finishCall(AccessLog& log, AccessRecord& record, CallClock::time_point start,
                        const Status& status);

// Writes the event line for an exception that reached a handler's boundary
// (program, method, file, exception) and returns the message its client gets,
// which names the method and leaves the exception to the server's log.
std::string logHandlerException(std::string_view program, const AccessRecord& record,
                                std::string_view what);

// Runs a handler's body; an exception becomes INTERNAL with
// logHandlerException's message.
template <typename Body>
Status guarded(std::string_view program, const AccessRecord& record, Body&& body) noexcept {
  return guardedCall(
      body, [&](std::string_view what) { return logHandlerException(program, record, what); });
}

}  // namespace crackvis::rpc
