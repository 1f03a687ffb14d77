// Hashed secrets, the authenticator and the configuration file, without a
// server.
#include <catch2/catch.hpp>

#include <crackvis/dataservice_config/server_config.hpp>
#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::testing {
namespace {

using namespace crackvis::dataservice;
using namespace crackvis::rpc;

TEST_CASE("Passwords are stored as salted PBKDF2 hashes, random tokens as SHA-256",
          "[dataservice]") {
  auto hash = hashSecret("correct horse", 2000);
  REQUIRE(hash.isOk());
  CHECK_THAT(*hash, Catch::StartsWith("pbkdf2-sha256$2000$"));
  CHECK(hash->find("correct horse") == std::string::npos);
  CHECK(verifySecret("correct horse", *hash));
  CHECK_FALSE(verifySecret("correct horse ", *hash));
  CHECK_FALSE(verifySecret("", *hash));
  // Salted: the same secret hashes differently each time.
  CHECK(hashSecret("correct horse", 2000).value() != *hash);
  for (const std::string bad : {"", "pbkdf2-sha256$2000$abc", "md5$1$AAAA$AAAA",
                                "pbkdf2-sha256$10$AAAAAAAAAAAAAAAAAAAAAA==$AAAA"}) {
    INFO(bad);
    CHECK_FALSE(verifySecret("x", bad));
  }
  CHECK(hashSecret("", 2000).status().code() == StatusCode::kInvalidArgument);
  auto token = generateToken();
  REQUIRE(token.isOk());
  CHECK(token->size() == 43);
  CHECK(generateToken().value() != *token);
  // A token (32 random bytes) is stored as one SHA-256 of it, unsalted:
  // the same token, the same hash, and only that token matches.
  auto tokenHash = hashToken(*token);
  REQUIRE(tokenHash.isOk());
  CHECK_THAT(*tokenHash, Catch::StartsWith("sha256$"));
  CHECK(tokenHash->find(*token) == std::string::npos);
  CHECK(hashToken(*token).value() == *tokenHash);
  CHECK(verifySecret(*token, *tokenHash));
  CHECK_FALSE(verifySecret(token->substr(1), *tokenHash));
  CHECK_FALSE(verifySecret(*token, "sha256$AAAA"));
  CHECK(hashToken("").status().code() == StatusCode::kInvalidArgument);
}

TEST_CASE("The authenticator maps credentials to users and folders", "[dataservice]") {
  SECTION("without users every certified client reads everything") {
    Authenticator open({});
    auto caller = open.authenticate("", "crackvis-client");
    REQUIRE(caller.isOk());
    CHECK(caller->name == "crackvis-client");
    CHECK(caller->mayRead("any/file.h5"));
  }
  SECTION("with users") {
    Authenticator auth(
        {{"alice", hashSecret("t0ken", 2000).value(), "", "", {"alice"}},
         {"bob", "", hashSecret("pw", 2000).value(), "bob-laptop", {"bob", "shared"}}});
    auto alice = auth.authenticate("Bearer t0ken", "crackvis-client");
    REQUIRE(alice.isOk());
    CHECK(alice->name == "alice");
    CHECK(alice->mayRead("alice/run.h5"));
    CHECK_FALSE(alice->mayRead("bob/run.h5"));
    CHECK_FALSE(alice->mayRead("alice2/run.h5"));
    CHECK(auth.authenticate("Bearer t0ken", "").isOk());  // cached the second time
    // "bob:pw" in base64
    auto bob = auth.authenticate("Basic Ym9iOnB3", "");
    REQUIRE(bob.isOk());
    CHECK(bob->mayRead("shared/x.h5"));
    CHECK(auth.authenticate("", "bob-laptop").value().name == "bob");
    for (const std::string bad : {"Bearer wrong", "Basic Ym9iOnB4", "Basic !!!!", "Token x"}) {
      INFO(bad);
      CHECK(auth.authenticate(bad, "").status().code() == StatusCode::kUnauthenticated);
    }
    auto none = auth.authenticate("", "crackvis-client");
    CHECK(none.status().code() == StatusCode::kUnauthenticated);
    CHECK_THAT(none.status().message(), Catch::Contains("no credentials"));
  }
}

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
