// Hashed secrets, the authenticator and per-user folders (rpcserver/),
// without a server.
#include <catch2/catch.hpp>

#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::testing {
namespace {

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

TEST_CASE("Folder access matches whole path parts", "[dataservice]") {
  using rpc::isWithinFolder;
  CHECK(isWithinFolder("alice/a.h5", "alice"));
  CHECK(isWithinFolder("alice/x/a.h5", "alice/"));
  CHECK(isWithinFolder("alice", "alice"));
  CHECK_FALSE(isWithinFolder("alice2/a.h5", "alice"));
  CHECK_FALSE(isWithinFolder("bob/a.h5", "alice"));
  CHECK(isWithinFolder("anything/at/all.h5", "*"));
  CHECK(isWithinFolder("anything.h5", ""));
}

}  // namespace
}  // namespace crackvis::testing
