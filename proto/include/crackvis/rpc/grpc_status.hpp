// The one mapping between crackvis Status codes and gRPC status codes, and
// what a server handler needs to know about its caller, shared by the data
// service, the render service and their clients.
#pragma once

#include <string>

#include <grpcpp/grpcpp.h>

#include <crackvis/common/status.hpp>

namespace crackvis::rpc {

grpc::Status toGrpcStatus(const Status& status);
// `call` names the call in messages about transport failures
// ("Describe: UNAVAILABLE: failed to connect"). A client that knows which
// server it meant uses connection_advice.hpp's overload, which says what
// to do when the server cannot be reached.
Status fromGrpcStatus(const grpc::Status& status, const std::string& call);
const char* grpcCodeName(grpc::StatusCode code);

// The common name of the client certificate; empty without one.
std::string certificateName(const grpc::ServerContextBase& context);
// The first value of a metadata key ("authorization"); empty if absent.
std::string metadataValue(const grpc::ServerContextBase& context, const char* key);

}  // namespace crackvis::rpc
