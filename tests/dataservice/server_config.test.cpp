// crackvis-data's configuration file and its merged limits, without a
// server.
#include <catch2/catch.hpp>

#include <crackvis/dataservice_config/server_config.hpp>

namespace crackvis::testing {
namespace {

using namespace crackvis::dataservice;
using namespace crackvis::rpc;

TEST_CASE("The configuration file is read strictly", "[dataservice]") {
  auto config = parseServerConfig(R"({
    "listen": "0.0.0.0:7000", "data_root": "/srv/data",
    "tls": {"ca": "ca.pem", "cert": "s.pem", "key": "s.key"},
    "limits": {"max_read_bytes": 1000, "max_concurrent_streams": 3, "max_call_seconds": 2.5},
    "users": [{"name": "alice", "token_hash": "h", "folders": ["alice"]}],
    "access_log": "/var/log/crackvis-data.log", "raw_tls_listen": "127.0.0.1:7001"})",
                                  "test.json");
  INFO(config.status().message());
  REQUIRE(config.isOk());
  CHECK(config->listen == "0.0.0.0:7000");
  CHECK(config->tls.key == "s.key");
  CHECK(config->limits.maxReadBytes == 1000);
  CHECK(config->limits.maxConcurrentStreams == 3);
  CHECK(config->limits.maxCallSeconds == 2.5);
  CHECK(config->limits.maxFetchBytes == Limits{}.maxFetchBytes);
  REQUIRE(config->users.size() == 1);
  CHECK(config->users[0].folders == std::vector<std::string>{"alice"});
  CHECK(config->rawTlsListen == "127.0.0.1:7001");

  struct Bad {
    std::string json;
    std::string message;
  };
  for (const Bad& bad : std::vector<Bad>{
           {"{", "not valid JSON"},
           {R"({"limit": {}})", "unknown key 'limit'"},
           {R"({"limits": {"max_read_byte": 1}})", "unknown key 'max_read_byte'"},
           {R"({"listen": 7})", "'listen' has the wrong type"},
           {R"({"users": [{"name": "x"}]})", "needs token_hash, password_hash or certificate_name"},
           {R"({"users": [{"name": "a b", "token_hash": "h"}]})", "without spaces"},
           {R"({"users": [{"name": "a", "token_hash": "h"}, {"name": "a", "token_hash": "h"}]})",
            "appears twice"}}) {
    INFO(bad.json);
    auto parsed = parseServerConfig(bad.json, "test.json");
    CHECK(parsed.status().code() == StatusCode::kInvalidArgument);
    CHECK_THAT(parsed.status().message(),
               Catch::StartsWith("test.json") && Catch::Contains(bad.message));
  }
}

TEST_CASE("Limits are checked on the merged configuration", "[dataservice]") {
  // The file alone may hold a value a flag then replaces.
  auto parsed = parseServerConfig(
      R"({"data_root": "/srv", "limits": {"max_concurrent_streams": 0}})", "test.json");
  REQUIRE(parsed.isOk());
  const Status refused = validateServerConfig(*parsed);
  CHECK(refused.code() == StatusCode::kInvalidArgument);
  CHECK_THAT(refused.message(), Catch::StartsWith("--max-streams must be at least 1, got 0"));
  parsed->limits.maxConcurrentStreams = 4;  // as --max-streams 4 does
  CHECK(validateServerConfig(*parsed).isOk());
}

}  // namespace
}  // namespace crackvis::testing
