// What the DataService's unary handlers (data_service.cpp) and its stream
// reactors (stream_reactors.cpp) share: the program's name in log lines and
// the parsing of a raw request. Private to the service library.
#pragma once

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include <crackvis/common/status.hpp>

namespace crackvis::dataservice {

inline constexpr const char* kProgram = "crackvis-data";

template <typename Request>
Status parseRequest(const grpc::ByteBuffer* buffer, Request& request) {
  grpc::Slice joined;
  if (!buffer->TrySingleSlice(&joined).ok() && !buffer->DumpToSingleSlice(&joined).ok()) {
    return invalidArgument("unreadable request");
  }
  if (!request.ParseFromArray(joined.begin(), static_cast<int>(joined.size()))) {
    return invalidArgument(fmt::format("malformed {}", request.GetTypeName()));
  }
  return Status::ok();
}

}  // namespace crackvis::dataservice
