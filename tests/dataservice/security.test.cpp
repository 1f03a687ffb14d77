// Mutual TLS and the per-user layer, with real certificates from
// certs/make-dev-certs.sh: clients without the right certificate never get
// an answer, users see only their folders, and every call leaves an access
// log line. After each refusal the server still serves a good client.
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <grpcpp/grpcpp.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "service_fixture.hpp"
#include "support/process.hpp"
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::testing {
namespace {

using dataservice::Hyperslab;

TEST_CASE("Clients without a certificate the server trusts are refused",
          "[dataservice][integration]") {
  auto server = startServer(baseConfig());
  struct Refused {
    std::string name;
    dataservice::ClientOptions options;
  };
  auto options = [&](const std::string& certificate, const std::string& ca = "ca") {
    auto result = clientOptions(*server);
    result.tls = clientTls(certificate, ca);
    result.timeoutSeconds = 5.0;
    return result;
  };
  auto insecure = clientOptions(*server);
  insecure.insecure = true;
  insecure.timeoutSeconds = 5.0;
  // A client that trusts another CA does not accept the server either.
  auto wrongTrust = options("client", "other-ca");
  std::vector<Refused> refused = {
      {"no client certificate (plaintext)", insecure},
      {"a certificate signed by another CA", options("other-client", "ca")},
      {"an expired certificate", options("expired-client")},
      {"a client that does not trust the server's CA", wrongTrust},
  };
  for (const Refused& client : refused) {
    DYNAMIC_SECTION(client.name) {
      auto connection = connect(client.options);
      const Status status = connection.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).status();
      INFO(status.message());
      CHECK(status.code() == StatusCode::kUnavailable);
      CHECK(connection.checkHealth().code() == StatusCode::kUnavailable);
      requireServerHealthy(*server);
    }
  }

  SECTION("a TLS client that offers no certificate of its own") {
    // The client library insists on a certificate for mutual TLS...
    auto noCert = options("client");
    noCert.tls.cert = "";
    noCert.tls.key = "";
    auto made = dataservice::DataClient::connect(noCert);
    CHECK(made.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(made.status().message(), Catch::Contains("no certificate file given"));
    // ...so a raw gRPC channel that trusts the server but has no certificate.
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = tls::loadTlsMaterial(clientTls()).value().caPem;
    auto channel = grpc::CreateChannel(server->address(), grpc::SslCredentials(ssl));
    auto health = grpc::health::v1::Health::NewStub(channel);
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    grpc::health::v1::HealthCheckResponse response;
    const grpc::Status status = health->Check(&context, {}, &response);
    INFO(status.error_message());
    CHECK(status.error_code() == grpc::StatusCode::UNAVAILABLE);
    requireServerHealthy(*server);
  }

  SECTION("the render server's own certificate is accepted") {
    auto render = connect(clientOptions(*server, "crackvis-render"));
    CHECK(render.checkHealth().isOk());
    CHECK(render.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
  }
}

TEST_CASE("A missing or mismatched certificate stops the server from starting, without abort",
          "[dataservice][integration]") {
  auto config = baseConfig();
  SECTION("missing file") {
    config.tls.cert = (certificateDir() / "absent.pem").string();
    auto server = dataservice::DataServer::start(config);
    CHECK(server.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(server.status().message(),
               Catch::Contains("absent.pem") && Catch::Contains("No such file"));
  }
  SECTION("key of another certificate") {
    config.tls.key = clientTls().key;
    auto server = dataservice::DataServer::start(config);
    CHECK(server.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(server.status().message(), Catch::Contains("does not belong to certificate"));
  }
  SECTION("not a certificate") {
    config.tls.ca = sampleRoot().file("notes.txt");
    auto server = dataservice::DataServer::start(config);
    CHECK(server.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(server.status().message(),
               Catch::Contains("notes.txt") && Catch::Contains("not a PEM certificate"));
  }
}

TEST_CASE("Insecure mode binds loopback only", "[dataservice][integration]") {
  auto config = baseConfig();
  config.insecure = true;
  config.tls = {};
  SECTION("any address but loopback is refused") {
    for (const std::string listen : {"0.0.0.0:0", "[::]:0", "192.0.2.1:0"}) {
      config.listen = listen;
      auto server = dataservice::DataServer::start(config);
      INFO(listen);
      CHECK(server.status().code() == StatusCode::kFailedPrecondition);
      CHECK_THAT(server.status().message(), Catch::Contains("loopback"));
    }
  }
  SECTION("loopback serves plaintext clients") {
    auto server = startServer(config);
    auto options = clientOptions(*server);
    options.insecure = true;
    auto client = connect(options);
    CHECK(client.checkHealth().isOk());
    auto arrays = client.read("run.h5", {Hyperslab::whole("/bonds/pairs")});
    REQUIRE(arrays.isOk());
    CHECK(bitIdentical(arrays->front().values<std::int32_t>().value(),
                       readDirect<std::int32_t>(sampleRoot().file("run.h5"), "/bonds/pairs")));
  }
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST_CASE("Users: tokens and passwords on top of mutual TLS, each with their folders",
          "[dataservice][integration]") {
  TempDir logDir;
  auto config = baseConfig();
  config.accessLog = logDir.file("access.log");
  // Fewer PBKDF2 iterations than in production keep the test fast; the
  // scheme is the same.
  constexpr int kIterations = 20000;
  dataservice::UserEntry alice{
      "alice", rpc::hashSecret("alice-token", kIterations).value(), "", "", {"alice", "flat"}};
  dataservice::UserEntry bob{
      "bob", "", rpc::hashSecret("bob's password", kIterations).value(), "", {"bob"}};
  dataservice::UserEntry render{"render", "", "", "crackvis-render", {"*"}};
  config.users = {alice, bob, render};
  auto server = startServer(config);

  auto as = [&](const std::string& token, const std::string& user = "",
                const std::string& password = "", const std::string& cert = "client") {
    auto options = clientOptions(*server, cert);
    options.token = token;
    options.user = user;
    options.password = password;
    return connect(options);
  };

  SECTION("a valid token reads the user's folders, and only those") {
    auto client = as("alice-token");
    auto arrays = client.read("alice/a.h5", {Hyperslab::whole("/bonds/pairs")});
    INFO(arrays.status().message());
    REQUIRE(arrays.isOk());
    CHECK(client.describe("flat/run2d.h5").isOk());
    const Status other = client.describe("bob/b.h5").status();
    CHECK(other.code() == StatusCode::kPermissionDenied);
    CHECK_THAT(other.message(), Catch::Contains("'alice'") && Catch::Contains("bob/b.h5"));
    // A symlink in alice's folder does not lend her bob's file.
    const Status linked = client.describe("alice/bob-link.h5").status();
    CHECK(linked.code() == StatusCode::kPermissionDenied);
    CHECK_THAT(linked.message(), Catch::Contains("bob/b.h5"));
    CHECK(client.describe("run.h5").status().code() == StatusCode::kPermissionDenied);
    // A file that does not exist in another's folder is not told apart.
    CHECK(client.describe("bob/nothing.h5").status().code() == StatusCode::kPermissionDenied);
    auto files = client.listFiles("", true);
    REQUIRE(files.isOk());
    std::vector<std::string> paths;
    for (const auto& file : *files) {
      paths.push_back(file.path);
    }
    CHECK(paths == std::vector<std::string>{"alice/a.h5", "flat/run2d.h5"});
  }

  SECTION("a wrong token, a wrong password, no credentials") {
    for (auto* client : {new dataservice::DataClient(as("wrong-token")),
                         new dataservice::DataClient(as("", "bob", "not bob's password")),
                         new dataservice::DataClient(as("", "alice", "alice-token")),
                         new dataservice::DataClient(as(""))}) {
      std::unique_ptr<dataservice::DataClient> owned(client);
      const Status status = owned->read("bob/b.h5", {Hyperslab::whole("/bonds/pairs")}).status();
      INFO(status.message());
      CHECK(status.code() == StatusCode::kUnauthenticated);
      CHECK(owned->listFiles().status().code() == StatusCode::kUnauthenticated);
      CHECK(owned->fetch("bob/b.h5", {}).status().code() == StatusCode::kUnauthenticated);
    }
    auto good = as("alice-token");
    CHECK(good.read("alice/a.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
  }

  SECTION("name and password") {
    auto client = as("", "bob", "bob's password");
    CHECK(client.read("bob/b.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
    CHECK(client.read("alice/a.h5", {Hyperslab::whole("/bonds/pairs")}).status().code() ==
          StatusCode::kPermissionDenied);
  }

  SECTION("a certificate that names a user needs no token") {
    auto client = as("", "", "", "crackvis-render");
    CHECK(client.read("bob/b.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
    CHECK(client.read("alice/a.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
  }

  SECTION("every call leaves one access log line: user, file, bytes, time, status") {
    auto client = as("alice-token");
    auto arrays = client.read("alice/a.h5", {Hyperslab::whole("/bonds/pairs")});
    REQUIRE(arrays.isOk());
    CHECK(client.describe("bob/b.h5").status().code() == StatusCode::kPermissionDenied);
    CHECK(as("wrong").listFiles().status().code() == StatusCode::kUnauthenticated);
    server->shutdown();  // flushes every reactor's line
    const auto logLines = lines(readText(config.accessLog));
    REQUIRE(logLines.size() == 3);
    // The bytes as sent: the bond list went packed.
    const std::uint64_t sentBytes = client.readWireBytes();
    CHECK(sentBytes < arrays->front().bytes.size());
    CHECK_THAT(logLines[0], Catch::Contains("method=Read") && Catch::Contains("user=\"alice\"") &&
                                Catch::Contains("cert=\"crackvis-client\"") &&
                                Catch::Contains("file=\"alice/a.h5\"") &&
                                Catch::Contains(fmt::format("bytes={} ", sentBytes)) &&
                                Catch::Contains("seconds=") && Catch::Contains("status=OK") &&
                                Catch::Contains("peer=\"ipv4:127.0.0.1:"));
    CHECK_THAT(logLines[1],
               Catch::Contains("method=Describe") && Catch::Contains("file=\"bob/b.h5\"") &&
                   Catch::Contains("status=PERMISSION_DENIED") && Catch::Contains("detail="));
    CHECK_THAT(logLines[2], Catch::Contains("method=ListFiles") && Catch::Contains("user=\"\"") &&
                                Catch::Contains("status=UNAUTHENTICATED"));
  }
}

}  // namespace
}  // namespace crackvis::testing
