#include <fmt/format.h>
#include <grpcpp/security/auth_context.h>

#include <crackvis/rpc/grpc_status.hpp>

namespace crackvis::rpc {

grpc::Status toGrpcStatus(const Status& status) {
  const auto code = [&] {
    switch (status.code()) {
      case StatusCode::kOk:
        return grpc::StatusCode::OK;
      case StatusCode::kInvalidArgument:
        return grpc::StatusCode::INVALID_ARGUMENT;
      case StatusCode::kNotFound:
        return grpc::StatusCode::NOT_FOUND;
      case StatusCode::kOutOfRange:
        return grpc::StatusCode::OUT_OF_RANGE;
      case StatusCode::kFailedPrecondition:
        return grpc::StatusCode::FAILED_PRECONDITION;
      case StatusCode::kPermissionDenied:
        return grpc::StatusCode::PERMISSION_DENIED;
      case StatusCode::kUnauthenticated:
        return grpc::StatusCode::UNAUTHENTICATED;
      case StatusCode::kResourceExhausted:
        return grpc::StatusCode::RESOURCE_EXHAUSTED;
      case StatusCode::kUnavailable:
        return grpc::StatusCode::UNAVAILABLE;
      case StatusCode::kInternal:
        return grpc::StatusCode::INTERNAL;
      case StatusCode::kCancelled:
        return grpc::StatusCode::CANCELLED;
      case StatusCode::kDeadlineExceeded:
        return grpc::StatusCode::DEADLINE_EXCEEDED;
    }
    return grpc::StatusCode::UNKNOWN;
  }();
  return code == grpc::StatusCode::OK ? grpc::Status::OK : grpc::Status(code, status.message());
}

const char* grpcCodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::UNKNOWN:
      return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    default:
      return "UNKNOWN";
  }
}

Status fromGrpcStatus(const grpc::Status& status, const std::string& call) {
  if (status.ok()) {
    return Status::ok();
  }
  const std::string& message = status.error_message();
  switch (status.error_code()) {
    case grpc::StatusCode::INVALID_ARGUMENT:
      return {StatusCode::kInvalidArgument, message};
    case grpc::StatusCode::OUT_OF_RANGE:
      return {StatusCode::kOutOfRange, message};
    case grpc::StatusCode::NOT_FOUND:
      return {StatusCode::kNotFound, message};
    case grpc::StatusCode::FAILED_PRECONDITION:
      return {StatusCode::kFailedPrecondition, message};
    case grpc::StatusCode::PERMISSION_DENIED:
      return {StatusCode::kPermissionDenied, message};
    case grpc::StatusCode::UNAUTHENTICATED:
      return {StatusCode::kUnauthenticated, message};
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return {StatusCode::kResourceExhausted, message};
    case grpc::StatusCode::CANCELLED:
      return cancelled(fmt::format("{}: CANCELLED: {}", call, message));
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return deadlineExceeded(fmt::format("{}: DEADLINE_EXCEEDED: {}", call, message));
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::ABORTED:
      return {StatusCode::kUnavailable,
              fmt::format("{}: {}: {}", call, grpcCodeName(status.error_code()), message)};
    default:
      return {StatusCode::kInternal,
              fmt::format("{}: {}: {}", call, grpcCodeName(status.error_code()), message)};
  }
}

std::string certificateName(const grpc::ServerContextBase& context) {
  auto auth = context.auth_context();
  if (!auth) {
    return {};
  }
  auto names = auth->FindPropertyValues(GRPC_X509_CN_PROPERTY_NAME);
  return names.empty() ? std::string() : std::string(names.front().data(), names.front().size());
}

std::string metadataValue(const grpc::ServerContextBase& context, const char* key) {
  const auto& metadata = context.client_metadata();
  auto it = metadata.find(key);
  return it == metadata.end() ? std::string() : std::string(it->second.data(), it->second.size());
}

}  // namespace crackvis::rpc
