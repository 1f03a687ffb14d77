// The one HOST:PORT parser and the loopback rule (proto's host_port.hpp).
#include <catch2/catch.hpp>

#include <crackvis/rpc/host_port.hpp>

namespace crackvis::testing {
namespace {

using namespace crackvis::rpc;

TEST_CASE("Listen addresses and loopback", "[dataservice]") {
  CHECK(parseHostPort("127.0.0.1:0").value().port == 0);
  CHECK(parseHostPort("[::1]:50051").value().host == "::1");
  CHECK(parseHostPort("localhost:65535").value().port == 65535);
  for (const std::string bad : {"localhost", ":80", "a:65536", "a:-1", "[::1]50051", "a:"}) {
    INFO(bad);
    CHECK(parseHostPort(bad).status().code() == StatusCode::kInvalidArgument);
  }
  CHECK(isLoopbackHost("127.0.0.1"));
  CHECK(isLoopbackHost("127.1.2.3"));
  CHECK(isLoopbackHost("::1"));
  CHECK(isLoopbackHost("localhost"));
  CHECK_FALSE(isLoopbackHost("0.0.0.0"));
  CHECK_FALSE(isLoopbackHost("::"));
  CHECK_FALSE(isLoopbackHost("128.0.0.1"));
  CHECK_FALSE(isLoopbackHost("127.0.0.1.example.com"));
}

}  // namespace
}  // namespace crackvis::testing
