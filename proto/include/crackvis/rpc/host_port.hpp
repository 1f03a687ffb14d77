// Network addresses as users write them: "host:port", "[v6]:port". One
// parser for the servers' listen addresses and the clients' targets.
#pragma once

#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::rpc {

struct HostPort {
  std::string host;  // without the brackets of an IPv6 address
  int port = 0;
};

// Splits "host:port" ("[::1]:50051" for IPv6); the port must be 0..65535.
// INVALID_ARGUMENT "address 'A': ..." otherwise.
Result<HostPort> parseHostPort(const std::string& address);
// 127.0.0.0/8, ::1 and "localhost".
bool isLoopbackHost(const std::string& host);

}  // namespace crackvis::rpc
