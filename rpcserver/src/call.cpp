#include <cstdio>

#include <fmt/format.h>

#include <crackvis/common/log.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc_server/call.hpp>

namespace crackvis::rpc {

Result<Caller> authenticateCall(const Authenticator& authenticator,
                                const grpc::ServerContextBase& context, AccessRecord& record) {
  record.peer = context.peer();
  record.certificateName = certificateName(context);
  auto caller = authenticator.authenticate(metadataValue(context, "authorization"),
                                           record.certificateName, record.peer);
  if (caller) {
    record.user = caller->name;
  }
  return caller;
}

void recordCall(AccessLog& log, AccessRecord& record, CallClock::time_point start,
                const Status& status) {
  record.seconds = std::chrono::duration<double>(CallClock::now() - start).count();
  record.status = std::string(toString(status.code()));
  record.detail = status.isOk() ? std::string() : status.message();
  log.record(record);
}

grpc::Status finishCall(AccessLog& log, AccessRecord& record, CallClock::time_point start,
                        const Status& status) {
  recordCall(log, record, start, status);
  return toGrpcStatus(status);
}

std::string logHandlerException(std::string_view program, const AccessRecord& record,
                                std::string_view what) {
  log::event(
      stderr, program, "handler_exception",
      {{"method", record.method}, {"file", echoed(record.file)}, {"what", std::string(what)}});
  return fmt::format("{}: internal error in {} (logged by the server)", record.method, program);
}

}  // namespace crackvis::rpc
