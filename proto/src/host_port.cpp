#include <cstdio>

#include <fmt/format.h>

#include <crackvis/rpc/host_port.hpp>

namespace crackvis::rpc {

Result<HostPort> parseHostPort(const std::string& address) {
  HostPort result;
  std::string portText;
  if (!address.empty() && address.front() == '[') {
    const size_t close = address.find(']');
    if (close == std::string::npos || close + 1 >= address.size() || address[close + 1] != ':') {
      return invalidArgument(fmt::format("address '{}': expected [host]:port", address));
    }
    result.host = address.substr(1, close - 1);
    portText = address.substr(close + 2);
  } else {
    const size_t colon = address.rfind(':');
    if (colon == std::string::npos || colon == 0) {
      return invalidArgument(fmt::format("address '{}': expected host:port", address));
    }
    result.host = address.substr(0, colon);
    portText = address.substr(colon + 1);
  }
  if (portText.empty() || portText.size() > 5 ||
      portText.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(portText) > 65535) {
    return invalidArgument(fmt::format("address '{}': port must be 0..65535", address));
  }
  result.port = std::stoi(portText);
  return result;
}

bool isLoopbackHost(const std::string& host) {
  if (host == "localhost" || host == "::1") {
    return true;
  }
  // 127.0.0.0/8, written as four decimal parts.
  unsigned a = 0, b = 0, c = 0, d = 0;
  char tail = 0;
  return std::sscanf(host.c_str(), "%u.%u.%u.%u%c", &a, &b, &c, &d, &tail) == 4 && a == 127 &&
         b < 256 && c < 256 && d < 256;
}

}  // namespace crackvis::rpc
