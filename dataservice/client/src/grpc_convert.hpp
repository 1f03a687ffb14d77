// Conversions between the wire types and the client library's types
// (private to the client library).
#pragma once

#include <grpcpp/grpcpp.h>

#include "crackvis/v1/data.pb.h"
#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_protocol/types.hpp>
#include <crackvis/rpc/grpc_status.hpp>

namespace crackvis::dataservice {

// gRPC's codes that crackvis has no name for (CANCELLED, DEADLINE_EXCEEDED,
// UNKNOWN, ...) become UNAVAILABLE or INTERNAL with the gRPC name kept in
// the message (crackvis::rpc, shared with the render service).
using rpc::fromGrpcStatus;

FileDescription fromProto(const crackvis::v1::DescribeResponse& response);

}  // namespace crackvis::dataservice
